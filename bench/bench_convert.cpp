// The conversion pipeline stage by stage, on two generated 10 000-quad cages, with a reference
// for each stage measured in the same run (scripts/bench.sh turns the output into tables 2-4
// of docs/benchmarks.md):
//
//   patches   cage arrays -> PatchSet: SubdivLevel::from_input + build_patches (default level)
//             ours_refine: its refinement part alone (from_input + refine_uniform to the same
//             level + positions of every level), to show how much of it is refinement
//             reference: OpenSubdiv 3.5 building its own patches for the same cage
//               osd_adaptive  TopologyRefinerFactory::Create + RefineAdaptive(isolation 2)
//                             + PatchTableFactory::Create (Gregory-basis end caps, double)
//                             + PrimvarRefiner positions of every level + local points
//               osd_uniform   TopologyRefinerFactory::Create + RefineUniform(2)
//                             + PatchTableFactory::Create (uniform: the level-2 quads)
//                             + PrimvarRefiner positions of levels 1 and 2
//   brep      PatchSet -> B-rep: occt::build_brep (which ends with BRepCheck_Analyzer); then,
//             untimed, BRepCheck_Analyzer(shape, GeomControls) + IsValid() alone on the result
//             (counters check_ms, check_cpu_ms: a paired measurement per repetition); freeing
//             the result is not timed
//   step      our occt::write_shape(..., Format::Step) versus OCCT's own STEPControl_Writer
//             (Transfer + Write, default Interface_Static settings, no lock, no messenger
//             silencing, no temporary file, fsync or rename), same shape, files in /tmp, back
//             to back in alternating order; counters ours_ms, occt_ms (wall), *_cpu_ms (thread
//             CPU), fsync_ms (an untimed fsync of the plain writer's file, what write_shape's
//             fsync costs)
//
// Cages (both closed tori, major radius 3, minor radius 1, 100 x 100 quads = 10 000 quads):
//   torus     regular: every vertex has valence 4
//   torus_ev  the same torus with 36 edge rotations spread over a 6 x 6 grid of sites. A
//             rotation replaces two adjacent quads (a b c d), (b e f c) by (d a b e), (e f c d):
//             b and c drop to valence 3, d and e rise to valence 5. Result: 72 valence-3 and
//             72 valence-5 vertices, still 10 000 quads.
//
// Stages that take seconds run one iteration per repetition (otherwise Google Benchmark times a
// first, discarded iteration before each repetition). Run with --benchmark_out=FILE (JSON):
// OCCT's plain STEP writer prints its transfer statistics on stdout, so stdout is not JSON.
#include <benchmark/benchmark.h>

#include <BRepCheck_Analyzer.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <STEPControl_Writer.hxx>
#include <TopoDS_Shape.hxx>

#include <fcntl.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <opensubdiv/far/patchTable.h>
#include <opensubdiv/far/patchTableFactory.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/stencilTable.h>
#include <opensubdiv/far/topologyDescriptor.h>

#include "common/shapes.h"
#include "converter/occt/brep_builder.h"
#include "converter/occt/writers.h"
#include "core/mesh/validate.h"
#include "core/patch/patch_builder.h"
#include "osd_bench.h"

using namespace subd2nurbs;
namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

