#!/usr/bin/env bash
# Grid measurements of issue 3, one benchmark at a time, single-threaded:
#  1. density sweep (lambda = 1/8 .. 8) of grid, hashgrid and grid2 on
#     bunny, sponza (interior view) and conference (interior view);
#  2. grid vs grid2 vs Embree on dragon_in_sponza (default view and a view
#     of the dragon);
#  3. a summary (Markdown) with the best lambda per scene and kind.
# Usage: scripts/grid_sweep.sh [OUT]   (run from the source directory after
# building; SHARED=../shared/scenes and RAYLAB=build/raylab by default).
set -euo pipefail
cd "$(dirname "$0")/.."
RAYLAB=${RAYLAB:-build/raylab}
SHARED=$(realpath "${SHARED:-../shared/scenes}")
OUT=${1:-out/grid_sweep}
REPEATS=${REPEATS:-3}
mkdir -p "$OUT/scenes"
for name in sponza conference dragon_in_sponza; do
  ln -sf "$SHARED/$name.ply" "$OUT/scenes/$name.ply"
  cp scripts/grid_views/$name.json "$OUT/scenes/$name.json"
done

DENSITIES=0.125,0.25,0.5,1,2,4,8
for scene in "$SHARED/bunny.ply" "$OUT/scenes/sponza.ply" "$OUT/scenes/conference.ply"; do
  name=$(basename "$scene" .ply)
  "$RAYLAB" bench --scene "$scene" --accel grid,hashgrid,grid2 --sweep density=$DENSITIES \
    --rays primary,diffuse --threads 1 --repeats "$REPEATS" --quiet --json "$OUT/sweep_$name.json" | tee "$OUT/sweep_$name.txt"
done

# Teapot in a stadium. The single grid tests ~1e5 triangles per ray that
# sees the dragon, so its run uses a smaller image.
"$RAYLAB" bench --scene "$SHARED/dragon_in_sponza.ply" --accel grid,hashgrid,grid2 --rays primary \
  --threads 1 --repeats "$REPEATS" --quiet --json "$OUT/dragon_default_view.json" | tee "$OUT/dragon_default_view.txt"
"$RAYLAB" bench --scene "$OUT/scenes/dragon_in_sponza.ply" --accel grid,grid2 --rays primary --size 128x128 \
  --threads 1 --repeats "$REPEATS" --quiet --json "$OUT/dragon_view.json" | tee "$OUT/dragon_view.txt"

/usr/bin/python3 scripts/grid_sweep_summary.py "$OUT"/sweep_*.json > "$OUT/summary.md"
cat "$OUT/summary.md"
