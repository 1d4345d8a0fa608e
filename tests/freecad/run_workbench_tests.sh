#!/usr/bin/env bash
# ctest driver (label freecad): the workbench's headless tests inside freecadcmd.
# Usage: run_workbench_tests.sh FREECADCMD SUBD2NURBS BUILD_PYTHON_DIR PLUGIN_DIR CORPUS_DIR
set -euo pipefail
freecadcmd=$1
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export S2N_CLI=$(realpath "$2") S2N_PYTHONPATH="$(realpath "$3"):$(realpath "$4")" S2N_CORPUS=$(realpath "$5")
export S2N_TEST_DIR="$here" PYTHONDONTWRITEBYTECODE=1
export HOME="$work"  # FreeCAD writes its user config under $HOME
cd "$work"
"$freecadcmd" -c "exec(open('$here/run_workbench_tests.py').read())"
