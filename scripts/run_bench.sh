#!/usr/bin/env bash
# The benchmark run behind `make bench`: the bench matrix, verify, watertight stress, parameter
# sweeps, scaling and equal-time renders, then the charts.
#
#   scripts/run_bench.sh [quick|full]      (default quick)
#
# Environment: BUILD (default build), OUT (default out/bench).
# Writes OUT/*.json, OUT/*.csv, OUT/equal_time/*, OUT/charts/*.png|svg and
# OUT/summary.md. With the quick preset it also copies the chart PNGs to
# docs/charts/ (the README shows them).
set -euo pipefail
cd "$(dirname "$0")/.."
PRESET=${1:-quick}
BUILD=${BUILD:-build}
OUT=${OUT:-out/bench}
RAYLAB=./$BUILD/raylab
PY=/usr/bin/python3
mkdir -p "$OUT/equal_time"

case "$PRESET" in
  quick)
    SWEEP_SCENE="terrain:n=96"
    SWEEP_ARGS=(--ray-sets primary,random --threads 1 --size 256x256 --rays 65536 --repeats 5 --build-repeats 1)
    SCALE="soup:n=1000,10000,100000,1000000"
    SCALE_ARGS=(--ray-sets primary,random --threads 1 --size 128x128 --rays 32768 --repeats 5 --build-repeats 1)
    SCALE_ACCELS="embree,bvh,kdtree,grid,hashgrid,grid2"
    VERIFY_SCENES=("cornell" "terrain:n=96" "sphereflake:level=2,segments=12")
    VERIFY_RAYS=16384
    RENDER_SCENE="sphereflake:level=2,segments=12"; RENDER_SIZE=96x96; RENDER_SPPS="1 2 4 8 16 32 64"; REF_SPP=2048
    ;;
  full)
    SWEEP_SCENE="terrain:n=256"
    SWEEP_ARGS=(--ray-sets primary,diffuse,random --threads 1 --size 512x512 --rays 262144 --repeats 7 --build-repeats 3)
    SCALE="soup:n=1000,10000,100000,1000000,10000000"
    SCALE_ARGS=(--ray-sets primary,random --threads 1 --size 256x256 --rays 65536 --repeats 5 --build-repeats 1)
    SCALE_ACCELS="embree,bvh,kdtree,grid,hashgrid,grid2"
    VERIFY_SCENES=("cornell" "terrain:n=256" "sphereflake:level=3" "city" "grass")
    VERIFY_RAYS=262144
    RENDER_SCENE="sphereflake:level=2"; RENDER_SIZE=128x128; RENDER_SPPS="1 2 4 8 16 32 64 128"; REF_SPP=4096
    ;;
  *) echo "run_bench.sh: unknown preset '$PRESET' (quick or full)" >&2; exit 2 ;;
esac

step() { echo "== $* ($(date -u +%H:%M:%S))" >&2; }

step "bench matrix (--preset $PRESET)"
$RAYLAB bench --preset "$PRESET" --json "$OUT/bench.json" > "$OUT/bench.txt"

step "verify"
i=0
for s in "${VERIFY_SCENES[@]}"; do
  # Exit code 1 = disagreements found: recorded in the JSON, not a failure of the run.
  $RAYLAB verify --scene "$s" --accel "all;bvh:layout=bvh2,tri=mt" --ray-sets primary,diffuse,shadow,random --rays $VERIFY_RAYS \
    --json "$OUT/verify_$i.json" > "$OUT/verify_$i.txt" || [ $? -eq 1 ]
  i=$((i + 1))
done

step "stress (watertight scenarios: leaks per accelerator, for the speed-vs-accuracy chart)"
# Exit code 1 = a watertight-test accelerator leaked or gave a wrong hit: recorded, and
# reported by the chart, not a failure of the benchmark run.
$RAYLAB stress --scenario watertight --json "$OUT/stress.json" > "$OUT/stress.txt" || [ $? -eq 1 ]

step "sweeps"
$RAYLAB bench --scene "$SWEEP_SCENE" --accel grid,hashgrid,grid2 --sweep density=0.0625,0.125,0.25,0.5,1,2,4,8 \
  "${SWEEP_ARGS[@]}" --json "$OUT/sweep_grid_density.json" > "$OUT/sweep_grid_density.txt"
$RAYLAB bench --scene "$SWEEP_SCENE" --accel kdtree --sweep ct=1,2.5,5,10,15,20,40,80 \
  "${SWEEP_ARGS[@]}" --json "$OUT/sweep_kdtree_ct.json" > "$OUT/sweep_kdtree_ct.txt"
$RAYLAB bench --scene "$SWEEP_SCENE" --accel bvh:layout=bvh2,bvh --sweep leaf=1,2,4,8,16,32 \
  "${SWEEP_ARGS[@]}" --json "$OUT/sweep_bvh_leaf.json" > "$OUT/sweep_bvh_leaf.txt"

step "scaling ($SCALE)"
$RAYLAB bench --scale "$SCALE" --accel "$SCALE_ACCELS" "${SCALE_ARGS[@]}" \
  --json "$OUT/scaling.json" > "$OUT/scaling.txt"

step "equal-time renders ($RENDER_SCENE $RENDER_SIZE)"
ET="$OUT/equal_time"
rm -f "$ET"/*.json "$ET"/*.pfm
$RAYLAB render --scene "$RENDER_SCENE" --accel embree --size $RENDER_SIZE --spp $REF_SPP --seed 12345 --quiet \
  --out "$ET/reference.pfm" --json "$ET/reference.json" > /dev/null
for accel in embree bvh kdtree grid hashgrid grid2; do
  for spp in $RENDER_SPPS; do
    $RAYLAB render --scene "$RENDER_SCENE" --accel $accel --size $RENDER_SIZE --spp $spp --seed 1 --quiet --threads 1 \
      --out "$ET/${accel}_spp$spp.pfm" --json "$ET/${accel}_spp$spp.json" > /dev/null
  done
done

step "charts"
$PY bench/plot.py --dir "$OUT" --out "$OUT/charts" --table "$OUT/summary.md"
if [ "$PRESET" = quick ]; then
  mkdir -p docs/charts
  cp "$OUT"/charts/*.png docs/charts/
fi
step "done"
