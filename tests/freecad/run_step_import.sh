#!/usr/bin/env bash
# ctest driver: convert a cage with the CLI (one face per quad, and packed), then import both
# STEP files in FreeCAD (headless).
# Usage: run_step_import.sh SUBD2NURBS FREECADCMD CAGE.obj
set -euo pipefail
exe=$(realpath "$1"); freecadcmd=$2; cage=$(realpath "$3")
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$exe" convert "$cage" -o "$work/part.step" --faces per-quad --quiet
"$exe" convert "$cage" -o "$work/packed.step" --report "$work/packed.json" --quiet
export S2N_STEP="$work/part.step" S2N_CAGE="$cage" S2N_PACKED="$work/packed.step" S2N_PACKED_REPORT="$work/packed.json"
export HOME="$work"  # FreeCAD writes its user config under $HOME
cd "$work"
"$freecadcmd" -c "exec(open('$here/check_step_import.py').read())"
