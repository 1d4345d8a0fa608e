// The shape fit's command line: `subd2nurbs fit CAGE --to TARGET` and `check --to TARGET`
// through the executable. Oracle: a torus cage's exact limit (LimitEvaluator), written by the
// test as a PLY triangle mesh or an .xyz point cloud; the perturbed cage must come back to it.
// The fitted OBJ is measured here again (measure_target_distance), not only through the report.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "common/json_text.h"
#include "common/run_command.h"
#include "core/eval/target_distance.h"
#include "fit/shape_fit_test_util.h"
#include "io/obj_reader.h"
#include "io/input_error.h"
#include "io/obj_writer.h"
#include "io/target_reader.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

const std::string kExe = SUBD2NURBS_EXE;

void write_ply(const std::string& path, const std::vector<Point3>& points,
               const std::vector<std::array<int, 3>>& triangles) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fprintf(f, "ply\nformat ascii 1.0\nelement vertex %zu\nproperty double x\nproperty double y\nproperty double z\n"
               "element face %zu\nproperty list uchar int vertex_indices\nend_header\n", points.size(), triangles.size());
  for (const Point3& p : points) std::fprintf(f, "%.17g %.17g %.17g\n", p[0], p[1], p[2]);
  for (const auto& t : triangles) std::fprintf(f, "3 %d %d %d\n", t[0], t[1], t[2]);
  std::fclose(f);
}

void write_xyz(const std::string& path, const std::vector<Point3>& points, const Point3& shift = {0, 0, 0}) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fprintf(f, "# x y z\n");
  for (const Point3& p : points) std::fprintf(f, "%.17g %.17g %.17g\n", p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]);
  std::fclose(f);
}

/// The larger of the two maxima of a two-sided distance ("before" / "after" / "target").
double two_sided(const std::string& json, const std::string& member) {
  return std::max(json_number(json, {member, "limit_to_target", "max"}),
                  json_number(json, {member, "target_to_limit", "max"}));
}

/// The torus with a ring of semi-sharp creases (sharpness 1; tags written and read back). With
/// sharpness >= 3 the fit stalls near 1e-4 (docs/fitting.md, "Convergence and limits").
MeshInput creased_torus() {
  MeshInput in = torus_cage(8, 6, 3, 1);
  for (int i = 0; i < 8; ++i) in.creases.push_back({i * 6, ((i + 1) % 8) * 6, 1.0});
  return in;
}

/// The exact limit at the measure's own samples: (i + 0.5) / grid per ptex face.
std::vector<Point3> limit_samples(const LimitEvaluator& limit, int grid = 8) {
  std::vector<Point3> out;
  for (int p = 0; p < limit.num_ptex_faces(); ++p)
    for (int i = 0; i < grid; ++i)
      for (int j = 0; j < grid; ++j) out.push_back(limit.evaluate_ptex(p, (i + 0.5) / grid, (j + 0.5) / grid).p);
  return out;
}

}  // namespace

