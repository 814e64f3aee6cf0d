#!/usr/bin/python3
"""Writes copies of a scene file with seeded random cameras, to check that a
measurement on one view holds on others (camera rays of one view are a narrow
bundle: a tree decision can suit one view and not the next).

  /usr/bin/python3 scripts/random_views.py scenes/shared/sponza.json OUT/sponza \
      --box=-12,1,-4.5,12,8,4.5 --count 10 --seed 7
  /usr/bin/python3 scripts/random_views.py scenes/shared/dragon_in_sponza.json OUT/dragon \
      --around=0,0.1,0 --distance 0.1,1.5 --count 5 --seed 11

--box: cameras at uniform points of the box, each looking at another one.
--around: cameras at uniform distances in the range from the point (uniform
azimuth, height up to half the distance above it), looking at the point.
Writes OUT_v0.json .. OUT_v{count-1}.json; mesh paths are made absolute, so
the files work from anywhere. Exits 2 on a usage error, 1 on bad values or an
unreadable scene.
"""
import argparse
import json
import math
import os
import random
import sys


def floats(text, n, what):
    try:
        v = [float(x) for x in text.split(",")]
    except ValueError:
        v = []
    if len(v) != n or not all(math.isfinite(x) for x in v):
        raise SystemExit(f"random_views: {what} needs {n} comma-separated numbers, got '{text}'")
    return v


def main():
    ap = argparse.ArgumentParser(description="scene copies with seeded random cameras")
    ap.add_argument("scene")
    ap.add_argument("out", help="output prefix: OUT_v0.json ...")
    ap.add_argument("--box", help="lo_x,lo_y,lo_z,hi_x,hi_y,hi_z")
    ap.add_argument("--around", help="x,y,z")
    ap.add_argument("--distance", default="1,2", help="min,max (with --around)")
    ap.add_argument("--count", type=int, default=10)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    if (a.box is None) == (a.around is None):
        ap.error("give exactly one of --box and --around")
    if a.count < 1:
        ap.error("--count must be at least 1")
    try:
        with open(a.scene) as f:
            base = json.load(f)
    except (OSError, ValueError) as e:
        raise SystemExit(f"random_views: cannot read {a.scene}: {e}") from None
    if not isinstance(base, dict) or not isinstance(base.get("camera"), dict):
        raise SystemExit(f"random_views: {a.scene} has no camera object")
    here = os.path.dirname(os.path.abspath(a.scene))
    for m in base.get("meshes", []):
        if isinstance(m, dict) and "file" in m and not os.path.isabs(m["file"]):
            m["file"] = os.path.normpath(os.path.join(here, m["file"]))
    base.pop("comment", None)
    rng = random.Random(a.seed)
    if a.box:
        b = floats(a.box, 6, "--box")
        lo, hi = b[:3], b[3:]
        if any(l > h for l, h in zip(lo, hi)):
            raise SystemExit("random_views: --box low corner above high corner")
    else:
        c = floats(a.around, 3, "--around")
        d0, d1 = floats(a.distance, 2, "--distance")
        if not 0 < d0 <= d1:
            raise SystemExit("random_views: --distance needs 0 < min <= max")
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    for i in range(a.count):
        if a.box:
            frm = [rng.uniform(lo[k], hi[k]) for k in range(3)]
            at = [rng.uniform(lo[k], hi[k]) for k in range(3)]
        else:
            d = rng.uniform(d0, d1)
            phi = rng.uniform(0.0, 2.0 * math.pi)
            frm = [c[0] + d * math.cos(phi), c[1] + rng.uniform(0.0, 0.5) * d, c[2] + d * math.sin(phi)]
            at = list(c)
        base["camera"]["from"], base["camera"]["at"] = frm, at
        with open(f"{a.out}_v{i}.json", "w") as f:
            json.dump(base, f, indent=1)
    print(f"wrote {a.count} views: {a.out}_v0.json .. {a.out}_v{a.count - 1}.json")


if __name__ == "__main__":
    sys.exit(main())
