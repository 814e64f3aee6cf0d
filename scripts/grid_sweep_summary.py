#!/usr/bin/env python3
"""Summarises the JSON reports written by scripts/grid_sweep.sh (one
directory). Every figure is the median over the passes (independent bench
runs); the ratio to Embree is taken per pass (Embree timed back to back with
the grid in the same process) before the median.

Tables: the density sweep per scene and ray set (build ms, bytes, cells,
occupied cells, cell-storage bytes per occupied cell -- bytes without the
36-byte copy of each triangle every grid holds --, Mrays/s, Embree Mrays/s,
ratio, cells and triangle tests per ray); the best density per scene, kind
and ray set against the rule's density 1; the teapot-in-a-stadium runs; the
memory of grid and hashgrid at large densities."""
import glob
import json
import os
import re
import statistics
import sys
from collections import defaultdict


def kind_and_density(spec):
    m = re.match(r"([a-z0-9]+)(?::(.*))?$", spec)
    params = dict(p.split("=", 1) for p in (m.group(2) or "").split(",") if p)
    return m.group(1), float(params.get("density", "1"))


def load(pattern):
    groups = defaultdict(list)  # (scene, ray_set, accel) -> records of all passes
    for path in sorted(glob.glob(pattern)):
        for r in json.load(open(path))["records"]:
            if not r["accel"].startswith("embree"):
                groups[(os.path.basename(r["scene"]), r["ray_set"], r["accel"])].append(r)
    return groups


def med(recs, key):
    return statistics.median(r[key] for r in recs)


def table(groups, title_extra=""):
    by_set = defaultdict(list)
    for (scene, ray_set, accel), recs in groups.items():
        by_set[(scene, ray_set)].append((accel, recs))
    best = []
    for (scene, ray_set), items in by_set.items():
        n = items[0][1][0]["triangles"]
        passes = len(items[0][1])
        print(f"\n### {scene} ({n} triangles), {ray_set} rays{title_extra} -- median of {passes} run(s)\n")
        print("| accel | build ms | bytes | cells | occupied | cell bytes / occupied | Mrays/s | Embree Mrays/s | ratio | cells/ray | tris/ray |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        by_kind = defaultdict(dict)
        for accel, recs in items:
            kind, density = kind_and_density(accel)
            ratio = med(recs, "ratio_to_embree")
            by_kind[kind][density] = ratio
            occ = recs[0]["leaves"]
            cell_bytes = recs[0]["bytes"] - 36 * recs[0]["triangles"]
            print(f"| {accel} | {med(recs, 'build_ms'):.1f} | {recs[0]['bytes']} | {recs[0]['nodes']} | {occ} | "
                  f"{cell_bytes / occ if occ else 0:.1f} | {med(recs, 'mrays_per_s'):.4g} | "
                  f"{med(recs, 'embree_mrays_per_s'):.4g} | {ratio:.4g} | {med(recs, 'nodes_per_ray'):.1f} | "
                  f"{med(recs, 'tris_per_ray'):.1f} |")
        for kind, d in by_kind.items():
            if 1.0 in d and len(d) > 1:
                b = max(d, key=d.get)
                best.append(f"| {scene} | {ray_set} | {kind} | {b:g} | {d[b]:.3f} | {d[1.0]:.3f} | {d[b] / d[1.0]:.2f}x |")
    return best


def main(out):
    best = table(load(os.path.join(out, "sweep_*.json")))
    if best:
        print("\n### Best density per scene (median ratio to Embree) against the rule's density 1\n")
        print("| scene | rays | kind | best density | ratio at best | ratio at 1 | best / rule |")
        print("|---|---|---|---:|---:|---:|---:|")
        for line in best:
            print(line)
    for name, what in (("dragon_default_*.json", ", default view"), ("dragon_view_*.json", ", view of the dragon"),
                       ("memory.json", ", memory at large density")):
        groups = load(os.path.join(out, name))
        if groups:
            table(groups, what)


if __name__ == "__main__":
    main(sys.argv[1])
