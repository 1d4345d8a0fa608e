// The quality report (core/eval/quality.h) against OCCT's independent measurement of the STEP
// file the conversion writes: the read-back surfaces sampled at the same parameters give the
// same same-parameter deviation from the exact limit, and OCCT's normal angle across the shared
// edges matches the report's normal jumps. Small shapes only (STEP read-back is slow).
#include <gtest/gtest.h>

#include <BRep_Tool.hxx>
#include <Geom_Surface.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <gp_Pnt.hxx>

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "converter/occt/shape_check.h"
#include "converter/occt/writers.h"
#include "converter/pipeline/conversion.h"
#include "core/nurbs/nurbs_eval.h"
#include "converter/pipeline/report.h"
#include "core/eval/quality.h"
#include "io/patch_json.h"
#include "io/temp_dir.h"
#include "limit_test_util.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

struct Converted {
  SubdivLevel base;
  std::vector<Point3> pos;
  pipeline::ConversionResult result;
};

Converted convert_shape(const std::string& name) {
  Converted c;
  const LoadedCage cage = read_obj(limit_corpus_path(name));
  c.base = SubdivLevel::from_input(cage.input);
  c.pos = positions_of(cage.input);
  pipeline::ConversionSettings settings;
  settings.level = 0;
  // Each read-back face is matched to its patch by its parametrisation: coplanar faces stay
  // B-splines (merged, they would be planes with parameters of their own).
  settings.planar = pipeline::PlanarMode::Keep;
  c.result = pipeline::convert(c.base, c.pos, settings);
  return c;
}

}  // namespace

class QualityVsOcct : public ::testing::TestWithParam<const char*> {};

TEST_P(QualityVsOcct, DeviationAndNormalJumpsAgreeWithTheReadBackStep) {
  const Converted c = convert_shape(GetParam());
  ASSERT_TRUE(c.result.brep.valid);
  const LimitEvaluator limit(c.base, c.pos);
  const int n = 7;  // steps of 1/6: not at the level-k vertices, where Construction Q interpolates
  // The exported faces (packed, the default) are what is measured and what OCCT reads back.
  const PackedSet& out = c.result.exported;
  const QualityReport q = measure_quality(c.result.build, limit, c.result.continuity, n, &out);
  const double size = c.result.build.set.model_size;

  TempDir dir;
  const std::string step = dir.file("out.step");
  occt::write_shape(c.result.brep.shape, step, occt::Format::Step);
  const TopoDS_Shape back = occt::read_shape(step);

  // Faces of the read-back shape, matched to the exported patches by their centre point.
  const PatchSet& ps = out.set;
  std::vector<Handle(Geom_Surface)> surfaces;
  for (TopExp_Explorer ex(back, TopAbs_FACE); ex.More(); ex.Next())
    surfaces.push_back(BRep_Tool::Surface(TopoDS::Face(ex.Current())));
  ASSERT_EQ(surfaces.size(), ps.patches.size());
  std::vector<size_t> face_of(ps.patches.size());
  for (size_t pi = 0; pi < ps.patches.size(); ++pi) {
    const double um = ps.patches[pi].knots_u.knots.back() / 2, vm = ps.patches[pi].knots_v.knots.back() / 2;
    const Point3 centre = evaluate(ps.patches[pi], um, vm).p;
    double best_d = HUGE_VAL;
    for (size_t k = 0; k < surfaces.size(); ++k) {
      const gp_Pnt x = surfaces[k]->Value(um, vm);
      const double d = dist({x.X(), x.Y(), x.Z()}, centre);
      if (d < best_d) best_d = d, face_of[pi] = k;
    }
    ASSERT_LT(best_d, 1e-9 * size) << "no read-back face has patch " << pi << "'s parametrisation";
  }
  // Every quad's samples, on the read-back face that holds it.
  double occt_parametric_max = 0;
  for (size_t qi = 0; qi < c.result.build.set.patches.size(); ++qi)
    for (const auto& st : quality_sample_parameters(
             c.result.build, static_cast<int>(qi), n,
             sampled_as_polynomial(c.result.build, limit, static_cast<int>(qi), &out))) {
      double u, v;
      place_parameters(out.place[qi], st[0], st[1], u, v);
      const gp_Pnt x = surfaces[face_of[out.place[qi].patch]]->Value(u, v);
      const LimitParam lp = patch_to_limit(c.result.build, static_cast<int>(qi), st[0], st[1]);
      const LimitSample L = limit.evaluate(lp.face, lp.sub, lp.u, lp.v);
      occt_parametric_max = std::max(occt_parametric_max, dist({x.X(), x.Y(), x.Z()}, L.p));
    }
  EXPECT_NEAR(q.parametric_max, occt_parametric_max, 1e-9 * size);
  if (c.result.build.info.pccm_patches > 0) {
    EXPECT_GT(q.parametric_max, 1e-6 * size);  // patches at irregular vertices approximate
  } else {
    EXPECT_LT(q.parametric_max, 1e-12 * size);  // every patch is the limit itself
  }
  EXPECT_LE(q.deviation_max, q.parametric_max + 1e-15 * size);

  // Normal jumps: OCCT's angle between the faces across every shared edge vs the report's.
  const occt::ShapeSummary summary = occt::summarize(back, 24, false);
  double ours = 0, limit_max = 0;
  for (const EdgeQuality& e : q.edges) {
    ours = std::max(ours, e.normal_jump_deg);
    limit_max = std::max(limit_max, e.limit_normal_jump_deg);
  }
  EXPECT_NEAR(summary.max_normal_angle_deg, ours, 1e-3) << "largest normal jump over the shared edges";
  EXPECT_NEAR(summary.max_normal_angle_deg, limit_max, q.max_normal_jump_error_deg + 1e-3);
  EXPECT_LE(summary.max_gap, q.max_gap + 1e-7 * size);  // OCCT also counts its edge tolerance
  std::printf("%s: parametric max %.3g (OCCT %.3g), distance max %.3g, normal jump %.4g deg (OCCT %.4g, limit %.4g)\n",
              GetParam(), q.parametric_max, occt_parametric_max, q.deviation_max, ours,
              summary.max_normal_angle_deg, limit_max);
}

