#!/usr/bin/env bash
# ctest driver (label freecad): the workbench in FreeCAD's GUI under Xvfb.
# Installs the workbench with `cmake --install BUILD --component freecad` into a scratch
# DESTDIR and points HOME there, so FreeCAD finds it in $HOME/.local/share/FreeCAD/Mod as a
# user would; then runs gui_convert.py in `freecad`.
# Usage: run_gui_test.sh FREECAD BUILD_DIR MOD_DIR CAGE.obj SCREENSHOT.png MESH.stl
#   MOD_DIR: the configured SUBD2NURBS_FREECAD_MOD_DIR (must end in .local/share/FreeCAD/Mod/NAME)
set -euo pipefail
freecad=$1; build=$(realpath "$2"); mod_dir=$3; cage=$(realpath "$4"); out=$(realpath -m "$5"); mesh=$(realpath "$6")
here=$(cd "$(dirname "$0")" && pwd)
suffix=/.local/share/FreeCAD/Mod/
case "$mod_dir" in
  *"$suffix"*) ;;
  *) echo "run_gui_test: SUBD2NURBS_FREECAD_MOD_DIR=$mod_dir is not a user Mod folder" >&2; exit 1 ;;
esac
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
DESTDIR="$work/dest" cmake --install "$build" --component freecad >/dev/null
export HOME="$work/dest${mod_dir%%"$suffix"*}"
test -f "$HOME/.local/share/FreeCAD/Mod/$(basename "$mod_dir")/InitGui.py"
export S2N_CAGE="$cage" S2N_SCREENSHOT="$out" S2N_MESH="$mesh" PYTHONDONTWRITEBYTECODE=1
export QTWEBENGINE_DISABLE_SANDBOX=1 QT_QPA_PLATFORM=xcb LIBGL_ALWAYS_SOFTWARE=1
cd "$work"
xvfb-run -a -s "-screen 0 1280x1024x24" "$freecad" "$here/gui_convert.py"
test -s "$out"
