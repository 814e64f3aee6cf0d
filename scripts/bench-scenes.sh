#!/usr/bin/env bash
# The benchmark scene set: the procedural library's hard cases (always) plus,
# when ../shared/scenes is present (skipped, with a note, when it is not),
# its meshes seen the way researchers see them: the interior views of
# scenes/shared/*.json (Sponza, the conference room and the dragon in Sponza
# from inside, lights inside) instead of those files' outside framing, every
# other mesh of MANIFEST.tsv with its own framing, and the SPD scenes.
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
  interior=(sponza conference dragon_in_sponza)  # scenes/shared/NAME.json replaces the mesh's outside view
  while IFS=$'\t' read -r name file _; do
    if [[ " ${interior[*]} " == *" $name "* ]]; then scenes+=("scenes/shared/$name.json"); else scenes+=("$shared/$file"); fi
  done < <(tail -n +2 "$shared/MANIFEST.tsv")
  scenes+=("scenes/shared/sponza_aisle.json")  # a second Sponza viewpoint
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