INSTANTIATE_TEST_SUITE_P(Small, QualityVsOcct,
                         ::testing::Values("catmark_cube", "catmark_pyramid", "catmark_edgecorner",
                                           "catmark_cubes_infsharp", "catmark_tent_creases0"),
                         [](const ::testing::TestParamInfo<const char*>& i) { return std::string(i.param); });

TEST(Quality, RegularPatchesAreTheLimitAndCreasesAreExpected) {
  // catmark_torus: every vertex regular, so every patch is the limit itself.
  {
    const Converted c = convert_shape("catmark_torus");
    const LimitEvaluator limit(c.base, c.pos);
    const QualityReport q = measure_quality(c.result.build, limit, c.result.continuity, 5, &c.result.exported);
    EXPECT_LT(q.parametric_max, 1e-12 * c.result.build.set.model_size);
    EXPECT_EQ(q.crease_edges, 0);
    EXPECT_EQ(q.class_mismatches, 0);
    EXPECT_LT(q.max_normal_jump_error_deg, 1e-6);
    EXPECT_GT(q.curvature.samples, 0);
  }
  // catmark_cube_creases1 has infinitely sharp edges: expected creases with a limit normal jump.
  {
    const Converted c = convert_shape("catmark_cubes_infsharp");
    const LimitEvaluator limit(c.base, c.pos);
    const QualityReport q = measure_quality(c.result.build, limit, c.result.continuity, 3, &c.result.exported);
    EXPECT_GT(q.crease_edges, 0);
    double crease_jump = 0;
    for (const EdgeQuality& e : q.edges)
      if (std::string(e.expected) == "crease") crease_jump = std::max(crease_jump, e.limit_normal_jump_deg);
    EXPECT_GT(crease_jump, 1.0);
  }
}

