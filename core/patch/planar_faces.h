// Coplanar faces of a PatchSet, for the B-rep export: a connected set of patches whose poles
// all lie on one plane (to rounding) is exactly a region of that plane, so it can be written as
// ONE planar face bounded by the set's outer curves (a single planar patch too: a plane is
// written as a plane) (docs/patches.md "Planar faces").
//
// Exactness: a B-spline surface (polynomial, or rational with positive weights) lies in the
// convex hull of its poles, so poles within a tolerance of a plane put the whole surface within
// that tolerance of it. The merged face's boundary is made of the same BoundaryCurves as before
// (their poles are rows of the patches' poles, on the plane too); curves between two members
// disappear, so does every corner inside the region.
#pragma once

#include <vector>

#include "core/nurbs/patch_set.h"

namespace subd2nurbs {

/// A curve traversed as a piece of a loop: from corner1 to corner0 when reversed.
struct LoopCurve {
  int curve = -1;
  bool reversed = false;
};

struct PlanarFace {
  std::vector<int> patches;  ///< one or more, connected across shared curves, ascending
  Point3 origin{};           ///< a point of the plane (the poles' mean)
  Point3 normal{};           ///< unit; the side the patches' normals X_u x X_v point to
  Point3 x_axis{};           ///< unit, in the plane (y = normal x x_axis)
  double tolerance = 0;      ///< model units: how far its poles and boundary curves may lie off the plane
  /// The region's boundary: loops[0] the outer loop, counter-clockwise seen from the normal
  /// side (the way the patches' own sides run), the others holes (clockwise). Each loop is
  /// closed: a curve's end corner is the next one's start corner.
  std::vector<std::vector<LoopCurve>> loops;
};

struct PlanarFaces {
  std::vector<PlanarFace> faces;
  std::vector<int> face_of_patch;  ///< per patch: its PlanarFace, or -1 (written as it is)
  int planar_patches = 0;          ///< patches whose poles lie on a plane (merged or not)
  int skipped = 0;                 ///< coplanar sets left as they are: their boundary touches itself
  int split = 0;  ///< coplanar sets whose loops crossed in the plane, split by leaving out the patches along the crossings
  /// Per patch: in a set, and its normal X_u x X_v turns against the set's somewhere (sampled 4 x 4
  /// per knot span): folded over itself in the plane. Its planar face is still the region the
  /// set's loops enclose (find_planar_faces).
  std::vector<char> folded_patch;
};

/// The coplanar sets of patches of `ps` (a set may be one patch). A patch is planar when its poles lie on
/// the plane through their mean with the normal of its control net
/// (the sum of the net's cell cross products, which points the way X_u x X_v does). A planar
/// patch may fold over itself in the plane (its normal turning against the net's somewhere); it
/// joins its set all the same: where the set's loops are simple curves that do not cross, the
/// patches cover every point they enclose (each such point's winding number is 1) and the planar
/// face is that region, covered once: a fold's doubled layers, and any flap out past the loops,
/// are not in it (`folded_patch` marks such patches). Neighbours
/// across a shared curve join a set when their poles lie on the set's first patch's plane and
/// their normals point the same way. "On a plane" with unit normal n means within
/// relative_tolerance x sum_i |n_i| s_i, where s_i is the largest |coordinate i| of any pole
/// (rounding scales with the coordinates along the normal: a part 1e8 long and 1e-8 thin), and
/// never more than relative_tolerance x ps.model_size. A set whose boundary passes a corner
/// twice (two regions touching at a point), or does not have exactly one outer loop, is left
/// as it is (`skipped`), unless its loops cross (patches overlapping: see split_planar_face),
/// when it is split as there (`split`).
PlanarFaces find_planar_faces(const PatchSet& ps, double relative_tolerance);

/// A planar face whose loops cross in its plane (its patches overlap there: a fold of the
/// surface beside it leaves a patch out or turns one over, so the set is not one region of the
/// plane; OCCT refuses its face) split into parts: the patches along the crossing curves
/// (crossing_curves) are left out, to be written as they are, and each connected rest with one
/// outer loop is a part (a rest whose loops still fail is split again, up to 4 rounds). `also`:
/// more curves to leave out (those a checker found intersecting: OCCT's BRepCheck_Wire). Empty
/// when no loop curve crosses. The parts' loops may still cross: check them again.
std::vector<PlanarFace> split_planar_face(const PatchSet& ps, const PlanarFace& f, const std::vector<int>& also = {});

/// The curves of `f`'s loops that cross a loop curve (another, or another piece of themselves)
/// in f's plane, each curve sampled at 16 segments (curves that only meet at a corner do not
/// cross), and the two curves of every corner where a loop turns back on itself (by more than
/// 150 degrees: a cusp, the curves running along each other). Ascending.
std::vector<int> crossing_curves(const PatchSet& ps, const PlanarFace& f);

}  // namespace subd2nurbs
