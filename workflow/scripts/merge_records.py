#!/usr/bin/python3
"""Merges per-cell `raylab bench` reports into one, as a single run over the whole matrix writes it.

  merge_records.py --out OUT.json [--preset NAME] CELL.json...

Each CELL.json is a `raylab bench -o` report (header fields, "options", "records", and
"skipped" when a structure did not fit), with its CSV next to it (CELL.csv). OUT.json gets the
first cell's header (machine, Embree, revision), the union of the cells' options, "complete" only
if every cell completed, the records in the order one run writes them (scene, accelerator,
ray set, thread count) and every cell's skips; OUT.csv the matching CSV rows, copied from the
cells' CSVs as raylab wrote them (so the columns follow raylab's, whatever they are). When the
records carry best-Embree figures (ratio_to_best_embree), they are recomputed over all cells,
since a cell only sees the Embree modes it ran. "merged_from" lists the cell files (relative to
OUT.json), so `raylab report`, which reads a folder recursively, skips them.
"""
import argparse
import csv
import io
import json
import os
import sys


def csv_path(json_path):
    root, _ = os.path.splitext(json_path)
    return root + ".csv"


def first_seen(values):
    order = {}
    for v in values:
        order.setdefault(v, len(order))
    return order


def union(lists):
    out = []
    for values in lists:
        for v in values:
            if v not in out:
                out.append(v)
    return out


def is_embree_spec(spec):
    return spec == "embree" or spec.startswith("embree:")


def refill_best_embree(records):
    """ratio_to_best_embree as one run computes it: per scene, ray set and thread count the fastest
    Embree mode (the reference `embree` counts with ratio 1), over every cell's records; each
    cell's ratios are to the Embree reference timed back to back in that cell."""
    best = {}
    for r in records:
        key = (r["scene"], r["ray_set"], r["threads"])
        if key not in best:
            best[key] = (1.0, "embree", r["embree_mrays_per_s"])
        if is_embree_spec(r["accel"]) and r["ratio_to_embree"] > best[key][0]:
            best[key] = (r["ratio_to_embree"], r["accel"], r["mrays_per_s"])
    for r in records:
        ratio, spec, mrays = best[(r["scene"], r["ray_set"], r["threads"])]
        r["best_embree"] = spec
        r["best_embree_mrays_per_s"] = mrays
        r["ratio_to_best_embree"] = r["ratio_to_embree"] / ratio if ratio > 0 else 0.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="merged JSON (the CSV goes next to it)")
    ap.add_argument("--preset", help="recorded as the merged report's preset")
    ap.add_argument("cells", nargs="+")
    a = ap.parse_args()

    reports, rows, header_row = [], [], None
    for path in a.cells:
        with open(path) as f:
            report = json.load(f)
        if report.get("command") != "bench" or "records" not in report:
            sys.exit(f"merge_records: {path}: not a `raylab bench` report")
        with open(csv_path(path), newline="") as f:
            table = list(csv.reader(f))
        if not table:
            sys.exit(f"merge_records: {csv_path(path)}: empty CSV")
        if header_row is None:
            header_row = table[0]
        elif table[0] != header_row:
            sys.exit(f"merge_records: {csv_path(path)}: columns differ from {csv_path(a.cells[0])}")
        if len(table) - 1 != len(report["records"]):
            sys.exit(f"merge_records: {path}: {len(report['records'])} records but {len(table) - 1} CSV rows")
        reports.append(report)
        rows.extend(table[1:])

    records = [r for rep in reports for r in rep["records"]]
    scene_order = first_seen(r["scene"] for r in records)
    accel_order = first_seen(r["accel"] for r in records)
    options = [rep.get("options", {}) for rep in reports]
    ray_sets = union(o.get("ray_sets", []) for o in options)
    set_order = {s: i for i, s in enumerate(ray_sets)}
    key = lambda i: (scene_order[records[i]["scene"]], accel_order[records[i]["accel"]],
                     set_order.get(records[i]["ray_set"], len(set_order)), records[i]["threads"])
    order = sorted(range(len(records)), key=key)

    merged = {k: v for k, v in reports[0].items() if k not in ("records", "skipped", "options", "complete")}
    if a.preset:
        merged["preset"] = a.preset
    merged_options = dict(options[0])
    for name in ("scenes", "accels", "ray_sets", "threads"):
        merged_options[name] = union(o.get(name, []) for o in options)
    merged["options"] = merged_options
    merged["complete"] = all(rep.get("complete", False) for rep in reports)
    merged["cells"] = len(reports)
    # The cell files this report holds, relative to it: `raylab report` reads a folder
    # recursively and must not count their records twice.
    out_dir = os.path.dirname(os.path.abspath(a.out))
    merged["merged_from"] = [os.path.relpath(os.path.abspath(p), out_dir) for p in a.cells]
    merged["skipped"] = [s for rep in reports for s in rep.get("skipped", [])]
    merged["records"] = [records[i] for i in order]
    if merged["records"] and "ratio_to_best_embree" in merged["records"][0]:
        refill_best_embree(merged["records"])
        for name in ("best_embree", "ratio_to_best_embree"):
            if name in header_row:
                col = header_row.index(name)
                for i in order:
                    v = records[i][name]
                    rows[i][col] = v if isinstance(v, str) else format(v, ".9g")

    tmp = a.out + ".tmp"
    with open(tmp, "w") as f:
        json.dump(merged, f, indent=2)
        f.write("\n")
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow(header_row)
    for i in order:
        w.writerow(rows[i])
    with open(csv_path(a.out) + ".tmp", "w", newline="") as f:
        f.write(text.getvalue())
    os.replace(csv_path(a.out) + ".tmp", csv_path(a.out))
    os.replace(tmp, a.out)


if __name__ == "__main__":
    main()
