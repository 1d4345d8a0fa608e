// Catmull-Clark cage -> PatchSet: one bicubic NURBS patch per quad of the coarsest all-quad
// mesh, with only the knots its surface needs (docs/patches.md).
//
// Pipeline (each phase has its own file in core/patch/):
//   1. a := 0 if the cage is all quads (holes and polar caps aside), else 1 (one CC step
//      splits n-gons). Only this level is ever built for the whole cage.
//   2. Fans (fan_construction): around every vertex that is irregular for some quad once its
//      semi-sharp tags have decayed, the faces within 5 rings are cut out and refined locally
//      (local_mesh) to the fan's level k_v = a + 2 + extra, deeper while a semi-sharp tag is
//      left within 3 rings; there Construction Q gives the 2x2 zone of every sector.
//   3. Leaves (this file): every coarse quad is walked as a quadtree. A sub-quad whose corners
//      are regular for it and carry no semi-sharp tag is one bicubic (regular_net); the
//      sub-quad at an irregular corner at level k_v - 1 is that fan's zone; anything else is
//      split, refining only the 2-ring of the sub-quads that are split.
//   4. Knots (knot_assembly): the union of the leaves' boundaries, double on zone lines,
//      minus every simple knot the surface does not need (zero third-derivative jump along
//      the whole line); poles by blossoming, so the patch is exactly the union of its leaves.
//   5. Topology: corners, one curve per coarse edge, which patches use it and the continuity
//      the construction guarantees across it.
//   With PatchOptions::polar, polar structures are found first. Their triangles and 1-layer
//   quads produce no Catmull-Clark patch and do not count for a; each structure becomes one
//   polar cap whose boundary, the cage's 2-link, is split into the curves of its neighbour
//   patches, with a seam at spoke 0 and a collapsed side at the pole (docs/polar.md).
#pragma once

#include <array>
#include <vector>

#include "core/patch/local_mesh.h"
#include "core/nurbs/patch_set.h"
#include "core/polar/polar_cap.h"
#include "core/polar/polar_structure.h"
#include "core/refine/refiner.h"
#include "core/util/small_vector.h"

