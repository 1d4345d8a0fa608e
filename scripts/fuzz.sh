#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (tests/fuzz, core and io only, ASan + UBSan) into
# build-fuzz and runs each for SECONDS seconds (default 600) or RUNS executions, from a seed
# corpus made of tests/data (the OpenSubdiv shapes, the invalid and valid samples) and
# samples/ (docs/hardening.md). Crashes are written to build-fuzz/findings/<target>/.
#   scripts/fuzz.sh                 all four targets, 600 s each
#   SECONDS_PER_TARGET=60 scripts/fuzz.sh fuzz_obj
#   RUNS=10000000 scripts/fuzz.sh fuzz_obj
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build-fuzz}
PER=${SECONDS_PER_TARGET:-600}
RUNS=${RUNS:--1}
JOBS=${JOBS:-2}
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=(fuzz_obj fuzz_gltf fuzz_limit_queries fuzz_convert)

nice -n 10 cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_C_COMPILER=clang -DSUBD2NURBS_FUZZ=ON -DSUBD2NURBS_BUILD_TESTS=OFF -DSUBD2NURBS_BUILD_BENCH=OFF \
  -DSUBD2NURBS_BUILD_PYTHON=OFF >/dev/null
nice -n 10 cmake --build "$BUILD" -j"$JOBS" --target "${TARGETS[@]}"

seeds="$BUILD/seeds"
mkdir -p "$seeds/obj" "$seeds/gltf" "$seeds/queries"
cp tests/data/corpus/*.obj tests/data/invalid/*.obj tests/data/valid/*.obj samples/*.obj "$seeds/obj/" 2>/dev/null || true
# glTF seeds: the hostile corpus's glTF / GLB files (valid cubes and each kind of broken one),
# the first byte choosing GLB (1) or JSON (0) as fuzz_gltf reads it.
python3 scripts/make_hostile_corpus.py "$BUILD/hostile" >/dev/null
for f in "$BUILD"/hostile/*.glb; do [ -f "$f" ] && { printf '\001'; cat "$f"; } > "$seeds/gltf/$(basename "$f")"; done
for f in "$BUILD"/hostile/*.gltf; do [ -f "$f" ] && { printf '\000'; cat "$f"; } > "$seeds/gltf/$(basename "$f")"; done
printf '0 0.5 0.5\n1 0 0.25 0.75\n# comment\n\n4 3 1 0\n' > "$seeds/queries/basic.txt"
printf '2 0 0 0\n2 1 1\n0 0 1 1\n' > "$seeds/queries/corners.txt"

dict_for() { case "$1" in fuzz_obj|fuzz_convert) echo tests/fuzz/obj.dict;; fuzz_gltf) echo tests/fuzz/gltf.dict;; *) echo "";; esac; }
seed_for() { case "$1" in fuzz_obj|fuzz_convert) echo "$seeds/obj";; fuzz_gltf) echo "$seeds/gltf";; *) echo "$seeds/queries";; esac; }

for t in "${TARGETS[@]}"; do
  work="$BUILD/corpus/$t"; findings="$BUILD/findings/$t"
  mkdir -p "$work" "$findings"
  dict=$(dict_for "$t"); dict_arg=(); [ -n "$dict" ] && dict_arg=(-dict="$dict")
  echo "== $t: ${PER}s (runs ${RUNS})"
  nice -n 19 "$BUILD/$t" "$work" "$(seed_for "$t")" "${dict_arg[@]}" -max_total_time="$PER" -runs="$RUNS" \
    -max_len=65536 -rss_limit_mb=2048 -timeout=20 -print_final_stats=1 -artifact_prefix="$findings/" \
    2>&1 | tee "$BUILD/$t.log" | grep -E "^(#[0-9]+ +DONE|stat::|==[0-9]+==ERROR|SUMMARY|Done)" || true
done
