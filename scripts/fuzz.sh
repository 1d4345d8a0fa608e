#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (tests/fuzz, core and io only, ASan + UBSan, or
# UBSan alone with SANITIZERS=undefined) into build-fuzz (build-fuzz-ubsan) and runs each for
# SECONDS_PER_TARGET seconds (default 600) or RUNS executions, from a seed corpus made of
# tests/data (the OpenSubdiv shapes, the invalid and valid samples) and samples/
# (docs/hardening.md). Crashes are written to <build>/findings/<target>/.
#   scripts/fuzz.sh                 all seven targets, 600 s each
#   SECONDS_PER_TARGET=60 scripts/fuzz.sh fuzz_obj
#   SANITIZERS=undefined RUNS=10000000 SECONDS_PER_TARGET=0 MAX_LEN=4096 scripts/fuzz.sh fuzz_obj
set -euo pipefail
cd "$(dirname "$0")/.."
SANITIZERS=${SANITIZERS:-address,undefined}
if [ "$SANITIZERS" = undefined ]; then BUILD=${BUILD:-build-fuzz-ubsan}; else BUILD=${BUILD:-build-fuzz}; fi
MAX_LEN=${MAX_LEN:-65536}
PER=${SECONDS_PER_TARGET:-600}
RUNS=${RUNS:--1}
JOBS=${JOBS:-2}
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=(fuzz_obj fuzz_gltf fuzz_limit_queries fuzz_convert fuzz_stl fuzz_ply fuzz_off fuzz_usda fuzz_usdc)

nice -n 10 cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_C_COMPILER=clang -DSUBD2NURBS_FUZZ=ON -DSUBD2NURBS_FUZZ_SANITIZERS="$SANITIZERS" -DSUBD2NURBS_BUILD_TESTS=OFF -DSUBD2NURBS_BUILD_BENCH=OFF \
  -DSUBD2NURBS_BUILD_PYTHON=OFF >/dev/null
nice -n 10 cmake --build "$BUILD" -j"$JOBS" --target "${TARGETS[@]}"

# Seeds: the OBJ shapes of tests/data and samples/; the glTF / GLB and query seeds of
# tests/fuzz/seeds (the glTF ones carry fuzz_gltf's leading GLB/JSON byte); and every earlier
# finding of tests/fuzz/regressions.
seeds="$BUILD/seeds"
mkdir -p "$seeds/obj"
cp tests/data/corpus/*.obj tests/data/invalid/*.obj tests/data/valid/*.obj samples/*.obj "$seeds/obj/" 2>/dev/null || true
# The mesh readers' seeds, with the small real OFF files of tests/data/mesh (the STL ones are
# near MAX_LEN and slow every execution down).
mkdir -p "$seeds/fuzz_stl" "$seeds/fuzz_ply" "$seeds/fuzz_off"
for t in fuzz_stl fuzz_ply fuzz_off; do cp tests/fuzz/seeds/$t/* "$seeds/$t/"; done
cp tests/data/mesh/*.off "$seeds/fuzz_off/"

dict_for() { case "$1" in fuzz_obj|fuzz_convert) echo tests/fuzz/obj.dict;; fuzz_gltf) echo tests/fuzz/gltf.dict;; fuzz_usda) echo tests/fuzz/usda.dict;; *) echo "";; esac; }
seed_for() { case "$1" in fuzz_obj|fuzz_convert) echo "$seeds/obj";; fuzz_stl|fuzz_ply|fuzz_off) echo "$seeds/$1";; *) echo "tests/fuzz/seeds/$1";; esac; }

for t in "${TARGETS[@]}"; do
  work="$BUILD/corpus/$t"; findings="$BUILD/findings/$t"
  mkdir -p "$work" "$findings"
  dict=$(dict_for "$t"); dict_arg=(); [ -n "$dict" ] && dict_arg=(-dict="$dict")
  echo "== $t: ${PER}s (runs ${RUNS})"
  found=(); [ -d "tests/fuzz/regressions/$t" ] && found=("tests/fuzz/regressions/$t")
  nice -n 19 "$BUILD/$t" "$work" "$(seed_for "$t")" "${found[@]}" "${dict_arg[@]}" -max_total_time="$PER" -runs="$RUNS" \
    -max_len="$MAX_LEN" -rss_limit_mb=2048 -timeout=20 -print_final_stats=1 -artifact_prefix="$findings/" \
    2>&1 | tee "$BUILD/$t.log" | grep -E "^(#[0-9]+ +DONE|stat::|==[0-9]+==ERROR|SUMMARY|Done)" || true
done