namespace subd2nurbs {

struct PatchOptions {
  /// Levels beyond the minimum (coarse all-quad level + 2) for every fan. More levels shrink
  /// the region where Construction Q deviates from the limit (rates per valence in
  /// docs/patches.md); each costs a few knots in the patches at that vertex.
  int extra_levels = 0;
  /// Further levels per coarse vertex (index: level-a vertex; missing entries are 0), added to
  /// extra_levels for the fans at that vertex: a tolerance deepens only the fans that need it.
  std::vector<int> vertex_extra_levels;
  /// A build of the same cage with the same options but other extra levels: every coarse quad
  /// none of whose corners changed its extra levels is copied from it instead of rebuilt (the
  /// quad depends only on its own pieces and the zones at its corners).
  const struct PatchBuild* reuse = nullptr;
  /// Polar structures of the cage (docs/math.md 3.1) become one singular polar cap each
  /// (docs/math.md 4); off: every vertex goes through Catmull-Clark, poles included.
  bool polar = true;
  PolarCapOptions cap;
  /// With `polar`: poles rejected only for a valence below 6 or for being too close to
  /// another structure get the separating first step (docs/math.md 3.7, polar_separation.h) and
  /// become caps of twice the valence; the patches are then built from that level-1 cage.
  bool separate_poles = false;
  /// Coarse quads with a corner of more than this many faces are refined in one shared piece
  /// per such vertex (the union of their 2-rings, refined once per level: O(n L) for the n quads
  /// at a valence-n vertex) instead of one piece per quad (each holding the vertex's whole star:
  /// O(n^2 L)). The pieces are the same either way (a point inside both pieces is computed by
  /// the same stencils in the same order); a huge value gives the per-quad path (tests).
  int shared_piece_valence = 8;
};

/// How the quads around one irregular vertex (one fan between sharp edges) were built.
enum class FanMode : unsigned char {
  Smooth,       ///< interior extraordinary vertex: Construction Q, exactly G1 (docs/math.md 5.3)
  Dart,         ///< one sharp edge ends here: Construction Q cut open at the sharp ray
  Crease,       ///< crease or smooth boundary vertex, k != 2 faces on this side: open fan
  Corner,       ///< corner vertex, k >= 2 faces between its sharp edges: open fan
  Approximate,  ///< no exact construction (cone point, valence 2): C0 rays, normal jump measured
};
const char* to_string(FanMode mode);

struct IrregularFan {
  int vertex = -1;       ///< level-k vertex (equal to its level-a index)
  int base_vertex = -1;  ///< cage vertex, or -1
  FanMode mode = FanMode::Smooth;
  int valence = 0;
  int sectors = 0;       ///< faces in the fan
  double c = 0;          ///< G1 coefficient: D + E = 2c(1-t)^2 e' on the smooth rays
  int level = 0;         ///< k_v: the level of its zone (a + 2 + extra, deeper past semi-sharp tags)
  int piece = -1;        ///< index into PatchBuild::fan_pieces
};

/// A coarse edge leaving an irregular vertex: where the exact residual of docs/math.md 10.3 applies.
struct RayCurve {
  int curve = -1;          ///< PatchSet curve index
  bool vertex_at_start;    ///< the irregular vertex is the curve's corner0
  int fan = -1;            ///< index into PatchBuildInfo::fans: the fan this ray belongs to
  Continuity continuity;   ///< G1 or C0 (sharp or approximate)
  double c = 0;            ///< the fan's G1 coefficient (docs/math.md 5.4: D + E = 2c(1-t)^2 e')
};

/// One polar cap: the structure it replaces and the cap before clamping.
struct CapInfo {
  int patch = -1;           ///< PatchSet patch index
  PolarStructure structure;
  PolarCap cap;
  PolarNet input;           ///< rings 0..3 of the cage
};

struct PatchBuildInfo {
  int coarse_level = 0;  ///< a: 0 if the cage is all quads (polar cap faces aside), else 1
  int level = 0;         ///< the deepest level of any leaf (a when every coarse quad is one bicubic)
  int min_fan_level = 0; ///< a + 2 + extra_levels: the level of a fan with no semi-sharp tag near it
  int regular_patches = 0;
  int pccm_patches = 0;
  /// Semi-sharp tags are refined exactly however sharp they are (below infinity), so no edge
  /// is ever made sharp; kept at 0 for the report format.
  int sharpened_edges = 0, sharpened_vertices = 0;
  long long leaves = 0;       ///< polynomial pieces of all patches before knot removal
  long long total_poles = 0;  ///< poles of all patches (caps included)
  long long removed_knots = 0;  ///< simple knots removed because the surface is one polynomial across them
  std::vector<IrregularFan> fans;
  std::vector<CapInfo> caps;             ///< polar caps (PatchOptions::polar)
  std::vector<RejectedPole> rejected_poles;  ///< pole-like vertices left to Catmull-Clark
  /// Cage vertices given the separating first step (PatchOptions::separate_poles). When not
  /// empty, `refinement.levels[0]` is the separated level-1 cage and levels count from it.
  std::vector<int> separated_poles;
  std::vector<RayCurve> rays;
};

/// One polynomial piece of a patch: a bicubic Bezier net over the square
/// [u0, u0 + size] x [v0, v0 + size] of the patch's domain [0,1]^2.
struct PatchLeaf {
  double u0 = 0, v0 = 0, size = 1;
  int level = 0;      ///< subdivision level of the piece
  bool zone = false;  ///< a Construction Q piece (else the exact limit, a regular bicubic)
  std::array<Point3, 16> net{};  ///< index i * 4 + j, i along u
};
/// A patch's pieces; most coarse quads are one bicubic, kept inline (small_vector.h).
using PatchLeaves = SmallVector<PatchLeaf, 1>;

/// The local piece of the level a fan was built on, kept for the deviation measurement: the
/// faces within 5 rings of the vertex at level k_v, with the Bezier nets (face frame) of the
/// zone faces and of the regular faces within 3 rings.
struct FanPiece {
  int vertex = -1;  ///< the irregular vertex, index in `mesh`
  int level = 0;    ///< k_v
  LocalMesh mesh;
  std::vector<Point3> nets;   ///< 16 per face of mesh
  std::vector<char> has_net;  ///< per face
};

struct PatchBuild {
  PatchSet set;
  PatchBuildInfo info;
  Refinement refinement;                 ///< levels 0..a only (the cage and its coarse all-quad level)
  std::vector<Point3> cage_positions;    ///< control points of level 0
  std::vector<Point3> coarse_positions;  ///< control points of level a
  std::vector<int> coarse_face;          ///< per patch: its level-a face, -1 for a polar cap
  std::vector<PatchLeaves> leaves;  ///< per patch: its pieces (empty for a polar cap)
  std::vector<FanPiece> fan_pieces;      ///< one per irregular vertex with fans
  std::vector<int> vertex_extra;         ///< per level-a vertex: the extra levels its fans were asked for
  std::vector<int> patch_deepest;        ///< per patch: the deepest level of its pieces (a for a cap)
  std::vector<int> patch_removed_knots;  ///< per patch: simple knots removed (0 for a cap)
};

/// The model size: the bounding-box diagonal of the cage's points that at least one face uses
/// (an unused vertex far away must not set the tolerances); 1 for a cage without faces.
double bounding_diagonal(const PolyMesh& m, const std::vector<Point3>& positions);

/// Builds the patches of a validated cage. Positions are the cage's vertex positions.
/// \throw std::invalid_argument if the topology is outside what the builder supports
///        (non-manifold input is rejected earlier, by validation).
PatchBuild build_patches(const SubdivLevel& base, const std::vector<Point3>& positions,
                         const PatchOptions& options = {});

}  // namespace subd2nurbs
