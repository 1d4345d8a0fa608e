#!/usr/bin/env bash
# Installs the Debian packages subd2nurbs needs (skipping those already present),
# then configures and builds into ./build. Idempotent; safe to run repeatedly.
# Usage: scripts/bootstrap.sh            (run as root, or with sudo available)
#        WITH_FREECAD=1 scripts/bootstrap.sh   also installs FreeCAD (for the tests)
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libtinyobjloader-dev libtinygltf-dev libcli11-dev
  liblz4-dev python3-lz4           # LZ4: the USD crate (usdc) reader; python3-lz4 for its test oracle
  libgtest-dev libgmock-dev libbenchmark-dev
  libosd-dev                       # OpenSubdiv: the Catmull-Clark oracle in tests and benchmarks
  pybind11-dev python3-dev python3-numpy   # the Python module (built for /usr/bin/python3)
  python3-distributed              # Dask: subd2nurbs-batch --scheduler / --dask-local and its tests
  # OCCT 7.6 (target subd2nurbs::occt). data-exchange-dev pulls in ocaf-dev and
  # visualization-dev, whose CMake targets OCCT's DataExchange config insists on;
  # libtbb-dev because the OCCT targets link /usr/lib/x86_64-linux-gnu/libtbb.so by path.
  libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev
  libocct-data-exchange-dev libocct-ocaf-dev libocct-visualization-dev libtbb-dev
)
# The tests also import our STEP files in FreeCAD (label freecad): scripts/test.sh sets
# WITH_FREECAD=1. About 1.4 GB and 2 minutes; the demo does not need it.
# xvfb + xauth: the workbench's GUI test runs FreeCAD under a virtual X server.
if [ "${WITH_FREECAD:-0}" = 1 ]; then PACKAGES+=(freecad xvfb xauth); fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "bootstrap: installing ${missing[*]}" >&2
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi

BUILD_TYPE=${BUILD_TYPE:-Release}
cmake -S . -B build -DCMAKE_BUILD_TYPE="$BUILD_TYPE" "$@" >&2
cmake --build build -j"$(nproc)" >&2
