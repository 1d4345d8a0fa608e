#!/usr/bin/env bash
# The main job on a bundled sample: install, build, describe and refine the cage, then convert
# it to bicubic NURBS and write a STEP file with a JSON report.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/bootstrap.sh
mkdir -p out
build/subd2nurbs info samples/rounded_box.obj
build/subd2nurbs refine samples/rounded_box.obj -l 2 -o out/rounded_box_l2.obj
echo "wrote out/rounded_box_l2.obj"
build/subd2nurbs convert samples/rounded_box.obj -o out/rounded_box.step --report out/rounded_box_report.json
