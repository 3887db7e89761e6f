#!/usr/bin/env bash
# The README's main command: installs dependencies, builds, and runs the whole pipeline on the
# built-in creature (no input file needed). Outputs go to out/ (or OUT_DIR).
set -euo pipefail
cd "$(dirname "$0")/.."
[ "${ISOCHARTS_DEMO_NO_BUILD:-0}" = 1 ] || ./scripts/install-deps.sh
[ "${ISOCHARTS_DEMO_NO_BUILD:-0}" = 1 ] || ./scripts/build.sh
out=${OUT_DIR:-out}
mkdir -p "$out"
bin=build/apps/isocharts
mesh=${1:-builtin:creature}
name=$(basename "${mesh#builtin:}")
name=${name%.*}
echo "== atlas: $mesh"
"$bin" atlas "$mesh" -o "$out/${name}_atlas.obj" -o "$out/${name}_atlas.glb" --png "$out/${name}_atlas.png" \
  --report "$out/${name}_atlas.json"
"$bin" render "$out/${name}_atlas.obj" --charts -o "$out/${name}_charts.png" --views 4
echo "== remesh: multi-chart geometry image pyramid of the same atlas"
"$bin" remesh "$out/${name}_atlas.obj" --atlas "$out/${name}_atlas.obj" -o "$out/${name}_remesh.ply" \
  --levels 256,128,64,32 --png "$out/${name}_gim" --exr "$out/${name}_gim" --report "$out/${name}_remesh.json"
"$bin" render "$out/${name}_remesh_64.ply" --wireframe -o "$out/${name}_remesh_64.png" --views 4
echo "== synth: the built-in procedural bricks exemplar (exemplars/bricks.png) grown over the surface"
"$bin" synth "$mesh" -o "$out/${name}_synth.glb" --report "$out/${name}_synth.json"
"$bin" render "$out/${name}_synth.obj" --texture "$out/${name}_synth.png" -o "$out/${name}_synth_views.png" --views 4
echo
echo "Outputs in $out/:"
ls -1 "$out"
