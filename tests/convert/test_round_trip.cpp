// Converted corpus shapes written as STEP (AP214), IGES and BREP and read back with OCCT's
// readers: the same faces, the same area, still valid. And the STEP file that
// `subd2nurbs convert` writes for the sample is a valid solid when read back.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "convert/corpus_brep.h"
#include "converter/occt/writers.h"
#include "common/run_command.h"
#include "io/temp_dir.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

/// Relative area agreement after a write and a read.
constexpr double kAreaTolerance = 1e-9;

occt::BrepResult convert(const std::string& shape, int extra_levels = 0) {
  const LoadedCage cage = read_obj(corpus_file(shape));
  PatchOptions options;
  options.extra_levels = extra_levels;
  const PatchBuild build = build_patches(SubdivLevel::from_input(cage.input),
                                         std::vector<Point3>(cage.input.positions.begin(), cage.input.positions.end()),
                                         options);
  return occt::build_brep(build.set);
}

double relative_difference(double a, double b) { return std::abs(a - b) / std::max(std::abs(a), std::abs(b)); }

class RoundTrip : public ::testing::TestWithParam<std::string> {};

TEST_P(RoundTrip, StepIgesAndBrepKeepFacesAreaAndValidity) {
  const occt::BrepResult built = convert(GetParam());
  ASSERT_TRUE(built.valid) << built.check_message;
  const occt::ShapeSummary before = occt::summarize(built.shape, 2);
  TempDir dir;
  struct Case {
    const char* file;
    occt::Format format;
  };
  for (const Case& c : {Case{"shape.step", occt::Format::Step}, Case{"shape.igs", occt::Format::Iges},
                        Case{"shape.brep", occt::Format::Brep}}) {
    occt::write_shape(built.shape, dir.file(c.file), c.format, occt::StepSchema::AP214);
    const occt::ShapeSummary after = occt::summarize(occt::read_shape(dir.file(c.file)), 2);
    EXPECT_TRUE(after.valid) << c.file << ": " << after.check_message;
    EXPECT_EQ(after.faces, before.faces) << c.file;
    EXPECT_LE(relative_difference(after.area, before.area), kAreaTolerance)
        << c.file << ": area " << after.area << " vs " << before.area;
    std::printf("%-24s %-10s faces %4d area %.17g (rel. diff %.2g) valid %d\n", GetParam().c_str(), c.file,
                after.faces, after.area, relative_difference(after.area, before.area), after.valid);
  }
}

INSTANTIATE_TEST_SUITE_P(Corpus, RoundTrip,
                         ::testing::Values("catmark_cube", "catmark_torus", "catmark_pyramid",
                                           "catmark_dart_edgecorner"),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

TEST(RoundTripCheck, AreaComparisonNoticesAGeometricChange) {
  // One more level moves the surface near the cube's valence-3 vertices by about 1e-3 of its
  // size: the area comparison of the round trips must see that.
  const occt::ShapeSummary a = occt::summarize(convert("catmark_cube").shape, 2);
  const occt::ShapeSummary b = occt::summarize(convert("catmark_cube", 1).shape, 2);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_GT(relative_difference(a.area, b.area), 1e3 * kAreaTolerance) << a.area << " vs " << b.area;
}


TEST(CliStep, SampleReadsBackAsAValidSolid) {
  TempDir dir;
  const std::string out = dir.file("rounded_box.step");
  const std::string command = quote(SUBD2NURBS_EXE) + " convert " +
                              quote(std::string(SUBD2NURBS_SAMPLES_DIR) + "/rounded_box.obj") + " -o " +
                              quote(out) + " -q";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command;
  const occt::ShapeSummary s = occt::summarize(occt::read_shape(out));
  EXPECT_TRUE(s.valid) << s.check_message;
  EXPECT_EQ(s.solids, 1);
  EXPECT_EQ(s.shells, 1);
  // One per side: a side's 2 x 2 quads, each at a corner of the box (valence 3), join across
  // the side's own edges (C2); the box's edges are fan rays (G1) and stay edges.
  EXPECT_EQ(s.faces, 6);
  EXPECT_EQ(s.free_edges, 0);
  EXPECT_GT(s.volume, 0);
  // The cage spans [-1, 1]^3 and the limit surface lies inside its hull: a sphere-like body.
  EXPECT_LT(s.volume, 8.0);
  EXPECT_LE(s.max_gap, 1e-10 * std::sqrt(12.0));
}

}  // namespace