TEST(ShapeFitCli, FitsAPerturbedTorusToItsLimit) {
  TempDir dir;
  const MeshInput in = creased_torus();
  const SubdivLevel level = SubdivLevel::from_input(in);
  const std::vector<Point3> truth = positions_of(in);
  // g = 16: the measure's limit samples ((i + 0.5) / 8 per ptex face) are target vertices, so the
  // target's chord error does not enter the limit -> target distance.
  const LimitTarget lt = limit_target(LimitEvaluator(level, truth), 16);
  const std::string target = dir.file("target.ply"), cage = dir.file("cage.obj"), out = dir.file("fitted.obj"),
                    report = dir.file("fit.json");
  write_ply(target, lt.points, lt.triangles);
  write_obj(cage, perturbed(truth, 0.01, 7), level);

  // An exact target needs little regularisation: the default smoothing (1e-4) alone keeps the
  // fit 2e-5 off this torus.
  CommandResult r = run_command(quote(kExe) + " fit " + quote(cage) + " --to " + quote(target) + " -o " + quote(out) +
                                " --smoothing 1e-8 --report " + quote(report));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("subd2nurbs: iteration 1: objective"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("subd2nurbs: after: limit -> target max"), std::string::npos) << r.err;
  const std::string json = read_text(report);
  const double before = two_sided(json, "before"), after = two_sided(json, "after");
  std::printf("fit: two-sided max distance before %.3g, after %.3g (relative); %d iterations, %s\n", before, after,
              static_cast<int>(json_number(json, {"iterations"})), r.err.substr(r.err.find("stopped")).c_str());
  EXPECT_LT(after, 1e-5);
  EXPECT_LT(after, 1e-2 * before);
  EXPECT_GT(json_number(json, {"iterations"}), 0);

  // The OBJ: same faces and tags; its limit measured here again.
  const LoadedCage fitted = read_obj(out);
  EXPECT_EQ(fitted.input.face_sizes, in.face_sizes);
  EXPECT_EQ(fitted.input.face_indices, in.face_indices);
  ASSERT_EQ(fitted.input.creases.size(), in.creases.size());
  for (size_t k = 0; k < in.creases.size(); ++k) EXPECT_EQ(fitted.input.creases[k].sharpness, 1.0);
  const TargetShape t = read_target(target);
  const ShapeTarget shape(t.points, t.triangles);
  const TargetDistance d = measure_target_distance(LimitEvaluator(level, positions_of(fitted.input)), shape);
  EXPECT_LT(std::max(d.limit_to_target.max, d.target_to_limit.max), 1e-5);

  // A missing target: exit 2 naming it; bad options: exit 1 naming the option; nothing written.
  const std::string none = dir.file("missing.ply"), out2 = dir.file("never.obj");
  r = run_command(quote(kExe) + " fit " + quote(cage) + " --to " + quote(none) + " -o " + quote(out2));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("missing.ply"), std::string::npos) << r.err;
  for (const std::string& bad : {std::string("--smoothing -1"), std::string("--levels 0"), std::string("--levels 5"),
                                 std::string("--max-iterations 0"), std::string("--tolerance 0"),
                                 std::string("--min-gain -1")}) {
    r = run_command(quote(kExe) + " fit " + quote(cage) + " --to " + quote(target) + " -o " + quote(out2) + " " + bad);
    EXPECT_EQ(r.exit_code, 1) << bad << ": " << r.err;
    EXPECT_NE(r.err.find(bad.substr(0, bad.find(' '))), std::string::npos) << r.err;
  }
  EXPECT_FALSE(std::ifstream(out2).good());
}

// fit --exact-target: the recovery setting from the command line. The same perturbed creased
// torus and exact target as above: the default weights stop near the smoothing's pull (about
// 2e-5), the exact-target weights recover the limit to 1e-6 of the diagonal (two-sided,
// measured here again on the written OBJ).
TEST(ShapeFitCli, ExactTargetRecoversTheLimit) {
  TempDir dir;
  const MeshInput in = creased_torus();
  const SubdivLevel level = SubdivLevel::from_input(in);
  const std::vector<Point3> truth = positions_of(in);
  const LimitTarget lt = limit_target(LimitEvaluator(level, truth), 16);
  const std::string target = dir.file("target.ply"), cage = dir.file("cage.obj");
  write_ply(target, lt.points, lt.triangles);
  write_obj(cage, perturbed(truth, 0.01, 7), level);
  double after[2] = {0, 0};
  for (int exact = 0; exact < 2; ++exact) {
    const std::string out = dir.file(exact ? "exact.obj" : "default.obj");
    const CommandResult r = run_command(quote(kExe) + " fit " + quote(cage) + " --to " + quote(target) + " -o " +
                                        quote(out) + " -q" + (exact ? " --exact-target" : ""));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const TargetDistance d =
        measure_target_distance(LimitEvaluator(level, positions_of(read_obj(out).input)), ShapeTarget(lt.points, lt.triangles));
    after[exact] = std::max(d.limit_to_target.max, d.target_to_limit.max);
  }
  std::printf("fit: two-sided max distance, default weights %.3g, --exact-target %.3g (relative)\n", after[0], after[1]);
  EXPECT_LT(after[1], 1e-6);
  EXPECT_GT(after[0], 1e-6);  // the flag is what makes the difference
}

