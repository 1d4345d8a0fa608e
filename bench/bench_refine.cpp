// Uniform Catmull-Clark refinement of a generated 100k-quad torus, ours against OpenSubdiv's
// TopologyRefiner + PrimvarRefiner, in the same run. Both start from plain arrays and end with
// the positions of every level. scripts/bench.sh turns the output into docs/benchmarks.md.
#include <benchmark/benchmark.h>

#include <memory>

#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>

#include "common/shapes.h"
#include "core/refine/refiner.h"
#include "osd_bench.h"

using namespace subd2nurbs;
namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

namespace {

const MeshInput& torus_100k() {
  static const MeshInput m = testing::torus(400, 250);  // 100 000 quads
  return m;
}

using bench::Vertex3;

void BM_Ours(benchmark::State& state) {
  const int levels = static_cast<int>(state.range(0));
  const MeshInput& in = torus_100k();
  const std::vector<Point3> base(in.positions.begin(), in.positions.end());
  for (auto _ : state) {
    SubdivLevel level = SubdivLevel::from_input(in);
    Refinement r = refine_uniform(level, levels);
    auto pos = r.positions(base);
    benchmark::DoNotOptimize(pos.back().data());
  }
  state.counters["faces"] = static_cast<double>(in.num_faces());
}

void BM_OpenSubdiv(benchmark::State& state) {
  const int levels = static_cast<int>(state.range(0));
  const MeshInput& in = torus_100k();
  for (auto _ : state) {
    std::unique_ptr<Far::TopologyRefiner> refiner = bench::osd_refiner(in);
    refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(levels));
    std::vector<std::vector<Vertex3>> buf(levels + 1);
    buf[0].resize(in.num_vertices());
    for (int v = 0; v < in.num_vertices(); ++v)
      for (int k = 0; k < 3; ++k) buf[0][v].p[k] = in.positions[v][k];
    Far::PrimvarRefinerReal<double> primvar(*refiner);
    for (int l = 1; l <= levels; ++l) {
      buf[l].resize(refiner->GetLevel(l).GetNumVertices());
      primvar.Interpolate(l, buf[l - 1], buf[l]);
    }
    benchmark::DoNotOptimize(buf.back().data());
  }
  state.counters["faces"] = static_cast<double>(in.num_faces());
}

}  // namespace

BENCHMARK(BM_Ours)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OpenSubdiv)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
