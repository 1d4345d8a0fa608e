// PatchSet: the finite bicubic surface and its shared boundary topology.
//
// This is the contract between the geometry core and every front end (OCCT B-rep, JSON,
// Python). It is plain data in double precision: no OCCT types, no behaviour beyond small
// accessors.
//
// Conventions (used by every consumer, keep them in sync with docs/formats.md):
// - A patch is a tensor-product NURBS surface of degree (3, 3) with clamped knot vectors (end
//   multiplicity degree + 1). Knots are stored as distinct values plus multiplicities, like
//   OCCT and STEP do. Its domain is [0,1] x [0,1], except for a packed patch (several coarse
//   quads, `cells` not empty): [0, mu] x [0, mv], one unit per quad (packing.h).
// - poles[i * num_poles_v + j] is pole (i, j): i runs along u, j along v.
// - weights is empty for a polynomial (non-rational) patch, else one weight per pole.
// - A patch's four sides are numbered counter-clockwise in the (u, v) domain, which is the
//   order of the cage face's corners:
//     side 0: v = 0, from (0,0) to (1,0)      side 1: u = 1, from (1,0) to (1,1)
//     side 2: v = 1, from (1,1) to (0,1)      side 3: u = 0, from (0,1) to (0,0)
//   corner c of the patch is the start of side c: (0,0), (1,0), (1,1), (0,1).
//   The surface normal X_u x X_v points to the side the cage face's normal points to.
// - A BoundaryCurve is the cubic B-spline that every patch using it has as a side. Its
//   parameter s in [0,1] runs from corner0 to corner1. A use with reversed = true traverses
//   the side (in the counter-clockwise direction above) from corner1 to corner0.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "core/util/point3.h"
#include "core/util/small_vector.h"

namespace subd2nurbs {

enum class PatchKind : unsigned char {
  RegularBSpline,  ///< every sub-quad is the exact Catmull-Clark limit (C2 inside)
  Pccm,            ///< touches an extraordinary vertex: Construction Q (docs/math.md 5) there
  PolarCap,        ///< singular polar cap (docs/math.md 4): u = 0 collapsed, periodic around the pole
};
const char* to_string(PatchKind kind);

/// Continuity the construction guarantees across a boundary curve.
enum class Continuity : unsigned char {
  Boundary,  ///< used by one patch: an open boundary of the surface
  C0,        ///< an infinitely sharp crease: positions only
  G1,        ///< tangent planes agree (edges leaving an extraordinary vertex)
  C1,        ///< first derivatives agree (with the parameter orientation of the two uses)
  C2,        ///< second derivatives agree too
};
const char* to_string(Continuity c);

struct KnotVector {
  // Inline room for a single span's {0, 1} and a few more (small_vector.h says why).
  SmallVector<double, 4> knots;  ///< strictly increasing distinct values
  SmallVector<int, 4> mults;     ///< multiplicity of each value; ends have degree + 1
  bool periodic = false;

  int num_poles(int degree) const;  ///< sum(mults) - degree - 1 (clamped)
  std::vector<double> flat() const; ///< every knot repeated by its multiplicity
};

/// One curve covering part [t0, t1] of a split side (side parameter t counter-clockwise).
struct SidePiece {
  int curve = -1;
  bool reversed = false;  ///< the side runs from the curve's corner1 to corner0 on [t0, t1]
  double t0 = 0, t1 = 1;
};

/// A coarse quad inside a packed patch: the cell [u, u+1] x [v, v+1] of the patch's domain.
/// The quad's own parameters (s, t) (corner 0 of its face at (0, 0), side 0 along t = 0) are
/// turned by `rotation` quarter turns: its corner `rotation` sits at (u, v) and its side
/// `rotation` runs along the cell's side v = const from there.
struct PatchCell {
  int base_face = -1;    ///< cage face
  int coarse_face = -1;  ///< face of the coarse all-quad level (the cage face when the cage is all quads)
  int u = 0, v = 0;
  int rotation = 0;
};

struct NurbsPatch {
  PatchKind kind = PatchKind::RegularBSpline;
  int degree_u = 3, degree_v = 3;
  KnotVector knots_u, knots_v;
  int num_poles_u = 0, num_poles_v = 0;
  SmallVector<Point3, 16> poles;  ///< num_poles_u * num_poles_v, index i * num_poles_v + j
  std::vector<double> weights;    ///< empty: all 1
  SmallVector<int, 2> base_faces; ///< cage faces this patch comes from
  std::vector<PatchCell> cells; ///< a packed patch's quads; empty for a patch of one quad or a cap

  std::array<int, 4> corners{{-1, -1, -1, -1}};  ///< PatchSet::corners index per patch corner
  std::array<int, 4> curves{{-1, -1, -1, -1}};   ///< PatchSet::curves index per side
  std::array<bool, 4> curve_reversed{{false, false, false, false}};
  std::array<std::vector<SidePiece>, 4> split_sides;  ///< non-empty only where curves[side] == -1

  const Point3& pole(int i, int j) const { return poles[static_cast<size_t>(i) * num_poles_v + j]; }
  Point3& pole(int i, int j) { return poles[static_cast<size_t>(i) * num_poles_v + j]; }
};

struct CurveUse {
  int patch = -1;
  int side = -1;          ///< 0..3, see the header comment
  bool reversed = false;  ///< side traversed counter-clockwise from corner1 to corner0
  double t0 = 0, t1 = 1;  ///< part of the side the curve covers (a piece of a split side)

  /// The side parameter t where the curve parameter is s (s in [0, 1]).
  double side_parameter(double s) const { return t0 + (reversed ? 1 - s : s) * (t1 - t0); }
};

struct BoundaryCurve {
  int corner0 = -1, corner1 = -1;  ///< PatchSet::corners indices (equal for a closed curve)
  int degree = 3;
  KnotVector knots;
  SmallVector<Point3, 4> poles;
  SmallVector<CurveUse, 2> uses;  ///< one (open boundary) or two patches (more for a split side)
  Continuity continuity = Continuity::Boundary;
};

struct PatchCorner {
  Point3 position{};
  int base_vertex = -1;  ///< cage vertex, or -1 for a vertex created by refinement
};

struct PatchSet {
  std::vector<NurbsPatch> patches;
  std::vector<BoundaryCurve> curves;
  std::vector<PatchCorner> corners;
  double model_size = 1.0;  ///< bounding-box diagonal of the cage (tolerances scale with it)
  bool closed = false;      ///< no open boundary curves: the patches bound a solid
};

}  // namespace subd2nurbs
