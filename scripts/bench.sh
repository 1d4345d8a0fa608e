#!/usr/bin/env bash
# Runs the refinement benchmark (ours vs OpenSubdiv, same run, interleaved repetitions) and
# writes docs/benchmarks.md with medians and ratios. Usage: scripts/bench.sh [repetitions]
set -euo pipefail
cd "$(dirname "$0")/.."
reps=${1:-9}
scripts/bootstrap.sh
json=$(mktemp)
build/bench/bench_refine --benchmark_repetitions="$reps" --benchmark_enable_random_interleaving=true \
  --benchmark_format=json >"$json"
python3 scripts/bench_table.py "$json" "$reps" > docs/benchmarks.md.tmp
mv docs/benchmarks.md.tmp docs/benchmarks.md
rm -f "$json"
cat docs/benchmarks.md
