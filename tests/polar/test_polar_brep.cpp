// Polar caps through OCCT: generated capped cylinders and mushrooms (pole valences 6..64,
// closed) become one valid solid with one face per cap and no free edges, and after a STEP
// write and read-back OCCT measures the same smoothness everywhere — cap boundaries and seams
// included (every edge of these shapes is G1 or smoother).
#include <gtest/gtest.h>

#include <string>

#include "common/shapes.h"
#include "converter/occt/brep_builder.h"
#include "converter/occt/shape_check.h"
#include "converter/occt/writers.h"
#include "core/patch/patch_builder.h"
#include "core/eval/continuity.h"
#include "io/obj_reader.h"
#include "io/temp_dir.h"

namespace subd2nurbs::testing {
namespace {

struct Case {
  std::string name;
  MeshInput input;
};

class PolarBrep : public ::testing::TestWithParam<int> {};

TEST_P(PolarBrep, StepReadBackIsAValidSmoothSolid) {
  const int n = GetParam();
  for (const Case& c : {Case{"cylinder", capped_cylinder(n, 0.05, 0.02)}, Case{"mushroom", mushroom(n, 0.1, 0.02)}}) {
    const PatchBuild b = build_patches(SubdivLevel::from_input(c.input), c.input.positions, PatchOptions{});
    ASSERT_EQ(b.info.caps.size(), 2u);
    const occt::BrepResult brep = occt::build_brep(b.set);
    ASSERT_TRUE(brep.valid) << c.name << n << ": " << brep.check_message;
    EXPECT_TRUE(brep.is_solid);
    TempDir dir;
    const std::string file = dir.file("polar.step");
    occt::write_shape(brep.shape, file, occt::Format::Step);
    const occt::ShapeSummary s = occt::summarize(occt::read_shape(file), 9, true);
    EXPECT_TRUE(s.valid) << c.name << n << ": " << s.check_message;
    EXPECT_EQ(s.solids, 1);
    EXPECT_EQ(s.faces, static_cast<int>(b.set.patches.size()));  // one face per cap
    EXPECT_EQ(s.free_edges, 0);
    EXPECT_GT(s.volume, 0);
    EXPECT_LE(s.max_gap, 1e-9 * b.set.model_size);
    EXPECT_LE(s.max_normal_angle_deg, 1e-6) << c.name << n;
    // Every shared edge measured: the n-piece cap boundaries and the seams included.
    EXPECT_EQ(s.shared_edges_sampled, s.edges - 2) << c.name << n;  // minus the two degenerate edges
    std::printf("%s n=%-3d faces %4d edges %4d max gap %.2e max normal angle %.2e deg volume %.6f\n",
                c.name.c_str(), n, s.faces, s.edges, s.max_gap, s.max_normal_angle_deg, s.volume);
    RecordProperty(c.name + "_max_normal_angle_deg", std::to_string(s.max_normal_angle_deg));
  }
}

INSTANTIATE_TEST_SUITE_P(Valences, PolarBrep, ::testing::Values(6, 7, 8, 12, 16, 24, 32, 64));

// OpenSubdiv's catmark_pole8 / catmark_pole64 have one quad ring around the pole, so they are
// not polar structures: they convert through Catmull-Clark (Construction Q at the pole), to a
// valid open shell that is G1 at the pole.
TEST(PolarCorpus, OneRingPolesConvertThroughCatmullClark) {
  for (const char* name : {"catmark_pole8", "catmark_pole64"}) {
    const LoadedCage cage = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/" + name + ".obj");
    const SubdivLevel base = SubdivLevel::from_input(cage.input);
    const PatchBuild b = build_patches(base, std::vector<Point3>(cage.input.positions.begin(), cage.input.positions.end()));
    EXPECT_TRUE(b.info.caps.empty()) << name;
    ASSERT_EQ(b.info.rejected_poles.size(), 1u) << name;
    EXPECT_NE(b.info.rejected_poles[0].reason.find("no 2-layer"), std::string::npos) << b.info.rejected_poles[0].reason;
    bool pole_fan = false;
    for (const IrregularFan& f : b.info.fans) pole_fan = pole_fan || (f.base_vertex == 4 && f.mode == FanMode::Smooth);
    EXPECT_TRUE(pole_fan) << name;
    const ContinuityReport k = measure_continuity(b.set);
    EXPECT_LT(k.max_normal_angle_deg, 1e-6) << name;
    const occt::BrepResult brep = occt::build_brep(b.set);
    ASSERT_TRUE(brep.valid) << name << ": " << brep.check_message;
    EXPECT_FALSE(brep.is_solid);
    EXPECT_EQ(brep.num_shells, 1);
    const occt::ShapeSummary s = occt::summarize(brep.shape, 9, false);
    EXPECT_LE(s.max_normal_angle_deg, 1e-6) << name;  // no creases: every shared edge is G1 or smoother
    EXPECT_GT(s.free_edges, 0);
  }
}

// Poles of valence 3..5 and poles too close to each other, with the separating first step
// (PatchOptions::separate_poles): valid smooth solids after a STEP round trip as well.
TEST(PolarBrepSeparated, LowValenceAndTooClosePoles) {
  for (const MeshInput& in : {capped_cylinder(3, 0.1, 0.02), capped_cylinder(4, 0.1, 0.02), mushroom(5, 0.1, 0.02),
                              revolved(8, {{0, 1}, {0.3, 1}, {0.7, 0.8}, {1, 0}, {0.7, -0.8}, {0.3, -1}, {0, -1}})}) {
    PatchOptions o;
    o.separate_poles = true;
    const PatchBuild b = build_patches(SubdivLevel::from_input(in), in.positions, o);
    ASSERT_EQ(b.info.caps.size(), 2u);
    const occt::BrepResult brep = occt::build_brep(b.set);
    ASSERT_TRUE(brep.valid) << brep.check_message;
    TempDir dir;
    occt::write_shape(brep.shape, dir.file("s.step"), occt::Format::Step);
    const occt::ShapeSummary s = occt::summarize(occt::read_shape(dir.file("s.step")), 9, false);
    EXPECT_TRUE(s.valid) << s.check_message;
    EXPECT_EQ(s.solids, 1);
    EXPECT_EQ(s.free_edges, 0);
    EXPECT_LE(s.max_normal_angle_deg, 1e-6);
  }
}

}  // namespace
}  // namespace subd2nurbs::testing