// fit --tag-features: the box cage without tags, against the sharp box (a triangulated
// PLY): the report's tagged_edges and the written creases are the box's 36 edge-running cage
// edges (oracle: both ends on one box edge, two coordinates at the box's bounds), and the
// tagged fit ends closer than the untagged one.
TEST(ShapeFitCli, TagFeaturesCreasesTheBoxsEdges) {
  TempDir dir;
  const Point3 size = {1.0, 0.5, 0.25};
  const MeshInput plain = box_cage(3, size, false), box = box_cage(16, size, false);
  std::vector<std::array<int, 3>> tris;
  for (size_t f = 0; f < box.face_sizes.size(); ++f) {
    const int* q = &box.face_indices[4 * f];
    tris.push_back({q[0], q[1], q[2]});
    tris.push_back({q[0], q[2], q[3]});
  }
  const std::string target = dir.file("box.ply"), cage = dir.file("cage.obj"), out = dir.file("tagged.obj"),
                    report = dir.file("tagged.json"), out0 = dir.file("plain.obj"), report0 = dir.file("plain.json");
  write_ply(target, box.positions, tris);
  write_obj(cage, perturbed(positions_of(plain), 0.005, 5), SubdivLevel::from_input(plain));
  CommandResult r = run_command(quote(kExe) + " fit " + quote(cage) + " --to " + quote(target) + " -o " + quote(out) +
                                " --tag-features --max-iterations 10 --report " + quote(report));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("tagged 36 cage edges"), std::string::npos) << r.err;
  const std::string json = read_text(report);
  EXPECT_EQ(json_number(json, {"tagged_edges"}), 36);
  const LoadedCage fitted = read_obj(out);
  ASSERT_EQ(fitted.input.creases.size(), 36u);
  for (const CreaseTag& c : fitted.input.creases) {
    EXPECT_GE(c.sharpness, kInfiniteSharpness);
    int shared = 0;  // coordinates where both ends sit on the same bound of the box
    for (int d = 0; d < 3; ++d)
      shared += std::abs(std::abs(plain.positions[c.v0][d]) - size[d]) < 1e-12 &&
                plain.positions[c.v0][d] == plain.positions[c.v1][d];
    EXPECT_GE(shared, 2) << c.v0 << " " << c.v1;
  }
  r = run_command(quote(kExe) + " fit " + quote(cage) + " --to " + quote(target) + " -o " + quote(out0) +
                  " --max-iterations 10 --report " + quote(report0));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string json0 = read_text(report0);
  EXPECT_TRUE(read_obj(out0).input.creases.empty());
  std::printf("box: two-sided max after the fit: untagged %.3g, tagged %.3g\n", two_sided(json0, "after"),
              two_sided(json, "after"));
  EXPECT_LT(two_sided(json, "after"), 0.1 * two_sided(json0, "after"));
}

// check --to: the cage's own limit samples are at distance 0 (rounding); moved, they are not.
TEST(ShapeFitCli, CheckMeasuresTheDistanceToATarget) {
  TempDir dir;
  const MeshInput in = creased_torus();
  const SubdivLevel level = SubdivLevel::from_input(in);
  const std::vector<Point3> pts = limit_samples(LimitEvaluator(level, positions_of(in)));
  const double diag = diagonal(pts);
  const std::string cage = dir.file("cage.obj"), own = dir.file("own.xyz"), moved = dir.file("moved.xyz"),
                    json = dir.file("q.json"), plain = dir.file("plain.json");
  write_obj(cage, positions_of(in), level);
  write_xyz(own, pts);
  write_xyz(moved, pts, {1e-3 * diag, 0, 0});

  CommandResult r = run_command(quote(kExe) + " check " + quote(cage) + " --to " + quote(own) + " --json " + quote(json));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("quality: target"), std::string::npos) << r.err;
  std::string text = read_text(json);
  const double zero = two_sided(text, "target");
  std::printf("check --to: own limit samples %.3g, ", zero);
  EXPECT_LT(zero, 1e-9);

  r = run_command(quote(kExe) + " check " + quote(cage) + " --to " + quote(moved) + " --json " + quote(json));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  text = read_text(json);
  const double shifted = two_sided(text, "target");
  std::printf("moved by 1e-3 x diagonal %.3g\n", shifted);
  EXPECT_GT(shifted, 5e-4);
  EXPECT_LT(shifted, 2e-3);

  // Without --to: no "target" member, no target line.
  r = run_command(quote(kExe) + " check " + quote(cage) + " --json " + quote(plain));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_text(plain).find("\"target\""), std::string::npos);
  EXPECT_EQ(r.err.find("quality: target"), std::string::npos);

  // A malformed target names FILE:LINE (exit 2).
  const std::string bad = dir.file("bad.xyz");
  std::ofstream(bad) << "1 2 3\n4 five 6\n";
  r = run_command(quote(kExe) + " check " + quote(cage) + " --to " + quote(bad));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("bad.xyz:2:"), std::string::npos) << r.err;
}

