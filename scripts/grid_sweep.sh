#!/usr/bin/env bash
# Grid measurements, one benchmark at a time, single-threaded:
#  1. density sweep (lambda = 1/8 .. 8) of grid, hashgrid and grid2 on
#     bunny, sponza (interior view) and conference (interior view);
#  2. memory at large lambda (1 .. 512): grid against hashgrid on
#     dragon_in_sponza;
#  3. grid vs grid2 (vs Embree) on dragon_in_sponza: the default view and a
#     view of the dragon;
#  4. a summary (Markdown): medians over PASSES runs, best lambda per scene.
# Usage: scripts/grid_sweep.sh [OUT]   (from the source directory, after
# building; SHARED=../shared/scenes, RAYLAB=build/raylab, PASSES=3,
# REPEATS=3 by default).
set -euo pipefail
cd "$(dirname "$0")/.."
RAYLAB=${RAYLAB:-build/raylab}
SHARED=$(realpath "${SHARED:-../shared/scenes}")
OUT=${1:-out/grid_sweep}
REPEATS=${REPEATS:-3}
PASSES=${PASSES:-3}
mkdir -p "$OUT/scenes"
for name in sponza conference dragon_in_sponza; do
  ln -sf "$SHARED/$name.ply" "$OUT/scenes/$name.ply"
  cp scripts/grid_views/$name.json "$OUT/scenes/$name.json"
done

bench() {  # bench NAME ARGS...: one run, table to NAME.txt, records to NAME.json
  local name=$1
  shift
  "$RAYLAB" bench --threads 1 --repeats "$REPEATS" --quiet -o "$OUT/$name.json" "$@" | tee "$OUT/$name.txt"
}

DENSITIES=0.125,0.25,0.5,1,2,4,8
for pass in $(seq 1 "$PASSES"); do
  for scene in "$SHARED/bunny.ply" "$OUT/scenes/sponza.ply" "$OUT/scenes/conference.ply"; do
    bench "sweep_$(basename "$scene" .ply)_$pass" --scene "$scene" --accel grid,hashgrid,grid2 \
      --sweep density=$DENSITIES --ray-sets primary,diffuse
  done
  # Teapot in a stadium, default view (the dragon is under a pixel) and a
  # view of the dragon. The single grid tests ~1e5 triangles for each ray
  # that meets the dragon, so that run uses a smaller image.
  bench "dragon_default_$pass" --scene "$SHARED/dragon_in_sponza.ply" --accel grid,hashgrid,grid2 --ray-sets primary
  bench "dragon_view_$pass" --scene "$OUT/scenes/dragon_in_sponza.ply" --accel grid,grid2 --ray-sets primary --size 128x128
done
bench memory --scene "$SHARED/dragon_in_sponza.ply" --accel grid,hashgrid --sweep density=1,8,64,512 --ray-sets primary

/usr/bin/python3 scripts/grid_sweep_summary.py "$OUT" > "$OUT/summary.md"
cat "$OUT/summary.md"
