// Catmull-Clark cage -> PatchSet: one bicubic NURBS patch per quad of the coarsest all-quad
// mesh (MATH.md sections 5.3, 5.4, 6).
//
// Pipeline:
//   1. a := 0 if the cage is all quads (holes aside), else 1 (one CC step splits n-gons).
//   2. Refine uniformly to level k = a + 2 + extra_levels, and further while any semi-sharp
//      sharpness is still active, so that every level-k edge is smooth or infinitely sharp.
//   3. Per level-k quad whose four corners are regular *for that quad* (smooth 4-valent,
//      crease vertex with 2 faces on the quad's side, corner vertex with 1 face), the exact
//      limit patch: the bicubic B-spline of its 4x4 neighbourhood, with phantom points across
//      sharp edges (MATH.md 1.2), converted to a Bezier net (6.1).
//   4. Per irregular vertex and per fan of faces between its sharp edges ("fan"), the quads
//      touching the vertex get Construction Q (5.3) or its open-fan variant (5.6, made
//      precise here and tested): exactly G1 across the smooth rays, with the level-k 2x2
//      zone joined C1 to the regular surface.
//   5. The level-k Bezier nets of each coarse quad are merged into one clamped B-spline
//      (5.4): double knots at h and 2h next to a corner that had a fan construction, simple
//      knots elsewhere. Poles are blossoms of one Bezier piece (exact when the pieces join
//      with the claimed continuity, which the tests verify piece by piece).
//   6. The shared boundary topology (corners, one curve per coarse edge, which patches use
//      it, and the continuity the construction guarantees across it).
//   With PatchOptions::polar, polar structures are found first (MATH.md 3.1). Their
//   triangles and 1-layer quads produce no Catmull-Clark patch and do not count for a; each
//   structure becomes one polar cap (MATH.md 4) whose boundary, the cage's 2-link, is split
//   into the curves of its neighbour patches, with a seam at spoke 0 and a collapsed side at
//   the pole. The whole cage is still refined by Catmull-Clark: the level-k points the
//   neighbour patches use lie on rings >= 2^(k+1) - 1, which do not depend on the pole
//   (MATH.md 3.3), so they are the Catmull-Clark side of the paper's 4-step procedure.
#pragma once

#include <vector>

#include "core/patch/patch_set.h"
#include "core/polar/polar_cap.h"
#include "core/polar/polar_structure.h"
#include "core/refine/refiner.h"

namespace subd2nurbs {

struct PatchOptions {
  /// Levels beyond the minimum (coarse all-quad level + 2). More levels shrink the region
  /// where Construction Q deviates from the limit (rates per valence in MATH.md 5.3).
  int extra_levels = 0;
  /// Semi-sharp creases are refined until they are smooth, but at most this many levels
  /// above the coarse all-quad level (each level quadruples the work). Sharpness left at
  /// that level is treated as infinite, and PatchBuildInfo says how many edges it touched.
  int max_levels_above_coarse = 5;
  /// Polar structures of the cage (MATH.md 3.1) become one singular polar cap each (MATH.md
  /// 4); off: every vertex goes through Catmull-Clark, poles included.
  bool polar = true;
  PolarCapOptions cap;
  /// With `polar`: poles rejected only for a valence below 6 or for being too close to
  /// another structure get the separating first step (MATH.md 3.4, polar_separation.h) and
  /// become caps of twice the valence; the patches are then built from that level-1 cage.
  bool separate_poles = false;
};

/// How the quads around one irregular vertex (one fan between sharp edges) were built.
enum class FanMode : unsigned char {
  Smooth,       ///< interior extraordinary vertex: Construction Q, exactly G1 (MATH.md 5.3)
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
};

/// A coarse edge leaving an irregular vertex: where MATH.md section 9's exact residual applies.
struct RayCurve {
  int curve = -1;          ///< PatchSet curve index
  bool vertex_at_start;    ///< the irregular vertex is the curve's corner0
  int fan = -1;            ///< index into PatchBuildInfo::fans: the fan this ray belongs to
  Continuity continuity;   ///< G1 or C0 (sharp or approximate)
  double c = 0;            ///< the fan's G1 coefficient (MATH.md 5.3: D + E = 2c(1-t)^2 e')
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
  int level = 0;         ///< k: the level the patches are built from
  int regular_patches = 0;
  int pccm_patches = 0;
  /// Level-k edges and vertices whose semi-sharpness had not decayed at the level cap and
  /// were made infinitely sharp (0 when every semi-sharp crease was refined to smoothness).
  int sharpened_edges = 0, sharpened_vertices = 0;
  std::vector<IrregularFan> fans;
  std::vector<CapInfo> caps;             ///< polar caps (PatchOptions::polar)
  std::vector<RejectedPole> rejected_poles;  ///< pole-like vertices left to Catmull-Clark
  /// Cage vertices given the separating first step (PatchOptions::separate_poles). When not
  /// empty, `refinement.levels[0]` is the separated level-1 cage and levels count from it.
  std::vector<int> separated_poles;
  std::vector<RayCurve> rays;
  /// For each patch, its (2^(k-a))^2 level-k quads, row-major [y][x] with x along u, each as
  /// the level-k corner at the quad's patch-frame origin (its x axis runs along u).
  std::vector<std::vector<int>> sub_corners;
};

struct PatchBuild {
  PatchSet set;
  PatchBuildInfo info;
  /// Level-k Bezier nets, 16 points per level-k face in the face's own frame
  /// (index i * 4 + j, i along the face's first edge). Kept for tests and deviation checks.
  std::vector<Point3> level_nets;
  Refinement refinement;  ///< levels 0..k
  std::vector<Point3> level_positions;  ///< control points of level k
};

/// Builds the patches of a validated cage. Positions are the cage's vertex positions.
/// \throw std::invalid_argument if the topology is outside what the builder supports
///        (non-manifold input is rejected earlier, by validation).
PatchBuild build_patches(const SubdivLevel& base, const std::vector<Point3>& positions,
                         const PatchOptions& options = {});

}  // namespace subd2nurbs
