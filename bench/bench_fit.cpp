// The interpolation solve on its own, in a fresh process (scripts/bench_fit.py runs it next to
// `subd2nurbs convert` with and without --fit interpolate): reads a cage, times limit_rows +
// interpolate, and prints one JSON line with the wall time and the peak resident memory before
// and after the fit (VmHWM of /proc/self/status, kB: the high-water mark of this process's own
// address space; getrusage's ru_maxrss would include the parent's size at fork), so the fit's own
// peak is visible.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>

#include "core/eval/target_distance.h"
#include "core/fit/interpolate.h"
#include "core/fit/shape_fit.h"
#include "io/obj_reader.h"

using namespace subd2nurbs;

static long peak_kb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

// With a second file: fit_to_shape of the cage (its own positions as the start) to that mesh,
// fan-triangulated, with default options; one JSON line with the fit's wall time, iterations,
// stop reason, peak memory and the independent two-sided distance (relative to the target's
// diagonal).
static int shape_fit(const LoadedCage& cage, const std::string& target_path) {
  const LoadedCage mesh = read_obj(target_path);
  std::vector<std::array<int, 3>> triangles;
  for (size_t f = 0, at = 0; f < mesh.input.face_sizes.size(); at += mesh.input.face_sizes[f++])
    for (int k = 1; k + 1 < mesh.input.face_sizes[f]; ++k)
      triangles.push_back({mesh.input.face_indices[at], mesh.input.face_indices[at + k], mesh.input.face_indices[at + k + 1]});
  const SubdivLevel level = SubdivLevel::from_input(cage.input);
  const std::vector<Point3> start(cage.input.positions.begin(), cage.input.positions.end());
  const long before = peak_kb();
  const auto t0 = std::chrono::steady_clock::now();
  const ShapeTarget target(std::vector<Point3>(mesh.input.positions.begin(), mesh.input.positions.end()), triangles);
  const ShapeFitResult r = fit_to_shape(level, start, target);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const long after = peak_kb();
  const TargetDistance d = measure_target_distance(LimitEvaluator(level, r.positions), target);
  std::printf("{\"vertices\": %d, \"target_triangles\": %zu, \"samples\": %d, \"fit_ms\": %.1f, \"iterations\": %d, "
              "\"stop\": \"%s\", \"peak_kb_before\": %ld, \"peak_kb_after\": %ld, \"surface_rms\": %.3e, "
              "\"target_rms\": %.3e, \"limit_to_target\": [%.3e, %.3e, %.3e], \"target_to_limit\": [%.3e, %.3e, %.3e]}\n",
              level.mesh.num_vertices(), triangles.size(), r.samples, ms, r.iterations, to_string(r.stop), before,
              after, r.surface_rms, r.target_rms, d.limit_to_target.max, d.limit_to_target.rms,
              d.limit_to_target.p95, d.target_to_limit.max, d.target_to_limit.rms, d.target_to_limit.p95);
  return 0;
}

int main(int argc, char** argv) {
  if (argc != 2 && argc != 3) {
    std::fprintf(stderr, "usage: bench_fit CAGE.obj [TARGET.obj]\n");
    return 1;
  }
  const LoadedCage cage = read_obj(argv[1]);
  if (argc == 3) return shape_fit(cage, argv[2]);
  const SubdivLevel level = SubdivLevel::from_input(cage.input);
  const std::vector<Point3> targets(cage.input.positions.begin(), cage.input.positions.end());
  const long before = peak_kb();
  const auto t0 = std::chrono::steady_clock::now();
  const InterpolationResult r = interpolate(level, targets);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf("{\"vertices\": %d, \"faces\": %d, \"fit_ms\": %.3f, \"peak_kb_before\": %ld, \"peak_kb_after\": %ld, "
              "\"residual_max\": %.3e, \"condition\": %.4g}\n",
              level.mesh.num_vertices(), level.mesh.num_faces(), ms, before, peak_kb(), r.residual.max, r.condition);
  return 0;
}