// Where the patch and the limit are one bicubic each over a quad, the report samples the 4 x 4
// grid {0, 1/3, 2/3, 1}^2 only (docs/math.md 11.2). Oracle: a dense evaluation of a patch with a
// moved pole (100 x 100 points, the nodes among them); its largest distance lies between the
// sampled one and kPolynomialBound times it. Every regular quad of the torus (all vertices of
// valence 4) is sampled so.
TEST(Quality, PolynomialQuadsAreCertifiedByTheirSixteenNodes) {
  Converted c = convert_shape("catmark_torus");
  const LimitEvaluator limit(c.base, c.pos);
  PatchBuild& build = c.result.build;
  const int patches = static_cast<int>(build.set.patches.size());
  const double size = build.set.model_size;
  for (const PackedSet* exported : std::initializer_list<const PackedSet*>{nullptr, &c.result.exported}) {
    const QualityReport q = measure_quality(build, limit, c.result.continuity, 9, exported);
    EXPECT_EQ(q.polynomial_patches, patches);
    EXPECT_EQ(q.deviation_samples, patches * kPolynomialSamples * kPolynomialSamples);
  }
  const int moved = 5;
  NurbsPatch& p = build.set.patches[moved];
  ASSERT_EQ(p.num_poles_u, 4);
  ASSERT_EQ(p.num_poles_v, 4);
  for (const auto& ij : {std::array<int, 2>{0, 3}, std::array<int, 2>{1, 2}, std::array<int, 2>{2, 2}}) {
    const Point3 before = p.pole(ij[0], ij[1]);
    p.pole(ij[0], ij[1])[2] += 1e-3 * size;
    const QualityReport q = measure_quality(build, limit, c.result.continuity, 9, nullptr);
    EXPECT_EQ(q.polynomial_patches, patches);
    double dense = 0;
    for (int i = 0; i <= 99; ++i)  // steps of 1/99: the nodes k/3 among them
      for (int j = 0; j <= 99; ++j) {
        const double s = i / 99.0, t = j / 99.0;
        const LimitParam lp = patch_to_limit(build, moved, s, t);
        const Point3 y = evaluate(p, s, t).p;
        const Point3 L = limit.evaluate(lp.face, lp.sub, lp.u, lp.v).p;
        dense = std::max(dense, std::sqrt((y[0] - L[0]) * (y[0] - L[0]) + (y[1] - L[1]) * (y[1] - L[1]) +
                                          (y[2] - L[2]) * (y[2] - L[2])));
      }
    p.pole(ij[0], ij[1]) = before;
    EXPECT_GT(q.parametric_max, 0.01 * 1e-3 * size);
    EXPECT_LE(q.parametric_max, dense * (1 + 1e-12));
    EXPECT_LE(dense, kPolynomialBound * q.parametric_max) << "pole " << ij[0] << ", " << ij[1];
  }
}

// The report takes the limit's normal jump across edges that are not infinitely sharp to be 0
// (docs/math.md 11.2) instead of measuring it. The theorem, measured with the exact evaluator:
// across every interior edge between two quads of cages with extraordinary vertices, semi-sharp
// creases (one sharpness and Chaikin), darts, corners and triangles next door, the limit normals
// of both sides agree at 24 interior points of the edge; across infinitely sharp edges they do
// not (the measurement can see a jump).
TEST(Quality, LimitIsTangentContinuousAcrossEveryEdgeNotInfinitelySharp) {
  double worst_smooth = 0, largest_sharp = 0;
  long smooth_edges = 0;
  for (const char* name : {"catmark_helmet", "catmark_pawn", "catmark_cube_creases1", "catmark_chaikin1",
                           "catmark_dart_edgecorner", "catmark_gregory_test6", "catmark_pyramid_creases1",
                           "catmark_cubes_infsharp", "catmark_xord_interior"}) {
    SCOPED_TRACE(name);
    const LoadedCage cage = read_obj(limit_corpus_path(name));
    const SubdivLevel base = SubdivLevel::from_input(cage.input);
    const LimitEvaluator limit(base, positions_of(cage.input));
    const PolyMesh& m = base.mesh;
    for (int e = 0; e < m.num_edges(); ++e) {
      if (m.is_boundary_edge(e)) continue;
      const int h = m.edge_corner(e), t = m.twin(h);
      const int f = m.corner_face(h), g = m.corner_face(t);
      if (m.face_size(f) != 4 || m.face_size(g) != 4 || base.face_hole[f] || base.face_hole[g]) continue;
      const bool sharp = base.edge_sharpness[e] >= static_cast<float>(kInfiniteSharpness);
      double jump = 0;
      for (int i = 0; i < 24; ++i) {
        const double x = (i + 0.5) / 24;  // along h; the twin runs the other way
        double u0, v0, u1, v1;
        side_parameters(h - m.face_begin(f), x, u0, v0);
        side_parameters(t - m.face_begin(g), 1 - x, u1, v1);
        const LimitSample a = limit.evaluate(f, 0, u0, v0), b = limit.evaluate(g, 0, u1, v1);
        ASSERT_LT(dist(a.p, b.p), 1e-12 * diagonal(limit.positions())) << "edge " << e;
        const double c = a.normal[0] * b.normal[0] + a.normal[1] * b.normal[1] + a.normal[2] * b.normal[2];
        const Point3 x_ = {a.normal[1] * b.normal[2] - a.normal[2] * b.normal[1],
                           a.normal[2] * b.normal[0] - a.normal[0] * b.normal[2],
                           a.normal[0] * b.normal[1] - a.normal[1] * b.normal[0]};
        jump = std::max(jump, std::atan2(std::sqrt(x_[0] * x_[0] + x_[1] * x_[1] + x_[2] * x_[2]), c) * 180 / M_PI);
      }
      if (sharp) {
        largest_sharp = std::max(largest_sharp, jump);
      } else {
        worst_smooth = std::max(worst_smooth, jump);
        ++smooth_edges;
        EXPECT_LT(jump, 1e-8) << "edge " << e << " (degrees)";
      }
    }
  }
  std::printf("%ld smooth edges: largest limit normal jump %.3g deg; across infinitely sharp edges up to %.3g deg\n",
              smooth_edges, worst_smooth, largest_sharp);
  EXPECT_GT(smooth_edges, 1000);
  EXPECT_GT(largest_sharp, 10.0);
}