namespace {

constexpr int kIsolation = 2;  // = our default level k for an all-quad cage (a = 0, k = a + 2)

// --- cages -----------------------------------------------------------------------------------

struct Cage {
  std::string name;
  MeshInput input;
  int valence3 = 0, valence5 = 0, other_ev = 0;
};

Cage make_cage(const std::string& name) {
  Cage cage;
  cage.name = name;
  if (name == "torus_ev") cage.input = testing::torus_with_rotated_edges();
  else if (name == "torus") cage.input = testing::torus(100, 100);
  else throw std::invalid_argument("unknown cage " + name);
  validate_and_build(cage.input);  // throws if a rotation broke the cage
  // Valences (every edge of a closed manifold quad mesh is seen twice, once per face).
  std::vector<int> twice(cage.input.positions.size(), 0);
  for (size_t f = 0; f < cage.input.face_sizes.size(); ++f)
    for (int k = 0; k < 4; ++k) {
      twice[cage.input.face_indices[4 * f + k]]++;
      twice[cage.input.face_indices[4 * f + (k + 1) % 4]]++;
    }
  for (int t : twice) {
    const int valence = t / 2;
    if (valence == 3) ++cage.valence3;
    else if (valence == 5) ++cage.valence5;
    else if (valence != 4) ++cage.other_ev;
  }
  return cage;
}

/// Everything a stage needs as input, built once per cage on first use (outside timing).
struct Prepared {
  Cage cage;
  PatchBuild build;         ///< from_input + build_patches
  occt::BrepResult brep;    ///< build_brep(build.set)
};

Prepared& prepared(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Prepared>> cache;
  std::unique_ptr<Prepared>& p = cache[name];
  if (!p) {
    p = std::make_unique<Prepared>();
    p->cage = make_cage(name);
    p->build = build_patches(SubdivLevel::from_input(p->cage.input), p->cage.input.positions);
    p->brep = occt::build_brep(p->build.set);
  }
  return *p;
}

void cage_counters(benchmark::State& state, const Cage& cage) {
  state.counters["faces"] = cage.input.num_faces();
  state.counters["ev3"] = cage.valence3;
  state.counters["ev5"] = cage.valence5;
}

// --- OpenSubdiv ------------------------------------------------------------------------------

using bench::Vertex3;
using bench::osd_refiner;


/// Positions of every level of `refiner` in one array (the numbering patch tables use), with
/// `extra` more slots at the end.
std::vector<Vertex3> osd_positions(const Far::TopologyRefiner& refiner, const MeshInput& in,
                                   int extra) {
  std::vector<Vertex3> pts(static_cast<size_t>(refiner.GetNumVerticesTotal()) + extra);
  for (int v = 0; v < in.num_vertices(); ++v)
    for (int k = 0; k < 3; ++k) pts[v].p[k] = in.positions[v][k];
  Far::PrimvarRefinerReal<double> primvar(refiner);
  Vertex3* src = pts.data();
  for (int level = 1; level < refiner.GetNumLevels(); ++level) {
    Vertex3* dst = src + refiner.GetLevel(level - 1).GetNumVertices();
    primvar.Interpolate(level, src, dst);
    src = dst;
  }
  return pts;
}

// --- benchmarks ------------------------------------------------------------------------------

void BM_PatchesOurs(benchmark::State& state, const std::string& name) {
  const Prepared& p = prepared(name);
  const MeshInput& in = p.cage.input;
  size_t patches = 0;
  for (auto _ : state) {
    PatchBuild b = build_patches(SubdivLevel::from_input(in), in.positions);
    patches = b.set.patches.size();
    benchmark::DoNotOptimize(b.set.patches.data());
  }
  cage_counters(state, p.cage);
  state.counters["patches"] = static_cast<double>(patches);
  state.counters["level"] = p.build.info.level;
  state.counters["regular_patches"] = p.build.info.regular_patches;
  state.counters["fan_patches"] = p.build.info.pccm_patches;
  state.counters["poles"] = static_cast<double>(p.build.info.total_poles);
}

/// The set-up part of BM_PatchesOurs alone: from_input (validation, connectivity and tags of
/// the cage, the only level that is built whole when the cage is all quads).
void BM_PatchesOursRefine(benchmark::State& state, const std::string& name) {
  const Prepared& p = prepared(name);
  const MeshInput& in = p.cage.input;
  for (auto _ : state) {
    SubdivLevel level = SubdivLevel::from_input(in);
    benchmark::DoNotOptimize(level.edge_sharpness.data());
  }
  cage_counters(state, p.cage);
}

void BM_PatchesOsdAdaptive(benchmark::State& state, const std::string& name) {
  const Prepared& p = prepared(name);
  const MeshInput& in = p.cage.input;
  Far::PatchTableFactory::Options popt(kIsolation);
  // As the test oracle (tests/oracle/osd_limit_eval.cpp): exact REGULAR patches, Gregory-basis
  // end caps in double precision.
  popt.useInfSharpPatch = true;
  popt.generateLegacySharpCornerPatches = false;
  popt.SetEndCapType(Far::PatchTableFactory::Options::ENDCAP_GREGORY_BASIS);
  popt.SetPatchPrecision<double>();
  int patches = 0;
  for (auto _ : state) {
    std::unique_ptr<Far::TopologyRefiner> refiner = osd_refiner(in);
    refiner->RefineAdaptive(popt.GetRefineAdaptiveOptions());
    std::unique_ptr<Far::PatchTable> table(Far::PatchTableFactory::Create(*refiner, popt));
    const int num_refined = refiner->GetNumVerticesTotal();
    std::vector<Vertex3> pts = osd_positions(*refiner, in, table->GetNumLocalPoints());
    if (table->GetNumLocalPoints() > 0)
      table->GetLocalPointStencilTable<double>()->UpdateValues(pts.data(), pts.data() + num_refined);
    patches = table->GetNumPatchesTotal();
    benchmark::DoNotOptimize(pts.data());
  }
  cage_counters(state, p.cage);
  state.counters["patches"] = patches;
}

void BM_PatchesOsdUniform(benchmark::State& state, const std::string& name) {
  const Prepared& p = prepared(name);
  const MeshInput& in = p.cage.input;
  int patches = 0;
  for (auto _ : state) {
    std::unique_ptr<Far::TopologyRefiner> refiner = osd_refiner(in);
    Far::TopologyRefiner::UniformOptions uopt(kIsolation);
    uopt.fullTopologyInLastLevel = true;
    refiner->RefineUniform(uopt);
    Far::PatchTableFactory::Options popt;  // uniform: the last level's quads
    std::unique_ptr<Far::PatchTable> table(Far::PatchTableFactory::Create(*refiner, popt));
    std::vector<Vertex3> pts = osd_positions(*refiner, in, 0);
    patches = table->GetNumPatchesTotal();
    benchmark::DoNotOptimize(pts.data());
  }
  cage_counters(state, p.cage);
  state.counters["patches"] = patches;
}

double thread_cpu_ms() {
  timespec t;
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

/// Wall-clock and thread CPU time of f(), in ms.
template <class F>
std::pair<double, double> stopwatch(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = thread_cpu_ms();
  f();
  const double cpu = thread_cpu_ms() - c0;
  return {std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count(),
          cpu};
}

/// Timed: build_brep. Untimed, on the same result right after it: BRepCheck_Analyzer alone
/// (construction, IsValid, destruction, as inside build_brep), reported in counters check_ms
/// and check_cpu_ms so that each repetition gives a paired (total, check) measurement; then
/// freeing the result, which is not build_brep's work.
void BM_Brep(benchmark::State& state, const std::string& name) {
  const Prepared& p = prepared(name);
  bool valid = false, check_valid = false;
  int faces = 0;
  std::pair<double, double> check{0, 0};
  for (auto _ : state) {
    occt::BrepResult r = occt::build_brep(p.build.set);
    valid = r.valid;
    faces = r.num_faces;
    benchmark::DoNotOptimize(r.shape.TShape().get());
    state.PauseTiming();
    check = stopwatch([&] {
      BRepCheck_Analyzer analyzer(r.shape, /*GeomControls=*/Standard_True);
      check_valid = analyzer.IsValid();
    });
    r = occt::BrepResult();
    state.ResumeTiming();
  }
  if (!valid || !check_valid) state.SkipWithError("BRepCheck found defects");
  cage_counters(state, p.cage);
  state.counters["brep_faces"] = faces;
  state.counters["check_ms"] = check.first;
  state.counters["check_cpu_ms"] = check.second;
}

std::string step_path(const std::string& who, const std::string& name) {
  return "/tmp/subd2nurbs_bench_" + std::to_string(::getpid()) + "_" + who + "_" + name + ".step";
}

double file_size(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 ? static_cast<double>(st.st_size) : 0.0;
}

/// One STEP write of each kind, back to back (so that both see the same machine load), in
/// alternating order from one repetition to the next; each timed on its own into counters
/// (ours_ms, occt_ms, *_cpu_ms). Google Benchmark's own time for this benchmark is their sum.
/// After the plain write, untimed: an fsync of its file (fsync_ms), as write_shape does with
/// its temporary file before the rename.
void BM_StepPair(benchmark::State& state, const std::string& name) {
  static std::map<std::string, int> calls;
  const Prepared& p = prepared(name);
  const std::string ours_path = step_path("ours", name), occt_path = step_path("occt", name);
  std::pair<double, double> ours{0, 0}, occt{0, 0}, fsync{0, 0};
  const bool ours_first = calls[name]++ % 2 == 0;
  for (auto _ : state) {
    auto write_ours = [&] {
      ours = stopwatch([&] { occt::write_shape(p.brep.shape, ours_path, occt::Format::Step); });
    };
    auto write_occt = [&] {
      bool ok = true;
      occt = stopwatch([&] {
        STEPControl_Writer writer;
        ok = writer.Transfer(p.brep.shape, STEPControl_AsIs) == IFSelect_RetDone &&
             writer.Write(occt_path.c_str()) == IFSelect_RetDone;
      });
      if (!ok) state.SkipWithError("STEPControl_Writer failed");
      fsync = stopwatch([&] {
        const int fd = ::open(occt_path.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd >= 0) {
          ::fsync(fd);
          ::close(fd);
        }
      });
    };
    if (ours_first) {
      write_ours();
      write_occt();
    } else {
      write_occt();
      write_ours();
    }
  }
  cage_counters(state, p.cage);
  state.counters["ours_first"] = ours_first;
  state.counters["ours_ms"] = ours.first;
  state.counters["ours_cpu_ms"] = ours.second;
  state.counters["occt_ms"] = occt.first;
  state.counters["occt_cpu_ms"] = occt.second;
  state.counters["fsync_ms"] = fsync.first;
  state.counters["ours_bytes"] = file_size(ours_path);
  state.counters["occt_bytes"] = file_size(occt_path);
  std::remove(ours_path.c_str());
  std::remove(occt_path.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  for (const std::string cage : {"torus", "torus_ev"}) {
    benchmark::RegisterBenchmark(("patches/ours/" + cage).c_str(), BM_PatchesOurs, cage)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("patches/ours_refine/" + cage).c_str(), BM_PatchesOursRefine,
                                 cage)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("patches/osd_adaptive/" + cage).c_str(), BM_PatchesOsdAdaptive,
                                 cage)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("patches/osd_uniform/" + cage).c_str(), BM_PatchesOsdUniform,
                                 cage)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("brep/build_brep/" + cage).c_str(), BM_Brep, cage)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(1);
    benchmark::RegisterBenchmark(("step/pair/" + cage).c_str(), BM_StepPair, cage)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(1);
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
