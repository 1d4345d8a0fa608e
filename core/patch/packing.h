// Packed faces: regular regions of the per-quad PatchSet merged into one B-spline surface each
// (docs/patches.md, "Packed faces").
//
// A pack is a rectangle of mu x mv coarse quads, laid out as a grid with consistent
// orientation, whose quads are regular patches (the exact limit: polynomial B-splines with
// simple knots, a single span unless a semi-sharp crease runs nearby) or patches at an
// extraordinary vertex (Construction Q: knots nested towards the vertex, double on the zone
// lines), and whose interior edges are smooth C2 curves with no sharpness (never a fan ray, a
// crease of any sharpness, a boundary or a polar cap's side). Every edge at an extraordinary
// vertex is a fan ray, so such a vertex is always a corner of the packs around it. Its surface
// is the one bicubic B-spline over [0, mu] x [0, mv] (one unit per quad, the same parameter
// speed as the quads' own [0,1]^2) whose knots are a simple knot at every integer, minus the
// cell lines across which the surface is one polynomial, plus in each column (row) the union
// of its quads' own knots, each value as often as the quad that has it most often.
// Poles are blossoms of the quads' polynomial pieces, and the surface is then checked to
// reproduce every piece of every quad (Bezier nets compared), so a pack is exactly the union
// of its quads.
//
// Rectangles are chosen greedily, largest first. A pack's side is one curve, or several
// (NurbsPatch::split_sides) where other faces meet it (T-junctions need no sewing: each curve
// is shared by both faces). The coarse edges between the same two faces are merged into one
// curve as long as no third face meets them. A ring of quads that closes on itself (a torus,
// a cylinder) becomes one pack whose opposite sides share their curves: the B-rep face then
// has seam edges, like OCCT's own cylinders and tori.
#pragma once

#include <vector>

#include "core/nurbs/patch_set.h"

namespace subd2nurbs {

struct PatchBuild;

/// Where a patch of the per-quad set ended up.
struct PatchPlace {
  int patch = -1;    ///< output patch
  int u = 0, v = 0;  ///< its cell [u, u+1] x [v, v+1] in the output patch's domain (0, 0 if alone)
  int rotation = 0;  ///< the quad's corner at the cell's (u, v) corner (0 if alone)
};

/// The quad's own parameters (s, t) in [0,1]^2 -> the output patch's (u, v).
void place_parameters(const PatchPlace& place, double s, double t, double& u, double& v);

struct PackedSet {
  PatchSet set;                     ///< what is exported: packs and the patches left alone
  std::vector<PatchPlace> place;    ///< per patch of the per-quad set
  std::vector<int> curve;           ///< per curve of the per-quad set: output curve, -1 inside a pack
  std::vector<std::vector<int>> source_curves;  ///< per output curve: the per-quad set's curves it joins
  int packs = 0;                    ///< output patches made of two or more quads
  int packed_quads = 0;             ///< quads inside those
  int rejected_packs = 0;           ///< rectangles whose surface did not reproduce its quads (kept per quad)
  long long total_poles = 0;        ///< poles of all output patches
  long long removed_knots = 0;      ///< knot lines dropped inside packs
};

/// The most edges on a packed face's boundary (docs/patches.md, "Packed faces"): a pack with
/// more (a ring of quads whose sides meet a fan's faces one by one) is cut into strips. OCCT's
/// STEP reader projects every edge onto its face's whole surface, so a face of E edges and
/// about E spans costs it E^2 (a 1024-sided capsule's side: 2 x 2048 edges, > 20 minutes).
constexpr int kMaxPackEdges = 128;

/// Packs a build: a patch may join a pack when it is a regular patch of a coarse quad with
/// simple knots or a patch at an extraordinary vertex (PatchKind::Pccm), polynomial, across a
/// curve claimed C2 whose coarse edge has no sharpness at all. Knot lines whose
/// third-derivative jump is at most tolerances::kKnotRemoval of the model size are dropped; a
/// pack must reproduce each quad within tolerances::kSameSurface, else its quads stay alone.
/// No pack has more than `max_edges` edges on its boundary (a seam counted twice).
PackedSet pack_patches(const PatchBuild& build, int max_edges = kMaxPackEdges);

/// The per-quad set unchanged, with the identity places (what `--faces per-quad` exports).
PackedSet unpacked(const PatchSet& quads);

}  // namespace subd2nurbs