// --- the GLB preview, read back with tinygltf ------------------------------------------------

#include <tiny_gltf.h>

#include "core/eval/preview_mesh.h"
#include "io/gltf_preview.h"

namespace {

/// The float vec3 data of an accessor.
std::vector<float> vec3s(const tinygltf::Model& m, int accessor) {
  const tinygltf::Accessor& a = m.accessors.at(static_cast<size_t>(accessor));
  EXPECT_EQ(a.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
  EXPECT_EQ(a.type, TINYGLTF_TYPE_VEC3);
  const tinygltf::BufferView& v = m.bufferViews.at(static_cast<size_t>(a.bufferView));
  const unsigned char* p = m.buffers.at(static_cast<size_t>(v.buffer)).data.data() + v.byteOffset + a.byteOffset;
  std::vector<float> out(a.count * 3);
  std::memcpy(out.data(), p, out.size() * sizeof(float));
  return out;
}

}  // namespace

TEST(Preview, GlbReadsBackWithTinygltfWithThePatchesAndTheirColours) {
  const Converted c = convert_shape("catmark_cube");
  const LimitEvaluator limit(c.base, c.pos);
  const int n = 6;
  const size_t patches = c.result.build.set.patches.size();
  for (PreviewColor mode : {PreviewColor::Deviation, PreviewColor::Curvature, PreviewColor::Zebra}) {
    const PreviewMesh mesh = build_preview(c.result.build, &limit, mode, n);
    TempDir dir;
    const std::string path = dir.file("p.glb");
    write_preview_glb(path, mesh, "cube");
    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    std::string error, warning;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, path)) << error;
    ASSERT_EQ(model.meshes.size(), 1u);
    const tinygltf::Primitive& prim = model.meshes[0].primitives.at(0);
    const std::vector<float> pos = vec3s(model, prim.attributes.at("POSITION"));
    const std::vector<float> nrm = vec3s(model, prim.attributes.at("NORMAL"));
    const std::vector<float> col = vec3s(model, prim.attributes.at("COLOR_0"));
    ASSERT_EQ(pos.size(), 3 * patches * n * n);
    ASSERT_EQ(nrm.size(), pos.size());
    ASSERT_EQ(col.size(), pos.size());
    EXPECT_EQ(model.accessors.at(static_cast<size_t>(prim.indices)).count, patches * (n - 1) * (n - 1) * 6);
    // Vertex (patch p, i, j) is the patch at (i, j) / (n - 1).
    for (size_t p = 0; p < patches; ++p) {
      const size_t v = (p * n + 2) * n + 3;
      const Point3 x = evaluate(c.result.build.set.patches[p], 2.0 / (n - 1), 3.0 / (n - 1)).p;
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(pos[3 * v + k], x[k], 1e-6);
    }
    for (float x : col) {
      EXPECT_GE(x, 0.0f);
      EXPECT_LE(x, 1.0f);
    }
    if (mode == PreviewColor::Curvature) {
      // The limit of a cube is convex: H < 0 everywhere, so every colour is on the blue side.
      for (size_t v = 0; v < col.size() / 3; ++v) EXPECT_EQ(col[3 * v + 2], 1.0f);
      EXPECT_LT(mesh.value_min, 0);
    }
    if (mode == PreviewColor::Zebra) {
      for (float x : col) EXPECT_TRUE(x == 0.0f || x == 1.0f);
    }
    if (mode == PreviewColor::Deviation) {
      // The largest value is the largest limit distance over the same grid.
      double grid_max = 0;
      for (size_t p = 0; p < patches; ++p)
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j)
            grid_max = std::max(grid_max, limit_distance(c.result.build, limit, static_cast<int>(p),
                                                         i / (n - 1.0), j / (n - 1.0)));
      EXPECT_GT(grid_max, 0);
      EXPECT_NEAR(mesh.value_max, grid_max, 1e-6 * grid_max);  // stored as float
    }
  }
}

