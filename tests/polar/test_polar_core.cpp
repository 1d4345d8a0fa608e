// Polar structures in the core (MATH.md sections 2-4): BP subdivision identities, detection,
// and the singular polar cap, each checked against an independent property — an exact
// identity, iterated subdivision, an analytic symmetry, a convergence rate.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "common/shapes.h"
#include "core/nurbs/nurbs_eval.h"
#include "core/polar/polar_cap.h"
#include "core/polar/polar_net.h"
#include "core/polar/polar_structure.h"
#include "polar/polar_test_util.h"

namespace subd2nurbs::testing {
namespace {

PolarNet net_of(const MeshInput& in, int which = 0) {
  const SubdivLevel base = SubdivLevel::from_input(in);
  const PolarDetection d = detect_polar_structures(base);
  EXPECT_GT(d.structures.size(), static_cast<size_t>(which));
  return polar_net_of(d.structures.at(which), in.positions);
}

// --- BP subdivision -------------------------------------------------------------------------

TEST(BpSubdivision, RadialAndCircularStepsAreAffine) {
  for (int n : {6, 7, 12}) {
    const PolarNet a = net_of(mushroom(n, 0.1, 0.03));
    PolarNet b = a;
    const V3 t(3.5, -2.0, 7.25);
    b.pole = pt(ev(b.pole) + t);
    for (Point3& p : b.rings) p = pt(ev(p) + t);
    for (int step = 0; step < 2; ++step) {
      const PolarNet ra = step == 0 ? radial_step(a) : circular_step(a);
      const PolarNet rb = step == 0 ? radial_step(b) : circular_step(b);
      ASSERT_EQ(ra.rings.size(), rb.rings.size());
      EXPECT_LT((ev(rb.pole) - ev(ra.pole) - t).norm(), 1e-14 * t.norm());
      for (size_t i = 0; i < ra.rings.size(); ++i)
        EXPECT_LT((ev(rb.rings[i]) - ev(ra.rings[i]) - t).norm(), 1e-13 * t.norm()) << n << " " << i;
    }
    EXPECT_EQ(radial_step(a).num_rings(), 5);  // rings 0..3 -> 0..5 (MATH.md 3.3)
    EXPECT_EQ(circular_step(a).n, 2 * n);
  }
}

// The pole's limit: iterate the radial step (rings 0..2 suffice: the ring-1 rule only reads
// the pole and ring 1) and compare with the closed form (p0 + m) / 2.
TEST(BpSubdivision, LimitPointAndNormalMatchIteratedSubdivision) {
  for (int n : {6, 8, 11, 16, 64}) {
    // Translated so that the limit is the origin: after many steps the ring-1 offsets are
    // ~2^-30, and absolute coordinates would round them to 1e-7 relative.
    PolarNet in = net_of(mushroom(n, 0.2, 0.05));
    const V3 shift = ev(bp_limit_point(in));
    in.pole = pt(ev(in.pole) - shift);
    for (Point3& x : in.rings) x = pt(ev(x) - shift);
    PolarNet p = in;
    p.rings.resize(static_cast<size_t>(2) * n);
    for (int step = 0; step < 60; ++step) {
      p = radial_step(p);
      p.rings.resize(static_cast<size_t>(2) * n);
    }
    EXPECT_LT(ev(bp_limit_point(in)).norm(), 1e-15);
    EXPECT_LT(ev(p.pole).norm(), 1e-15) << "n = " << n;  // iterated pole -> the closed form
    // Ring 1 after 30 steps lies in the limit tangent plane up to (1/2)^30 of its radius: the
    // subdominant eigenvalue is 1/2 and the next 1/4.
    PolarNet q = in;
    q.rings.resize(static_cast<size_t>(2) * n);
    for (int step = 0; step < 30; ++step) {
      q = radial_step(q);
      q.rings.resize(static_cast<size_t>(2) * n);
    }
    const V3 N = ev(bp_limit_normal(in));
    EXPECT_NEAR(N.norm(), 1.0, 1e-14);
    for (int j = 0; j < n; ++j) {
      const V3 d = ev(q.at(1, j)) - ev(q.pole);
      EXPECT_LT(std::abs(d.dot(N)) / d.norm(), 1e-7) << "n = " << n << " spoke " << j;
    }
    // The limit normal is invariant under radial steps (t1, t2 halve).
    EXPECT_LT((ev(bp_limit_normal(radial_step(in))) - N).norm(), 1e-13);
  }
}

// Away from the pole (rings >= 3) BP is the uniform bicubic tensor spline of the (ring,
// spoke) grid: a radial step there is knot insertion, so the tensor limit mask at a vertex
// is unchanged, and a circular step is knot insertion in the other direction.
TEST(BpSubdivision, OuterRingsAreTheTensorSplineAndCircularStepsAreKnotInsertion) {
  for (int n : {6, 9, 32}) {
    PolarNet p = radial_step(net_of(capped_cylinder(n, 0.15, 0.04)));  // rings 0..5
    const PolarNet r = radial_step(p);                                  // rings 0..9
    const PolarNet c = circular_step(p);
    for (int j = 0; j < n; ++j) {
      EXPECT_LT((ev(bp_grid_limit(p, 3, j)) - ev(bp_grid_limit(r, 6, j))).norm(), 1e-14);
      EXPECT_LT((ev(bp_grid_limit(p, 4, j)) - ev(bp_grid_limit(r, 8, j))).norm(), 1e-14);
      EXPECT_LT((ev(bp_grid_limit(p, 3, j)) - ev(bp_grid_limit(c, 3, 2 * j))).norm(), 1e-14);
    }
    for (double U : {3.0, 3.3, 3.75, 4.0})
      for (double V : {0.0, 0.4, 2.5, n - 0.1}) {
        EXPECT_LT((grid_point(p, U, V) - grid_point(c, U, 2 * V)).norm(), 1e-14) << U << " " << V;
        EXPECT_LT((grid_point(p, U, V) - grid_point(r, 2 * U, V)).norm(), 1e-14) << U << " " << V;
      }
  }
}

// --- detection --------------------------------------------------------------------------------

TEST(PolarDetection, FindsBothPolesOfGeneratedShapes) {
  for (int n : {6, 7, 16, 64}) {
    for (const MeshInput& in : {capped_cylinder(n), mushroom(n)}) {
      const SubdivLevel base = SubdivLevel::from_input(in);
      const PolarDetection d = detect_polar_structures(base);
      ASSERT_EQ(d.structures.size(), 2u) << "n = " << n;
      EXPECT_TRUE(d.rejected.empty());
      const PolarStructure& top = d.structures[0];
      EXPECT_EQ(top.pole, 0);
      EXPECT_EQ(top.valence, n);
      for (int r = 0; r < 3; ++r)
        for (int j = 0; j < n; ++j) EXPECT_EQ(top.rings[r][j], 1 + r * n + j);  // spoke order kept
      EXPECT_EQ(top.cap_faces.size(), 2u * n);
      EXPECT_EQ(top.layer2_faces.size(), static_cast<size_t>(n));
      EXPECT_EQ(d.structures[1].pole, in.num_vertices() - 1);
    }
  }
}

TEST(PolarDetection, RejectsWithReasons) {
  auto reasons = [](const MeshInput& in) {
    const PolarDetection d = detect_polar_structures(SubdivLevel::from_input(in));
    std::string all;
    for (const RejectedPole& r : d.rejected) all += std::to_string(r.vertex) + ": " + r.reason + "\n";
    return std::make_pair(d.structures.size(), all);
  };
  {  // valence 5: below the BP minimum
    const auto [found, why] = reasons(capped_cylinder(5));
    EXPECT_EQ(found, 0u);
    EXPECT_NE(why.find("valence 5 is below 6"), std::string::npos) << why;
  }
  {  // two poles sharing ring 3: too close
    const auto [found, why] = reasons(revolved(8, {{0, 1}, {0.3, 1}, {0.7, 0.8}, {1, 0}, {0.7, -0.8}, {0.3, -1}, {0, -1}}));
    EXPECT_EQ(found, 0u);
    EXPECT_NE(why.find("too close"), std::string::npos) << why;
  }
  {  // only one quad ring between the poles' 1-links: ring 2 has valence 4 but no 2-layer quads
    const auto [found, why] = reasons(revolved(8, {{0, 1}, {0.5, 0.5}, {0.5, -0.5}, {0, -1}}));
    EXPECT_EQ(found, 0u);
    EXPECT_FALSE(why.empty());
  }
  {  // a crease inside the structure
    MeshInput in = capped_cylinder(8);
    in.creases.push_back({0, 1, 2.0});
    const auto [found, why] = reasons(in);
    EXPECT_EQ(found, 1u);
    EXPECT_NE(why.find("creased"), std::string::npos) << why;
  }
}

// --- the cap ---------------------------------------------------------------------------------

TEST(PolarCap, CentreIsTheBpLimitPointAndTheCollapsedEdgeIsThere) {
  for (int n : {6, 10, 64}) {
    const PolarNet in = net_of(mushroom(n, 0.3, 0.04));
    for (int s : {1, 2}) {
      const PolarCap cap = build_polar_cap(in, {s, 0.75});
      EXPECT_EQ(cap.m, s == 1 ? 3 : 7);
      EXPECT_LT((ev(cap.centre) - ev(bp_limit_point(in))).norm(), 1e-15 * 4);
      EXPECT_LT((ev(cap.normal) - ev(bp_limit_normal(in))).norm(), 1e-13);
      const NurbsPatch patch = polar_cap_patch(cap, 0);
      for (double v : {0.0, 0.13, 0.5, 0.99, 1.0})
        EXPECT_LT((ev(evaluate(patch, 0, v).p) - ev(cap.centre)).norm(), 1e-14) << v;
    }
  }
}

TEST(PolarCap, CircularKnotInsertionLeavesTheCapUnchanged) {
  for (int n : {6, 13, 40}) {
    const PolarCap cap = build_polar_cap(net_of(capped_cylinder(n, 0.2, 0.05)), {1, 0.75});
    const NurbsPatch p0 = polar_cap_patch(cap, 0), p1 = polar_cap_patch(cap, 1), p2 = polar_cap_patch(cap, 2);
    EXPECT_EQ(p1.num_poles_v, 2 * n + 3);
    EXPECT_EQ(p2.num_poles_v, 4 * n + 3);
    for (double u : {0.0, 0.01, 0.3, 0.71, 1.0})
      for (double v : {0.0, 0.05, 0.377, 0.8, 1.0}) {
        const SurfaceDerivs a = evaluate(p0, u, v), b = evaluate(p1, u, v), c = evaluate(p2, u, v);
        EXPECT_LT((ev(a.p) - ev(b.p)).norm(), 1e-14);
        EXPECT_LT((ev(a.p) - ev(c.p)).norm(), 1e-14);
        EXPECT_LT((ev(a.du) - ev(c.du)).norm(), 1e-12 * (1 + ev(a.du).norm()));
        EXPECT_LT((ev(a.dv) - ev(c.dv)).norm(), 1e-12 * (1 + ev(a.dv).norm()));
      }
  }
}

// The cap equals the BP limit for u >= 2 (MATH.md 4.2) and differs only between the pole
// and ring 3 of the pre-subdivided net; more radial pre-steps shrink that region, so the
// distance from the BP limit to the cap falls.
TEST(PolarCap, ConvergesToTheBpLimitAsRadialPreStepsGrow) {
  for (int n : {6, 8, 16}) {
    for (const MeshInput& shape : {capped_cylinder(n, 0.1, 0.03), mushroom(n, 0.25, 0.03)}) {
      const PolarNet in = net_of(shape);
      double previous = 0;
      for (int s = 1; s <= 4; ++s) {
        const PolarCap cap = build_polar_cap(in, {s, 0.75});
        const double d = cap_distance_to_bp(in, cap, polar_cap_patch(cap, 0), s + 4);
        if (n == 8) RecordProperty("distance_s" + std::to_string(s), std::to_string(d));
        if (s > 1) EXPECT_LT(d, 0.7 * previous) << "n = " << n << ", steps " << s << ": " << previous << " -> " << d;
        previous = d;
      }
    }
  }
}

TEST(PolarCap, RotationallySymmetricStructureGivesASymmetricCap) {
  for (int n : {6, 9, 24}) {
    for (const MeshInput& shape : {capped_cylinder(n, 0.4), mushroom(n, -0.2)}) {
      const PolarCap cap = build_polar_cap(net_of(shape), {1, 0.75});
      const NurbsPatch patch = polar_cap_patch(cap, 1);
      const Eigen::Matrix3d rot = Eigen::AngleAxisd(2 * M_PI / n, V3::UnitZ()).toRotationMatrix();
      for (double u : {0.02, 0.4, 0.9, 1.0})
        for (double v : {0.0, 0.031, 0.5, 0.77}) {
          const V3 a = ev(evaluate(patch, u, v).p);
          const double v2 = std::fmod(v + 1.0 / n, 1.0);
          const V3 b = ev(evaluate(patch, u, v2).p);
          EXPECT_LT((rot * a - b).norm(), 1e-13) << n << " " << u << " " << v;
        }
    }
  }
}

// Curvature at the pole stays bounded (the 1-link projection, MATH.md 4.1 (iv)) and the
// normal converges to the BP limit normal, linearly in the distance.
TEST(PolarCap, BoundedCurvatureAndNormalConvergenceAtThePole) {
  for (int n : {6, 8, 12, 16, 64}) {
    const MeshInput shapes[2] = {capped_cylinder(n, 0.1, 0.05), mushroom(n, 0.3, 0.04)};
    for (const MeshInput& shape : shapes) {
      const PolarCap cap = build_polar_cap(net_of(shape), {1, 0.75});
      const NurbsPatch patch = relative_to_centre(polar_cap_patch(cap, 0), cap.centre);
      double kmax[4], angle[4];
      const double dist[4] = {1e-1, 1e-2, 1e-3, 1e-4};
      for (int i = 0; i < 4; ++i) {
        kmax[i] = 0;
        angle[i] = 0;
        for (int q = 0; q < 64; ++q) {
          const double u = dist[i] / cap.m, v = (q + 0.5) / 64;
          const Curvature c = curvature(evaluate(patch, u, v));
          kmax[i] = std::max({kmax[i], std::abs(c.k1), std::abs(c.k2)});
          angle[i] = std::max(angle[i], angle_deg(c.normal, ev(cap.normal)));
        }
      }
      if (n == 8 || n == 64)
        for (int i = 0; i < 4; ++i) {
          const std::string key = "n" + std::to_string(n) + "_" + std::to_string(&shape == &shapes[0] ? 0 : 1) + "_d" + std::to_string(i + 1);
          RecordProperty(key + "_kmax", std::to_string(kmax[i]));
          RecordProperty(key + "_angle_deg", std::to_string(angle[i]));
        }
      EXPECT_TRUE(std::isfinite(kmax[3]));
      EXPECT_LT(kmax[3], 2 * kmax[1]) << "n = " << n << ": max |k| at 1e-4 " << kmax[3] << " vs 1e-2 " << kmax[1];
      EXPECT_LT(kmax[2], 2 * kmax[1]) << "n = " << n;
      // Linear convergence: a factor ~10 per decade (at least 5 asserted).
      EXPECT_LT(angle[2], angle[1] / 5) << "n = " << n;
      EXPECT_LT(angle[3], angle[2] / 5) << "n = " << n;
      EXPECT_LT(angle[3], 1e-2) << "n = " << n;
    }
  }
}

// Without the 1-link projection (lambda -> the raw ring) the paper's Lemma 1 predicts no
// tangent plane: the test above must be able to fail. Here row 1 is put back to the
// pre-subdivided ring 1 and the normal spread at the pole stays large.
TEST(PolarCap, WithoutTheProjectionThereIsNoTangentPlane) {
  const PolarNet in = net_of(capped_cylinder(8, 0.1, 0.08));
  PolarCap cap = build_polar_cap(in, {1, 0.75});
  const PolarNet p = radial_step(in);
  for (int j = 0; j < cap.n; ++j) cap.rows[static_cast<size_t>(cap.n) + j] = p.at(1, j);
  const NurbsPatch patch = relative_to_centre(polar_cap_patch(cap, 0), cap.centre);
  double spread = 0;
  for (int q = 0; q < 32; ++q)
    spread = std::max(spread, angle_deg(unit(evaluate(patch, 1e-5, q / 32.0)), ev(cap.normal)));
  EXPECT_GT(spread, 0.5);
}

}  // namespace
}  // namespace subd2nurbs::testing
