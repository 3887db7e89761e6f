#!/usr/bin/env bash
# The README's main command: installs dependencies, builds, and runs the whole pipeline on the
# built-in creature (no input file needed). Outputs go to out/ (or OUT_DIR).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
./scripts/build.sh
out=${OUT_DIR:-out}
mkdir -p "$out"
bin=build/apps/isocharts
mesh=${1:-builtin:creature}
echo "== atlas: $mesh"
"$bin" atlas "$mesh" -o "$out/creature_atlas.obj" -o "$out/creature_atlas.glb" --png "$out/creature_atlas.png" \
  --report "$out/creature_atlas.json"
"$bin" render "$out/creature_atlas.obj" --charts -o "$out/creature_charts.png" --views 4
echo
echo "Outputs in $out/:"
ls -1 "$out"
