#!/usr/bin/env bash
# The long correctness check (docs/method.md): every registered structure's default and
# its scalar variant (simd=0 where it has one) judged by the exact oracle on at least 10^7
# rays each, with raylab verify (camera, diffuse, shadow and random rays over the interior
# views of scenes/shared, the Cornell box far from the origin, the needles and two scanned
# meshes) and raylab stress (the watertight scenarios for leaks, the far-from-origin,
# needle and ray corner-case scenarios). Not part of CI: several hours on 2 cores.
#
#   scripts/long-check.sh [OUT]        # default out/long-check; run from the checkout
#   RAYS=1000 scripts/long-check.sh out/long-check-small   # a small run, to time it
#
# Every cell (scene x structure for verify, scenario for stress) writes its own record,
# OUT/verify/<scene>/<spec>.json and OUT/stress/<scenario>.json; a cell whose record exists
# is skipped, so an interrupted run continues where it stopped. The binary is copied to
# OUT/raylab at the first run: rebuilding the tree meanwhile does not mix revisions (delete
# OUT/raylab, or OUT, to check a new one). At the end scripts/long_check_summary.py writes
# OUT/summary.csv and OUT/summary.md (rays, raylab wrong, Embree wrong, ties, leaks per
# structure).
#
# Environment: BUILD (default build), RAYS (rays per ray set and scene, default 300000),
# STRESS_SCALE (raylab stress --ray-scale, default 8), NICE (default 5), BRUTE_MAX_TRIS
# (brute force only on scenes up to this size, default 10000; its cells get 3x RAYS).
set -euo pipefail

OUT=${1:-out/long-check}
BUILD=${BUILD:-build}
RAYS=${RAYS:-300000}
STRESS_SCALE=${STRESS_SCALE:-8}
NICE=${NICE:-5}
BRUTE_MAX_TRIS=${BRUTE_MAX_TRIS:-10000}
PY=/usr/bin/python3

mkdir -p "$OUT/verify" "$OUT/stress"
if [ ! -x "$OUT/raylab" ]; then
  [ -x "$BUILD/raylab" ] || { echo "long-check: no $BUILD/raylab (make build first)" >&2; exit 2; }
  cp "$BUILD/raylab" "$OUT/raylab"
fi
R="$OUT/raylab"
run() { nice -n "$NICE" "$@"; }

# Every registered structure but the reference, and its scalar variant, from the registry.
mapfile -t SPECS < <("$R" accels --json | "$PY" -c '
import json, sys
for a in json.load(sys.stdin):
    if a["capabilities"]["reference"]:
        continue
    print(a["name"])
    if a["capabilities"].get("scalar_variant"):
        print(a["name"] + ":" + a["capabilities"]["scalar_variant"])')

SCENES=(scenes/checks/cornell_far_1e5.json scenes/checks/cornell_far_1e7.json needles)
if [ -d ../shared/scenes ]; then
  for f in scenes/shared/*.json; do SCENES+=("$f"); done
  SCENES+=(../shared/scenes/bunny.ply ../shared/scenes/dragon_res2.ply)
else
  echo "long-check: ../shared/scenes is absent: the interior views and scanned meshes are left out" >&2
fi

slug() { echo "$1" | sed -e 's/=//g' -e 's/[^A-Za-z0-9.]\{1,\}/-/g' -e 's/^-//' -e 's/-$//'; }
triangles() { "$R" info "$1" | awk '/^triangles/ {print $2}'; }

start=$(date +%s)
echo "long-check: ${#SPECS[@]} structures x ${#SCENES[@]} scenes, $RAYS rays per set; records in $OUT"

# verify: one cell per scene x structure.
for scene in "${SCENES[@]}"; do
  dir="$OUT/verify/$(slug "$(basename "$scene")")"
  mkdir -p "$dir"
  tris=$(triangles "$scene")
  for spec in "${SPECS[@]}"; do
    cell="$dir/$(slug "$spec")"
    [ -f "$cell.json" ] && continue
    rays=$RAYS
    if [ "${spec%%:*}" = brute ]; then
      [ "$tris" -le "$BRUTE_MAX_TRIS" ] || continue
      rays=$((3 * RAYS))
    fi
    t0=$(date +%s)
    rc=0
    run "$R" verify "$scene" --accel "$spec" --ray-sets primary,diffuse,shadow,random --rays "$rays" \
      --judge-ties -q -o "$cell.json.part" > "$cell.txt" 2>&1 || rc=$?
    # 0: agreed; 1: a wrong answer (the record says which); 2 with a record: a structure left
    # out (memory, or its build failed on this scene). Anything else keeps no record.
    if [ -f "$cell.json.part" ] && { [ $rc -le 1 ] || [ $rc -eq 2 ]; }; then
      mv "$cell.json.part" "$cell.json"
    fi
    echo "verify $scene $spec: exit $rc, $(( $(date +%s) - t0 )) s"
  done
done

# stress: one cell per scenario, every structure in one process (the oracle's answers for
# the leak rays are computed once per scenario).
spec_list=$(IFS=,; echo "${SPECS[*]}")
for scenario in watertight_sphere watertight_box watertight_torus watertight_far far_1e5 far_1e7 slivers rays; do
  cell="$OUT/stress/$scenario"
  [ -f "$cell.json" ] && continue
  t0=$(date +%s)
  rc=0
  run "$R" stress "$scenario" --accel "$spec_list" --ray-scale "$STRESS_SCALE" --budget 3600 -q \
    -o "$cell.json.part" > "$cell.txt" 2>&1 || rc=$?
  if [ -f "$cell.json.part" ] && [ $rc -le 2 ]; then mv "$cell.json.part" "$cell.json"; fi
  echo "stress $scenario: exit $rc, $(( $(date +%s) - t0 )) s"
done

"$PY" scripts/long_check_summary.py "$OUT" --csv "$OUT/summary.csv" --md "$OUT/summary.md"
echo "long-check: $(( ($(date +%s) - start) / 60 )) min this run; summary in $OUT/summary.md"
