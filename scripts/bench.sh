#!/usr/bin/env bash
# Runs the benchmarks and writes docs/benchmarks.md with medians and ratios:
#   bench_refine   uniform refinement, ours vs OpenSubdiv (100k-quad torus)
#   bench_limit    exact limit evaluation throughput, ours vs OpenSubdiv's PatchTable + PatchMap
#   bench_convert  the conversion pipeline on 10k-quad cages: cage -> patches (vs OpenSubdiv's
#                  patch tables), PatchSet -> B-rep (and BRepCheck alone), STEP (ours vs OCCT's
#                  plain STEPControl_Writer)
#   bench_models   real models through the command line (scripts/bench_models.py): wall time,
#                  peak RSS, STEP size, faces and poles, what --report and check cost; 3 runs
#                  each with and without --report, and of check (MODEL_REPS)
#   bench_packing  packed faces against one face per quad (scripts/bench_packing.py): wall time,
#                  peak RSS, STEP size, faces, edges, poles; 3 runs each (PACK_REPS)
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
{
  echo
  echo "## 7. Real models through the command line (\`scripts/bench_models.py\`)"
  echo
  echo "\`subd2nurbs convert X.obj -o X.step --report r.json -q\` with the defaults (deviation tolerance"
  echo "1e-4 of the diagonal), ${MODEL_REPS:-3} runs each, medians, alternating with as many runs without"
  echo "\`--report\` and of \`subd2nurbs check X.obj --json q.json\`. The quality stage (\`quality_ms\`) runs"
  echo "on a thread of its own beside packing, the measures, OCCT's B-rep and the STEP writing, so its"
  echo "own time is not what it adds: the column \"--report adds\" is (median wall with it - median wall"
  echo "without) / median wall without. \`check\` builds no B-rep; its last column is the time it waited"
  echo "for the stage after its own stages (\`quality_wait_ms\`) over the median conversion wall without"
  echo "\`--report\`. Issue #11 asks for at most 0.25 of the conversion. A difference of two medians of"
  echo "separate runs carries the machine's noise (about +-0.1 of the wall on the shared 2-core machine)."
  echo
  python3 scripts/bench_models.py "$build/subd2nurbs" tests/data/corpus "${MODEL_REPS:-3}"
  cat <<'BEFORE'

Before issue #11 (every patch with all the uniform spans of level k, semi-sharp creases capped
at level a + 5), as the issue measured it on the landed main (wall on an idle machine, in
brackets on a busy one):

| cage (faces) | wall | peak RSS | STEP | faces | poles per face |
|---|---|---|---|---|---|
| catmark_bishop (968) | 40 s (111 s) | 5.3 GB | 432 MB | 3 406 | 1 225 |
| catmark_rook | 29 s (153 s) | 4.5 GB | 387 MB | 3 064 | 1 225 |
| catmark_car | 25 s (45 s) | 2.4 GB | 212 MB | 1 575 | - |
| catmark_pawn | (8 s) | 0.9 GB | 72 MB | 588 | 1 237 |
| 100 000-quad regular torus | (117 s) | 8.0 GB | 870 MB | 100 000 | 49 |
BEFORE
} >> docs/benchmarks.md.tmp
{
  echo
  echo "## 8. Packed faces against one face per quad (\`scripts/bench_packing.py\`)"
  echo
  echo "\`subd2nurbs convert X.obj -o X.step -q --faces per-quad\` and \`--faces packed\` (the default), no"
  echo "report: the whole pipeline from reading the OBJ to the renamed STEP file. ${PACK_REPS:-3} runs of each,"
  echo "alternating, medians; faces, edges and poles from one more run with \`--report\`. The last column"
  echo "divides packed by per-quad (wall time, B-rep faces, poles)."
  echo
  python3 scripts/bench_packing.py "$build/subd2nurbs" tests/data/corpus "${PACK_REPS:-3}"
} >> docs/benchmarks.md.tmp
# Section 9 (subd2nurbs fit on real cages and scans) is measured by hand with /usr/bin/time as
# the section says; it is carried over from the current page.
{
  echo
  sed -n '/^## 9\. Fitting/,/^## 10\./p' docs/benchmarks.md | sed '$d'
} >> docs/benchmarks.md.tmp
{
  echo "## 10. Python threads (\`bench/python_threads.py\`, issue #32 item 5)"
  echo
  echo "\`subd2nurbs.convert\` runs without the interpreter lock. Catmark car, pawn, rook and bishop,"
  echo "each converted twice (defaults), in one thread and spread over 4 threads; wall time, median"
  echo "of 3 runs each. Each conversion's own parallel loops already use every core, so threads add"
  echo "throughput only where a conversion runs single-threaded stages."
  echo
  PYTHONPATH="$build/python" /usr/bin/python3 bench/python_threads.py
} >> docs/benchmarks.md.tmp
# Section 11 (subd2nurbs-batch: local pool and Dask against a plain convert loop,
# bench/batch_bench.py, about 15 minutes) is measured by hand; carried over from the current page.
{
  echo
  sed -n '/^## 11\. Batch conversion/,/^## 12\./p' docs/benchmarks.md | sed '/^## 12\./d'
} >> docs/benchmarks.md.tmp
# Section 12 (the mesh path against Blender's QuadriFlow, scripts/bench_meshes.py: needs Blender,
# about 15 minutes) is measured by hand; carried over from the current page.
{
  sed -n '/^## 12\. Mesh path/,$p' docs/benchmarks.md
} >> docs/benchmarks.md.tmp
mv docs/benchmarks.md.tmp docs/benchmarks.md
cat docs/benchmarks.md
