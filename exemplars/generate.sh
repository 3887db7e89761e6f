#!/bin/sh
# Regenerates the project's procedural exemplars (deterministic: same bytes on every run).
# Usage: exemplars/generate.sh [path/to/isocharts]   (default: build/apps/isocharts)
set -e
here=$(cd "$(dirname "$0")" && pwd)
cli=${1:-$here/../build/apps/isocharts}
for name in bricks cells weave noise; do
  "$cli" exemplar "$name" --size 128 -o "$here/$name.png" -q
done
