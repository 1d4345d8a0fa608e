#!/usr/bin/env bash
# Install, build and run every test (the same command CI runs).
set -euo pipefail
cd "$(dirname "$0")/.."
WITH_FREECAD=1 scripts/bootstrap.sh
ctest --test-dir build --output-on-failure -j"$(nproc)" "$@"
