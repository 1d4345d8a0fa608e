#!/usr/bin/env bash
# ctest driver: convert a cage with the CLI, then import the STEP in FreeCAD (headless).
# Usage: run_step_import.sh SUBD2NURBS FREECADCMD CAGE.obj
set -euo pipefail
exe=$(realpath "$1"); freecadcmd=$2; cage=$(realpath "$3")
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$exe" convert "$cage" -o "$work/part.step" --quiet
export S2N_STEP="$work/part.step" S2N_CAGE="$cage"
export HOME="$work"  # FreeCAD writes its user config under $HOME
cd "$work"
"$freecadcmd" -c "exec(open('$here/check_step_import.py').read())"
