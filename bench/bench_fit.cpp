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

#include "core/fit/interpolate.h"
#include "io/obj_reader.h"

using namespace subd2nurbs;

static long peak_kb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: bench_fit CAGE.obj\n");
    return 1;
  }
  const LoadedCage cage = read_obj(argv[1]);
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
