// Knot assembly: the polynomial pieces of one coarse quad -> one clamped bicubic B-spline
// with only the knots its surface needs (docs/patches.md, "Knots").
//
// The pieces (PatchLeaf) tile [0,1]^2 as a quadtree. The patch's knot vector in u is the union
// of the pieces' u-boundaries (v alike): simple where the pieces join C2, double on the zone
// lines where Construction Q joins only C1. A simple knot xi is then removed when the surface
// is one polynomial across the whole line u = xi: two cubic pieces that join C2 differ by
// c(v) (u - xi)^3, and c is tested on four parameters of every cell (it is a cubic). The
// poles are blossoms of the polynomial of a cell in each pole's support, so the B-spline is
// exactly the union of the pieces whenever they join with the continuity the knots claim.
#pragma once

#include <map>
#include <vector>

#include "core/patch/patch_builder.h"

namespace subd2nurbs {

/// Point location in a quadtree of pieces.
class LeafIndex {
 public:
  explicit LeafIndex(const PatchLeaves& leaves);
  /// The piece containing (u, v); on a piece boundary, the one on the side of larger u and v.
  int locate(double u, double v) const;

 private:
  struct Node {
    int child[4] = {-1, -1, -1, -1};  ///< (x, y) -> 2y + x
    int leaf = -1;
  };
  std::vector<Node> nodes_;
};

/// Position on a piece at patch parameters (u, v) (which may lie outside the piece: the
/// polynomial is extended), minus `origin`.
Point3 eval_leaf(const PatchLeaf& leaf, double u, double v, const Point3& origin = {0, 0, 0});

/// For every line u = xi (across_u) or v = xi where pieces meet: the largest jump of the third
/// derivative across it between the pieces on either side, as a position at the pieces' scale
/// (|jump| h^3 / 6, h the smaller piece's size). A knot whose jump is rounding noise is a
/// candidate for removal.
std::map<double, double> knot_line_jumps(const PatchLeaves& leaves, const LeafIndex& index, bool across_u);

/// Largest distance between the patch and the piece at 4 x 4 parameters inside the piece (two
/// bicubics equal there are the same polynomial).
double leaf_error(const PatchLeaf& leaf, const NurbsPatch& patch);

struct AssemblyStats {
  int removed_knots = 0;
};

/// Fills patch.knots_u/v, num_poles_u/v and poles from the pieces. Knot values in `double_u` /
/// `double_v` get multiplicity 2; a simple knot is removed when its knot_line_jumps value is
/// at most `tolerance` (model units) and the patch without it still reproduces every piece
/// within `check` (leaf_error).
AssemblyStats assemble_patch(const PatchLeaves& leaves, const std::vector<double>& double_u,
                             const std::vector<double>& double_v, double tolerance, double check,
                             NurbsPatch& patch);

}  // namespace subd2nurbs
