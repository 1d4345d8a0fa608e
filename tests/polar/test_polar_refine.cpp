// The combined 4-step refinement (MATH.md 3.3): BP at polar structures, Catmull-Clark
// elsewhere, merged where the two agree.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "common/shapes.h"
#include "core/polar/polar_net.h"
#include "core/polar/polar_refine.h"
#include "polar/polar_test_util.h"

namespace subd2nurbs::testing {
namespace {

TEST(PolarRefine, OverlapRingsAgreeAndTheMeshIsTheMergedOne) {
  double worst_overlap = 0;
  for (int n : {6, 9, 16}) {
    for (const MeshInput& in : {capped_cylinder(n, 0.1, 0.03), mushroom(n, 0.2, 0.03)}) {
      const SubdivLevel base = SubdivLevel::from_input(in);
      const PolarDetection d = detect_polar_structures(base);
      ASSERT_EQ(d.structures.size(), 2u);
      const int quads = static_cast<int>(in.face_sizes.size()) - 2 * n;
      for (int k = 1; k <= 3; ++k) {
        const PolarRefinement r = refine_with_polar(base, in.positions, k, d.structures);
        EXPECT_EQ(r.structures, 2);
        // Identical to rounding where both are valid (the paper's merge condition).
        EXPECT_LT(r.max_overlap_difference, 1e-14 * 8) << "n " << n << " k " << k;
        worst_overlap = std::max(worst_overlap, r.max_overlap_difference);
        // Faces: the quads refined, the two poles with n 2^k triangles each and 2^k - 1 BP
        // rings of quads inside the first ring.
        const int N = n << k, inner = 1 << k;
        const int expected = quads * (1 << (2 * k)) + 2 * (N + N * (inner - 1));
        EXPECT_EQ(r.level.mesh.num_faces(), expected) << "n " << n << " k " << k;
        int triangles = 0;
        for (int f = 0; f < r.level.mesh.num_faces(); ++f) triangles += r.level.mesh.face_size(f) == 3;
        EXPECT_EQ(triangles, 2 * N);
        // The pole is BP's: after k radial steps it approaches the BP limit point by 1/4 per
        // step (the pole/ring-1 block has eigenvalues 1 and 1/4, MATH.md 2.3).
        const V3 limit = ev(bp_limit_point(polar_net_of(d.structures[0], in.positions)));
        const V3 pole0 = ev(in.positions[0]);
        double nearest = 1e9;
        for (const Point3& p : r.positions) nearest = std::min(nearest, (ev(p) - limit).norm());
        EXPECT_NEAR(nearest, std::pow(0.25, k) * (pole0 - limit).norm(), 1e-12) << "n " << n << " k " << k;
      }
    }
  }
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", worst_overlap);
  RecordProperty("max_overlap_difference", text);
}

TEST(PolarRefine, WithoutStructuresItIsCatmullClark) {
  const MeshInput in = capped_cylinder(8);
  const SubdivLevel base = SubdivLevel::from_input(in);
  const PolarRefinement r = refine_with_polar(base, in.positions, 2, {});
  const Refinement cc = refine_uniform(base, 2);
  EXPECT_EQ(r.level.mesh.num_faces(), cc.levels.back().mesh.num_faces());
  EXPECT_EQ(r.positions, cc.positions(in.positions).back());
}

}  // namespace
}  // namespace subd2nurbs::testing
