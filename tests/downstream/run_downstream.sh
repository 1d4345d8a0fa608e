#!/usr/bin/env bash
# ctest driver of the downstream suite: converts small cages with the CLI (packed and per-quad
# faces, polar caps on and off) to BREP, then runs downstream_ops.py in FreeCAD (headless):
# booleans, offsets, hollow, cut-then-shell, fillet, sections, mesh, STEP round trip, on our
# bodies and on OCCT's own.
# Usage: run_downstream.sh SUBD2NURBS FREECADCMD CORPUS_DIR SAMPLES_DIR MESH_DIR
set -euo pipefail
exe=$(realpath "$1"); freecadcmd=$2; corpus=$(realpath "$3"); samples=$(realpath "$4"); meshes=$(realpath "$5")
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
convert() {  # NAME CAGE [OPTIONS...]
  local name=$1 cage=$2; shift 2
  "$exe" convert "$cage" -o "$work/$name.brep" --report "$work/$name.json" --quiet "$@"
  bodies="$bodies $name=$work/$name.brep"
}
bodies=""
convert torus_packed "$corpus/catmark_torus.obj"
convert torus_per_quad "$corpus/catmark_torus.obj" --faces per-quad
convert cube_packed "$corpus/catmark_cube.obj"
convert capped_cylinder_polar "$samples/capped_cylinder.obj"
convert capped_cylinder_nopolar "$samples/capped_cylinder.obj" --polar off
convert cube_creases "$corpus/catmark_cube_creases2.obj"
# Semi-sharp creases: a smallest radius (0.0088, 0.0065) far below 2 % of the diagonal, so the
# shell and the inward offsets run at half of it (docs/downstream.md).
convert torus_creases0 "$corpus/catmark_torus_creases0.obj"
convert torus_creases1 "$corpus/catmark_torus_creases1.obj"
# A real cage (Bob, 334 quads, 20 extraordinary vertices, genus 1): packs as large as real
# models get, taking in the quads at extraordinary vertices with their nested knots, where the
# test shapes above stay small (docs/downstream.md).
convert bob_packed "$meshes/bob_controlmesh.obj"
export S2N_BODIES="$bodies" S2N_OUT="$work" S2N_HELPERS="$here"  # S2N_HELPERS: cut_helpers.py
export HOME="$work"  # FreeCAD writes its user config under $HOME
cd "$work"
"$freecadcmd" -c "exec(open('$here/downstream_ops.py').read())"
