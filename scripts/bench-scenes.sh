#!/usr/bin/env bash
# The benchmark scene set: the procedural library's hard cases (always) plus
# every mesh of ../shared/scenes/MANIFEST.tsv and the SPD scenes when that
# folder is present (skipped, with a note, when it is not).
#
#   scripts/bench-scenes.sh --list                  print the scene specs, one per line
#   scripts/bench-scenes.sh [raylab bench options]  run `raylab bench` on each scene in turn,
#                                                   e.g. --accel embree,bvh --ray-sets primary,diffuse --threads 1
# Default options: --accel embree,bvh --ray-sets primary,diffuse,shadow,random --threads 1.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
scenes=(cornell sphereflake terrain grass stadium city tetra "soup:n=100000")
shared="../shared/scenes"
if [ -f "$shared/MANIFEST.tsv" ]; then
  while IFS=$'\t' read -r _ file _; do scenes+=("$shared/$file"); done < <(tail -n +2 "$shared/MANIFEST.tsv")
  for f in "$shared"/spd/*.obj; do scenes+=("$f"); done
else
  echo "bench-scenes: $shared not present: real meshes skipped" >&2
fi

if [ "${1:-}" = "--list" ]; then
  printf '%s\n' "${scenes[@]}"
  exit 0
fi
[ -x build/raylab ] || { echo "bench-scenes: build raylab first (make build)" >&2; exit 2; }
opts=("$@")
[ ${#opts[@]} -gt 0 ] || opts=(--accel embree,bvh --ray-sets primary,diffuse,shadow,random --threads 1)
for scene in "${scenes[@]}"; do
  build/raylab bench --scene "$scene" "${opts[@]}"
done
