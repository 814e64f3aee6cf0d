#!/usr/bin/env python3
"""Summarises `raylab bench --sweep density=...` JSON reports of the grids:
one table per scene and ray set (build ms, bytes, cells, occupied cells,
bytes of the cell storage, i.e. without the 36-byte copy of each triangle
that every grid holds, per occupied cell, Mrays/s, ratio to Embree), then
the best density per scene, grid kind and ray set next to the rule's
density 1."""
import json
import re
import sys
from collections import defaultdict


def kind_and_density(spec):
    m = re.match(r"([a-z0-9]+)(?::(.*))?$", spec)
    params = dict(p.split("=", 1) for p in (m.group(2) or "").split(",") if p)
    return m.group(1), float(params.get("density", "1"))


def main(paths):
    rows = defaultdict(list)  # (scene, ray_set) -> records
    for path in paths:
        for r in json.load(open(path))["records"]:
            if r["accel"].startswith("embree"):
                continue
            rows[(r["scene"], r["ray_set"])].append(r)
    best_lines = []
    for (scene, ray_set), recs in rows.items():
        print(f"\n### {scene} ({recs[0]['triangles']} triangles), {ray_set} rays\n")
        print("| accel | build ms | bytes | cells | occupied | cell bytes / occupied | Mrays/s | Embree Mrays/s | ratio | cells/ray | tris/ray |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        by_kind = defaultdict(dict)
        for r in recs:
            kind, density = kind_and_density(r["accel"])
            by_kind[kind][density] = r
            occ = r["leaves"]
            print(f"| {r['accel']} | {r['build_ms']:.1f} | {r['bytes']} | {r['nodes']} | {occ} | "
                  f"{(r['bytes'] - 36 * r['triangles']) / occ if occ else 0:.1f} | {r['mrays_per_s']:.3f} | {r['embree_mrays_per_s']:.3f} | "
                  f"{r['ratio_to_embree']:.3f} | {r['nodes_per_ray']:.1f} | {r['tris_per_ray']:.1f} |")
        for kind, d in by_kind.items():
            best = max(d, key=lambda k: d[k]["ratio_to_embree"])
            one = d.get(1.0)
            if one is None:
                continue
            best_lines.append(
                f"| {scene} | {ray_set} | {kind} | {best:g} | {d[best]['ratio_to_embree']:.3f} | "
                f"{one['ratio_to_embree']:.3f} | {d[best]['ratio_to_embree'] / one['ratio_to_embree']:.2f}x |")
    print("\n### Best density per scene (by ratio to Embree) against the rule's density 1\n")
    print("| scene | rays | kind | best density | ratio at best | ratio at 1 | best / rule |")
    print("|---|---|---|---:|---:|---:|---:|")
    for line in best_lines:
        print(line)


if __name__ == "__main__":
    main(sys.argv[1:])
