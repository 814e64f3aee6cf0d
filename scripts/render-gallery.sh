#!/usr/bin/env bash
# Renders scenes one at a time with `raylab render` and prints one table row
# per scene: triangles, load ms, BVH build ms, render seconds and the exact
# command. Used for the README gallery (docs/gallery/) and for checking that
# every scene renders.
#
#   scripts/render-gallery.sh                      the gallery: procedural library + examples -> docs/gallery
#   scripts/render-gallery.sh --shared             every mesh of ../shared/scenes (incl. spd/) -> out/shared
#   scripts/render-gallery.sh [options] SCENE...   any scenes
# Options: --out DIR, --size WxH (default 256x256), --spp N (default 32 for the
# gallery, 16 otherwise), --accel SPEC (default bvh).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
raylab="build/raylab"
[ -x "$raylab" ] || { echo "render-gallery: build raylab first (make build)" >&2; exit 2; }
size=256x256
spp=""
accel=bvh
out=""
shared=0
scenes=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --size) size="$2"; shift 2 ;;
    --spp) spp="$2"; shift 2 ;;
    --accel) accel="$2"; shift 2 ;;
    --shared) shared=1; shift ;;
    -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
    *) scenes+=("$1"); shift ;;
  esac
done

if [ "$shared" = 1 ]; then
  dir="$root/../shared/scenes"
  [ -f "$dir/MANIFEST.tsv" ] || { echo "render-gallery: ../shared/scenes not present" >&2; exit 2; }
  while IFS=$'\t' read -r _ file _; do scenes+=("../shared/scenes/$file"); done < <(tail -n +2 "$dir/MANIFEST.tsv")
  scenes+=("../shared/scenes/extras/CornellBox-Original.obj")
  for f in "$dir"/spd/*.obj; do scenes+=("../shared/scenes/spd/$(basename "$f")"); done
  out="${out:-out/shared}"
  spp="${spp:-16}"
elif [ ${#scenes[@]} -eq 0 ]; then
  scenes=(cornell soup sphere sphereflake terrain grass stadium city tetra
          scenes/examples/cornell_flake.json scenes/examples/studio.json scenes/examples/mini_spd.nff)
  out="${out:-docs/gallery}"
  spp="${spp:-32}"
fi
out="${out:-out/gallery}"
spp="${spp:-16}"
mkdir -p "$out"

printf '| scene | triangles | load ms | build ms | render s | command |\n|---|---:|---:|---:|---:|---|\n'
status=0
for scene in "${scenes[@]}"; do
  name="$(basename "$scene")"
  name="${name%.*}"
  name="${name//[^A-Za-z0-9_-]/_}"
  cmd="build/raylab render $scene --accel $accel --size $size --spp $spp -o $out/$name.png --quiet"
  if line="$($cmd 2>&1)"; then
    # "<name>: N triangles (loaded in X ms), bvh built in Y ms, WxH at S spp in T s (...)"
    tris="$(sed -E 's/.*: ([0-9]+) triangles.*/\1/' <<<"$line")"
    load="$(sed -E 's/.*loaded in ([0-9.]+) ms.*/\1/' <<<"$line")"
    build="$(sed -E 's/.* built in ([0-9.]+) ms.*/\1/' <<<"$line")"
    secs="$(sed -E 's/.* spp in ([0-9.]+) s .*/\1/' <<<"$line")"
    printf '| %s | %s | %s | %s | %s | `%s` |\n' "$scene" "$tris" "$load" "$build" "$secs" "$cmd"
  else
    printf '| %s | - | - | - | - | `%s` -> %s |\n' "$scene" "$cmd" "$line"
    status=1
  fi
done
exit $status
