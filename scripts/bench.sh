#!/usr/bin/env bash
# Runs the benchmarks and writes docs/benchmarks.md with medians and ratios:
#   bench_refine   uniform refinement, ours vs OpenSubdiv (100k-quad torus)
#   bench_limit    exact limit evaluation throughput, ours vs OpenSubdiv's PatchTable + PatchMap
#   bench_convert  the conversion pipeline on 10k-quad cages: cage -> patches (vs OpenSubdiv's
#                  patch tables), PatchSet -> B-rep (and BRepCheck alone), STEP (ours vs OCCT's
#                  plain STEPControl_Writer)
#   bench_fit.py   convert --fit interpolate against a plain convert, 10k- and 100k-quad tori
#                  (wall time and peak memory of separate processes; FIT_REPS repetitions,
#                  default 3, about 10 minutes)
# Each binary runs every benchmark REPS times, repetitions randomly interleaved.
# Usage: scripts/bench.sh [repetitions]    (default 9: about 8 minutes on the 2-core machine)
#   BUILD_DIR=DIR scripts/bench.sh N   builds only the benchmarks in DIR (configured with tests
#                                      off) instead of running scripts/bootstrap.sh into ./build
set -euo pipefail
cd "$(dirname "$0")/.."
reps=${1:-9}
build=${BUILD_DIR:-build}
if [ "$build" = build ]; then
  scripts/bootstrap.sh
else
  cmake -S . -B "$build" -DSUBD2NURBS_BUILD_TESTS=OFF -DSUBD2NURBS_BUILD_BENCH=ON >&2
  cmake --build "$build" -j"$(nproc)" --target bench_refine bench_convert bench_limit bench_fit subd2nurbs >&2
fi
refine_json=$(mktemp)
convert_json=$(mktemp)
limit_json=$(mktemp)
trap 'rm -f "$refine_json" "$convert_json" "$limit_json" docs/benchmarks.md.tmp' EXIT
# JSON goes to files: OCCT's plain STEP writer (the reference in bench_convert) prints its
# statistics on stdout. The console output goes to stderr as progress.
common=(--benchmark_repetitions="$reps" --benchmark_enable_random_interleaving=true
        --benchmark_out_format=json)
"$build"/bench/bench_refine "${common[@]}" --benchmark_out="$refine_json" >&2
"$build"/bench/bench_convert "${common[@]}" --benchmark_out="$convert_json" >&2
"$build"/bench/bench_limit "${common[@]}" --benchmark_out="$limit_json" >&2
python3 scripts/bench_table.py "$refine_json" "$reps" "$convert_json" "$limit_json" > docs/benchmarks.md.tmp
{ echo; python3 scripts/bench_fit.py "$build" "${FIT_REPS:-3}"; } >> docs/benchmarks.md.tmp
mv docs/benchmarks.md.tmp docs/benchmarks.md
cat docs/benchmarks.md