// io/target_reader: polygons fan-triangulated without quad recovery, unused vertices dropped;
// vertices without faces (OBJ `v` lines, PLY vertices only) and .xyz are point clouds; .xyz
// errors name FILE:LINE.
TEST(ShapeFitCli, TargetReaderMeshesAndClouds) {
  TempDir dir;
  const std::string quad = dir.file("quad.obj"), cloud = dir.file("cloud.obj"), ply = dir.file("cloud.ply"),
                    tris = dir.file("two.off"), xyz = dir.file("p.xyz");
  std::ofstream(quad) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 1 0.5\nv 5 5 5\nf 1 2 3 4 5\n";
  std::ofstream(cloud) << "v 0 0 0\nv 1 0 0\nv 1 1 0\n";
  std::ofstream(ply) << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                        "end_header\n0 0 0\n1 2 3\n";
  // Two triangles forming a quad: kept as triangles (no quad recovery for targets).
  std::ofstream(tris) << "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
  std::ofstream(xyz) << "# points\n0 0 0\n\n1,2,3 0.5 extra\n";
  TargetShape t = read_target(quad);
  EXPECT_EQ(t.points.size(), 5u);  // vertex 6 unused
  EXPECT_EQ(t.triangles, (std::vector<std::array<int, 3>>{{0, 1, 2}, {0, 2, 3}, {0, 3, 4}}));
  EXPECT_EQ(read_target(cloud).points.size(), 3u);
  EXPECT_TRUE(read_target(cloud).triangles.empty());
  t = read_target(ply);
  EXPECT_EQ(t.points.size(), 2u);
  EXPECT_TRUE(t.triangles.empty());
  EXPECT_EQ(read_target(tris).triangles.size(), 2u);
  t = read_target(xyz);
  ASSERT_EQ(t.points.size(), 2u);
  EXPECT_EQ(t.points[1], (Point3{1, 2, 3}));
  for (const auto& [text, line] : std::vector<std::pair<std::string, std::string>>{
           {"1 2 3\n1 2\n", ":2:"}, {"1 2 nan\n", ":1:"}, {"# nothing\n", "no points"}, {"\n\nx 1 2\n", ":3:"}}) {
    std::ofstream(xyz) << text;
    try {
      read_target(xyz);
      ADD_FAILURE() << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(line), std::string::npos) << e.what();
    }
  }
}

// convert --fit-to is `fit` then `convert` of the fitted cage: the same patches, bit for bit
// (the fitted OBJ keeps every coordinate exactly), and it excludes --fit interpolate.
TEST(ShapeFitCli, ConvertFitToIsFitThenConvert) {
  TempDir dir;
  const MeshInput in = creased_torus();
  const SubdivLevel level = SubdivLevel::from_input(in);
  const std::vector<Point3> truth = positions_of(in);
  const LimitTarget lt = limit_target(LimitEvaluator(level, truth), 8);
  const std::string target = dir.file("target.ply"), cage = dir.file("cage.obj"), fitted = dir.file("fitted.obj"),
                    two_steps = dir.file("two.json"), one_step = dir.file("one.json");
  write_ply(target, lt.points, lt.triangles);
  write_obj(cage, perturbed(truth, 0.01, 11), level);
  CommandResult r = run_command(quote(kExe) + " fit " + quote(cage) + " --to " + quote(target) + " -o " +
                                quote(fitted) + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_command(quote(kExe) + " convert " + quote(fitted) + " -o " + quote(two_steps) + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string report = dir.file("report.json");
  r = run_command(quote(kExe) + " convert " + quote(cage) + " --fit-to " + quote(target) + " -o " + quote(one_step) +
                  " --report " + quote(report));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("subd2nurbs: after: limit -> target max"), std::string::npos) << r.err;
  EXPECT_EQ(read_text(one_step), read_text(two_steps));
  // The report's fit.to_target: the two-sided distances before and after against the measure
  // taken here of the input cage and of `fit`'s output (the same fit), and the stop reason.
  const std::string json = read_text(report);
  const ShapeTarget shape(lt.points, lt.triangles);
  const TargetDistance before = measure_target_distance(LimitEvaluator(level, read_obj(cage).input.positions), shape);
  const TargetDistance after = measure_target_distance(LimitEvaluator(level, read_obj(fitted).input.positions), shape);
  for (const auto& [member, d] : {std::pair<const char*, const TargetDistance&>{"before", before}, {"after", after}})
    for (const char* side : {"limit_to_target", "target_to_limit"}) {
      const DistanceStats& st = std::string(side) == "limit_to_target" ? d.limit_to_target : d.target_to_limit;
      EXPECT_NEAR(json_number(json, {"fit", "to_target", member, side, "max"}), st.max, 1e-9 * st.max + 1e-15) << member << side;
    }
  EXPECT_GT(json_number(json, {"fit", "to_target", "iterations"}), 0);
  EXPECT_NE(json.find("\"stop\": \""), std::string::npos);
  // (this 8 x 8 target's chords are ~1e-3 off the limit between its vertices, and the default
  // smoothing biases the fit: only the improvement is claimed)
  EXPECT_LT(after.target_to_limit.max, 0.1 * before.target_to_limit.max);
  // Without --fit-to the perturbed cage's own patches differ.
  r = run_command(quote(kExe) + " convert " + quote(cage) + " -o " + quote(two_steps) + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(read_text(one_step), read_text(two_steps));
  r = run_command(quote(kExe) + " convert " + quote(cage) + " --fit-to " + quote(target) + " --fit interpolate -o " +
                  quote(dir.file("never.json")));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("--fit-to and --fit interpolate"), std::string::npos) << r.err;
}