// The quality and preview stages (issue #15): their results are data in the ConversionResult,
// the same as measuring and tessellating on their own, and the report carries the quality
// section exactly when the stage ran.
TEST(QualityStage, IsTheStandaloneMeasureAndItsSectionIsInTheReport) {
  Converted c = convert_shape("catmark_cube_creases0");
  EXPECT_FALSE(c.result.quality);
  EXPECT_FALSE(c.result.preview);
  const std::string plain = pipeline::report_json(c.result);
  EXPECT_EQ(plain.find("\"quality"), std::string::npos);
  EXPECT_EQ(plain.substr(plain.size() - 4), "}\n}\n");  // timings_ms, then the end

  pipeline::ConversionSettings settings;
  settings.level = 0;
  settings.quality_samples = 5;
  settings.preview = pipeline::PreviewSettings{PreviewColor::Zebra, 4};
  std::vector<std::string> stages;
  pipeline::ConversionProgress progress;
  progress.stage = [&](pipeline::Stage s, const std::string&) { stages.push_back(pipeline::to_string(s)); };
  // The quality stage starts once the patches are final, before packing, and runs beside
  // packing, the measures, the B-rep and after_brep (called once, after the B-rep, before the
  // result has its quality); the preview comes last.
  int after_brep_calls = 0;
  progress.after_brep = [&](pipeline::ConversionResult& result) {
    ++after_brep_calls;
    EXPECT_TRUE(result.has_brep);
    EXPECT_FALSE(result.quality);
    stages.push_back("after_brep");
  };
  pipeline::ConversionResult r = pipeline::convert(c.base, c.pos, settings, progress);
  ASSERT_TRUE(r.quality && r.preview);
  EXPECT_EQ(after_brep_calls, 1);
  const auto index = [&](const std::string& name) { return std::find(stages.begin(), stages.end(), name) - stages.begin(); };
  ASSERT_GE(stages.size(), 4u);
  EXPECT_LT(index("quality"), index("packing"));
  EXPECT_LT(index("packing"), index("brep"));
  const std::vector<std::string> last(stages.end() - 3, stages.end());
  EXPECT_EQ(last, (std::vector<std::string>{"brep", "after_brep", "preview"}));
  EXPECT_GE(r.ms.quality_wait, 0);

  const LimitEvaluator limit(c.base, c.pos);
  const QualityReport q = measure_quality(r.build, limit, r.continuity, 5, &r.exported);
  EXPECT_EQ(r.quality->samples_per_side, 5);
  EXPECT_EQ(r.quality->deviation_max, q.deviation_max);
  EXPECT_EQ(r.quality->patch_max, q.patch_max);
  EXPECT_EQ(r.quality->edges.size(), q.edges.size());
  const PreviewMesh mesh = build_preview(r.build, nullptr, PreviewColor::Zebra, 4);
  EXPECT_EQ(r.preview->positions, mesh.positions);
  EXPECT_EQ(r.preview->colors, mesh.colors);
  EXPECT_EQ(r.preview->indices, mesh.indices);

  const std::string report = pipeline::report_json(r);
  const size_t at = report.find("\n  \"quality\": {\n    \"samples_per_side\": 5,");
  ASSERT_NE(at, std::string::npos);
  EXPECT_LT(report.find("\"timings_ms\""), at);  // after the conversion's timings
  EXPECT_NE(report.find("\n  \"quality_ms\": ", at), std::string::npos);
  const std::string check = pipeline::quality_report_json(r);
  EXPECT_EQ(check.rfind("{\n  \"format\": \"subd2nurbs-quality\",", 0), 0u);
  // The same section in both documents: the one writer, the one function.
  const std::string key = "\n  \"quality\": ";
  const size_t in_check = check.find(key);
  ASSERT_NE(in_check, std::string::npos);
  const size_t from = at + key.size(), to = report.find(",\n  \"quality_ms\"", at);
  EXPECT_EQ(check.substr(in_check + key.size(), check.size() - 3 - in_check - key.size()),
            report.substr(from, to - from));
}

