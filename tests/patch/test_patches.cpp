// Patch builder: exact identities and continuity claims (MATH.md 5.3, 5.4, 6, 9).
//
// Oracles used here: the Bezier pieces themselves (blossoming must reproduce them exactly,
// which holds only if the pieces really join with the continuity the knot multiplicities
// claim), the limit masks (regular patches interpolate the limit at their corners), and the
// exact G1 identity D + E = 2c(1-t)^2 e' of Construction Q.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "common/shapes.h"
#include "core/eval/continuity.h"
#include "core/eval/nurbs_eval.h"
#include "core/patch/patch_builder.h"
#include "io/obj_reader.h"
#include "patch/patch_test_util.h"

namespace subd2nurbs::testing {
namespace {

TEST(Patches, RegularTorusIsOneC2BSplinePerQuad) {
  const MeshInput in = torus(8, 6);
  const PatchBuild b = build_from_input(in);
  EXPECT_EQ(b.info.coarse_level, 0);
  EXPECT_EQ(b.info.level, 0);  // every quad is one bicubic already: nothing is refined
  ASSERT_EQ(static_cast<int>(b.set.patches.size()), 48);
  EXPECT_EQ(b.info.regular_patches, 48);
  EXPECT_TRUE(b.set.closed);
  for (const NurbsPatch& p : b.set.patches) {
    EXPECT_EQ(p.num_poles_u, 4);  // one span: the 16 poles of the quad's bicubic
    EXPECT_EQ(p.num_poles_v, 4);
  }
  EXPECT_EQ(b.info.total_poles, 48 * 16);
  const ContinuityReport r = measure_continuity(b.set);
  const double tol = 1e-12 * b.set.model_size;
  EXPECT_LT(r.max_gap, tol);
  EXPECT_LT(r.max_c1_jump, 1e-11);
  EXPECT_LT(r.max_c2_jump, 1e-10);
  EXPECT_LT(max_piece_error(b), tol);
  EXPECT_LT(max_corner_limit_error(b), tol);
}

TEST(Patches, StarsAreExactlyG1AtTheExtraordinaryVertex) {
  for (int n : {3, 5, 6, 7, 8, 12}) {
    SCOPED_TRACE("valence " + std::to_string(n));
    const MeshInput in = star(n);
    const PatchBuild b = build_from_input(in);
    EXPECT_EQ(b.info.coarse_level, 1);  // the bottom n-gon is split first
    const ContinuityReport r = measure_continuity(b.set);
    EXPECT_LT(r.max_gap, 1e-12 * b.set.model_size);
    EXPECT_LT(r.max_normal_angle_deg, 1e-6);
    EXPECT_LT(r.max_coplanarity, 1e-10);
    EXPECT_LT(max_piece_error(b), 1e-12 * b.set.model_size);
    EXPECT_LT(max_g1_residual(b), 1e-12);
    EXPECT_GT(b.info.pccm_patches, 0);
  }
}

TEST(Patches, G1ResidualTestCanFail) {
  // Perturb one pole next to an extraordinary ray: the exact residual must notice.
  const MeshInput in = star(5);
  PatchBuild b = build_from_input(in);
  ASSERT_FALSE(b.info.rays.empty());
  const RayCurve& ray = b.info.rays.front();
  const CurveUse& use = b.set.curves[ray.curve].uses[0];
  NurbsPatch& p = b.set.patches[use.patch];
  p.pole(1, 1)[2] += 1e-3;
  p.pole(p.num_poles_u - 2, 1)[2] += 1e-3;
  p.pole(1, p.num_poles_v - 2)[2] += 1e-3;
  p.pole(p.num_poles_u - 2, p.num_poles_v - 2)[2] += 1e-3;
  EXPECT_GT(max_g1_residual(b), 1e-6);
}

}  // namespace
}  // namespace subd2nurbs::testing
