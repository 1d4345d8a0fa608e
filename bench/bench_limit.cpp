// Limit surface evaluation throughput: ours (core/limit LimitEvaluator) against OpenSubdiv's
// Far::PatchTable + Far::PatchMap, in the same run, on 100 000 random (ptex face, u, v) queries
// over two closed 10 000-quad cages (a regular torus, and the same torus with 72 valence-3 and
// 72 valence-5 vertices made by edge rotations). Both sides return position, du and dv per
// query; set-up (our per-face preparation, OpenSubdiv's adaptive refinement and patch table) is
// timed separately. scripts/bench.sh turns the output into docs/benchmarks.md.
#include <benchmark/benchmark.h>

#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <opensubdiv/far/patchMap.h>
#include <opensubdiv/far/patchTable.h>
#include <opensubdiv/far/patchTableFactory.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/stencilTable.h>

#include "common/shapes.h"
#include "core/limit/limit_evaluator.h"
#include "osd_bench.h"

using namespace subd2nurbs;
namespace Far = OpenSubdiv::Far;

namespace {

constexpr int kQueries = 100000;
constexpr int kIsolation = 10;  // OpenSubdiv's deepest, as in the test oracle

const MeshInput& cage(int which) {
  static const MeshInput regular = testing::torus(100, 100);
  static const MeshInput ev = testing::torus_with_rotated_edges();
  return which == 0 ? regular : ev;
}

struct Query {
  int face;
  double u, v;
};

const std::vector<Query>& queries() {
  static const std::vector<Query> q = [] {
    std::mt19937 rng(12345);
    std::uniform_int_distribution<int> face(0, 9999);
    std::uniform_real_distribution<double> t(0.0, 1.0);
    std::vector<Query> out(kQueries);
    for (Query& x : out) x = {face(rng), t(rng), t(rng)};
    return out;
  }();
  return q;
}

std::vector<Point3> positions(const MeshInput& in) {
  return std::vector<Point3>(in.positions.begin(), in.positions.end());
}

// --- OpenSubdiv: adaptive patch table with Gregory end caps, as tests/oracle/osd_limit_eval ---

struct OsdEval {
  std::unique_ptr<Far::PatchTable> table;
  std::unique_ptr<Far::PatchMap> map;
  std::vector<bench::Vertex3> points;
};

std::unique_ptr<OsdEval> osd_build(const MeshInput& in) {
  auto e = std::make_unique<OsdEval>();
  std::unique_ptr<Far::TopologyRefiner> refiner = bench::osd_refiner(in);
  Far::PatchTableFactory::Options popt(kIsolation);
  popt.useInfSharpPatch = true;
  popt.generateLegacySharpCornerPatches = false;
  popt.SetEndCapType(Far::PatchTableFactory::Options::ENDCAP_GREGORY_BASIS);
  popt.SetPatchPrecision<double>();
  refiner->RefineAdaptive(popt.GetRefineAdaptiveOptions());
  e->table.reset(Far::PatchTableFactory::Create(*refiner, popt));
  const int num_refined = refiner->GetNumVerticesTotal();
  const int num_local = e->table->GetNumLocalPoints();
  e->points.resize(static_cast<size_t>(num_refined) + num_local);
  for (int v = 0; v < in.num_vertices(); ++v)
    for (int k = 0; k < 3; ++k) e->points[v].p[k] = in.positions[v][k];
  Far::PrimvarRefinerReal<double> primvar(*refiner);
  bench::Vertex3* src = e->points.data();
  for (int level = 1; level < refiner->GetNumLevels(); ++level) {
    bench::Vertex3* dst = src + refiner->GetLevel(level - 1).GetNumVertices();
    primvar.Interpolate(level, src, dst);
    src = dst;
  }
  if (num_local > 0)
    e->table->GetLocalPointStencilTable<double>()->UpdateValues(e->points.data(),
                                                                 e->points.data() + num_refined);
  e->map = std::make_unique<Far::PatchMap>(*e->table);
  return e;
}

// --- benchmarks --------------------------------------------------------------------------------

void BM_LimitOurs(benchmark::State& state) {
  const MeshInput& in = cage(static_cast<int>(state.range(0)));
  const LimitEvaluator ev(SubdivLevel::from_input(in), positions(in));
  const std::vector<Query>& qs = queries();
  for (auto _ : state) {
    double sum = 0;
    for (const Query& q : qs) {
      const LimitPoint s = ev.evaluate_point(q.face, 0, q.u, q.v);
      sum += s.p[0] + s.du[1] + s.dv[2];
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(qs.size()));
}

void BM_LimitOsd(benchmark::State& state) {
  const MeshInput& in = cage(static_cast<int>(state.range(0)));
  const std::unique_ptr<OsdEval> e = osd_build(in);
  const std::vector<Query>& qs = queries();
  for (auto _ : state) {
    double sum = 0;
    for (const Query& q : qs) {
      const Far::PatchTable::PatchHandle* h = e->map->FindPatch(q.face, q.u, q.v);
      double wp[20], wu[20], wv[20];
      e->table->EvaluateBasis(*h, q.u, q.v, wp, wu, wv);
      Far::ConstIndexArray cvs = e->table->GetPatchVertices(*h);
      double p[3] = {0, 0, 0}, du[3] = {0, 0, 0}, dv[3] = {0, 0, 0};
      for (int i = 0; i < cvs.size(); ++i) {
        const double* c = e->points[cvs[i]].p;
        for (int k = 0; k < 3; ++k) {
          p[k] += wp[i] * c[k];
          du[k] += wu[i] * c[k];
          dv[k] += wv[i] * c[k];
        }
      }
      sum += p[0] + du[1] + dv[2];
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(qs.size()));
}

void BM_LimitSetupOurs(benchmark::State& state) {
  const MeshInput& in = cage(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    LimitEvaluator ev(SubdivLevel::from_input(in), positions(in));
    benchmark::DoNotOptimize(&ev);
  }
}

void BM_LimitSetupOsd(benchmark::State& state) {
  const MeshInput& in = cage(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    std::unique_ptr<OsdEval> e = osd_build(in);
    benchmark::DoNotOptimize(e.get());
  }
}

}  // namespace

// Arg 0: regular torus, 1: torus with EVs.
BENCHMARK(BM_LimitOurs)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LimitOsd)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LimitSetupOurs)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LimitSetupOsd)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
