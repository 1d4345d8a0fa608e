// libFuzzer target: the query-line parser of `subd2nurbs limit` (converter/cli/limit_queries.h)
// against a fixed cage with quads and pentagons (sub-faces), plus the exact limit
// evaluation of the first 16 accepted queries (every query is parsed and checked; evaluating
// hundreds per input, each a descent of up to 40 local refinements near a corner, held the
// fuzzer at a few hundred inputs per second). InputError is an accepted outcome.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "converter/cli/limit_queries.h"
#include "core/limit/limit_evaluator.h"
#include "core/refine/refiner.h"
#include "io/input_error.h"

namespace {

struct Fixture {
  subd2nurbs::SubdivLevel level;
  std::vector<subd2nurbs::Point3> positions;
  Fixture() {
    // A cube with an extra vertex on one edge: two pentagons (sub-faces) next to quads.
    subd2nurbs::MeshInput in;
    in.positions = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}, {-1, -1, 1},
                    {1, -1, 1},   {1, 1, 1},   {-1, 1, 1}, {0, -1, 1}};
    in.face_sizes = {4, 5, 4, 4, 5, 4};
    in.face_indices = {0, 3, 2, 1, /**/ 0, 1, 5, 8, 4, /**/ 1, 2, 6, 5, /**/ 2, 3, 7, 6, /**/ 4, 8, 5, 6, 7,
                       /**/ 3, 0, 4, 7};
    level = subd2nurbs::SubdivLevel::from_input(in);
    positions.assign(in.positions.begin(), in.positions.end());
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Fixture fixture;
  static const subd2nurbs::LimitEvaluator evaluator(fixture.level, fixture.positions);
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const std::vector<subd2nurbs::cli::Query> queries = subd2nurbs::cli::read_queries(in, "fuzz", fixture.level.mesh);
    for (size_t i = 0; i < queries.size() && i < 16; ++i)
      evaluator.evaluate(queries[i].face, queries[i].sub, queries[i].u, queries[i].v);
  } catch (const subd2nurbs::InputError&) {
  }
  return 0;
}