// The quality stage runs on a thread of its own from before packing to after the B-rep: an
// exception on the conversion's thread at any point of that (here from the progress callback
// or from after_brep) comes out of convert, with the stage's thread stopped, never a hang.
// With threads = 1 the stage runs on the conversion's thread when its result is asked for; the
// same exceptions end the conversion the same way.
TEST(QualityStage, ExceptionsBesideItEndTheConversion) {
  Converted c = convert_shape("catmark_cube_creases0");
  for (const std::optional<int> threads : {std::optional<int>{}, std::optional<int>{1}})
  for (const char* where : {"packing", "continuity", "brep", "after_brep"}) {
    SCOPED_TRACE(threads ? "threads 1" : "threads: default");
    pipeline::ConversionSettings settings;
    settings.level = 0;
    settings.quality_samples = 5;
    settings.limits.threads = threads;
    pipeline::ConversionProgress progress;
    progress.stage = [&](pipeline::Stage s, const std::string&) {
      if (pipeline::to_string(s) == std::string(where)) throw std::runtime_error(where);
    };
    progress.after_brep = [&](pipeline::ConversionResult&) {
      if (std::string(where) == "after_brep") throw std::runtime_error(where);
    };
    try {
      pipeline::convert(c.base, c.pos, settings, progress);
      ADD_FAILURE() << "no exception from " << where;
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), where);
    }
  }
}

// The `threads` setting (#30, #32): one thread gives the same conversion as all of them, to the
// bit: the same faces and poles, the same continuity and quality measures (the stage then runs
// on the conversion's thread, after the B-rep), on a cage with extraordinary vertices, creases
// and a tolerance that chooses the levels.
TEST(QualityStage, OneThreadGivesTheSameConversionToTheBit) {
  Converted c = convert_shape("catmark_cube_creases1");
  std::string patches[2], quality[2];
  for (int run = 0; run < 2; ++run) {
    pipeline::ConversionSettings settings;
    settings.tolerance = 1e-4;
    settings.quality_samples = 6;
    if (run == 1) settings.limits.threads = 1;
    const pipeline::ConversionResult r = pipeline::convert(c.base, c.pos, settings);
    ASSERT_TRUE(r.quality);
    EXPECT_TRUE(r.has_brep);
    patches[run] = patch_set_to_json(r.exported.set);
    const std::string json = pipeline::quality_report_json(r);
    const size_t at = json.find("\n  \"quality\": ");  // the measures, after the stage's times
    ASSERT_NE(at, std::string::npos);
    quality[run] = json.substr(at);
  }
  EXPECT_GT(patches[0].size(), 1000u);
  EXPECT_TRUE(patches[0] == patches[1]) << "the exported patches differ with one thread";
  EXPECT_EQ(quality[0], quality[1]);
}

TEST(QualityStage, ThreadsFollowTheirRule) {
  for (int threads : {0, -1, pipeline::kMaxThreads + 1}) {
    pipeline::ConversionSettings settings;
    settings.limits.threads = threads;
    try {
      pipeline::validate(settings);
      ADD_FAILURE() << threads << " threads were accepted";
    } catch (const pipeline::SettingsError& e) {
      EXPECT_EQ(e.setting(), "threads");
      EXPECT_EQ(e.rule(), "must be 1 .. 1024");
    }
  }
  pipeline::ConversionSettings settings;
  settings.limits.threads = pipeline::kMaxThreads;
  EXPECT_NO_THROW(pipeline::validate(settings));
}

TEST(QualityStage, SamplesFollowTheirRules) {
  pipeline::ConversionSettings settings;
  settings.quality_samples = 1;
  try {
    pipeline::validate(settings);
    FAIL() << "1 sample per side was accepted";
  } catch (const pipeline::SettingsError& e) {
    EXPECT_EQ(e.setting(), "samples");
    EXPECT_EQ(e.rule(), "must be 2 .. 64");
  }
  settings.quality_samples.reset();
  settings.preview = pipeline::PreviewSettings{PreviewColor::Curvature, 65};
  try {
    pipeline::validate(settings);
    FAIL() << "65 preview samples per side were accepted";
  } catch (const pipeline::SettingsError& e) {
    EXPECT_EQ(e.setting(), "preview_samples");
  }
}
