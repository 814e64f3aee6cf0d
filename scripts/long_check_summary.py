#!/usr/bin/python3
"""The long correctness check's records (scripts/long-check.sh) as one CSV row per record and a
table per structure: rays, raylab wrong, Embree wrong, ties, leaks (docs/method.md, "The long check").

  scripts/long_check_summary.py out/long-check --csv out/long-check/summary.csv --md out/long-check/summary.md
  scripts/long_check_summary.py --from-csv docs/correctness.csv --md table.md   # the table from the CSV alone
"""
import argparse
import csv
import glob
import json
import os
import sys

COLUMNS = ["check", "scene", "ray_set", "accel", "rays", "hit_miss_disagree", "prim_disagree", "ties",
           "raylab_wrong", "embree_wrong", "occlusion_disagree", "leak_rays", "leaks", "status",
           "revision", "date", "cpu", "threads", "kernel_isa", "embree", "compiler"]


def report_provenance(report):
    """The columns every row of a report shares: the binary's revision, when and where it ran."""
    return {"revision": report.get("revision", ""), "date": report.get("date", ""), "cpu": report.get("cpu", ""),
            "threads": report.get("hardware_threads", ""), "kernel_isa": report.get("bvh_isa", ""),
            "embree": report.get("embree", ""), "compiler": report.get("compiler", "")}


def rows_from_records(out):
    """One row per record of OUT/verify/*/*.json and OUT/stress/*.json; skipped structures as
    rows with status 'skipped' and no rays."""
    rows = []
    for path in sorted(glob.glob(os.path.join(out, "verify", "*", "*.json")) +
                       glob.glob(os.path.join(out, "stress", "*.json"))):
        with open(path) as f:
            report = json.load(f)
        check = "verify" if os.sep + "verify" + os.sep in path else "stress"
        prov = report_provenance(report)
        for r in report.get("records", []):
            if check == "stress" and not r.get("counts_for_exit", True):
                continue  # Embree's and the tri=mt rows: shown by raylab stress, not structures under check
            rows.append({"check": check, "scene": r["scene"], "ray_set": r["ray_set"], "accel": r["accel"],
                         "rays": r["rays"], "hit_miss_disagree": r["hit_miss_disagree"],
                         "prim_disagree": r["prim_disagree"], "ties": r["ties"], "raylab_wrong": r["raylab_wrong"],
                         "embree_wrong": r["embree_wrong"], "occlusion_disagree": r["occlusion_disagree"],
                         "leak_rays": r.get("leak_rays", 0), "leaks": r.get("leaks", 0),
                         "status": r.get("status", "ok" if r.get("ok", True) else "wrong"), **prov})
        for s in report.get("skipped", []):
            rows.append({"check": check, "scene": s["scene"], "ray_set": "", "accel": s["accel"], "rays": 0,
                         "hit_miss_disagree": 0, "prim_disagree": 0, "ties": 0, "raylab_wrong": 0,
                         "embree_wrong": 0, "occlusion_disagree": 0, "leak_rays": 0, "leaks": 0,
                         "status": "skipped: " + s["reason"], **prov})
    return rows


def per_structure(rows):
    table = {}
    for r in rows:
        t = table.setdefault(r["accel"], {"verify_rays": 0, "stress_rays": 0, "raylab_wrong": 0, "embree_wrong": 0,
                                          "ties": 0, "occlusion_disagree": 0, "leak_rays": 0, "leaks": 0,
                                          "skipped": 0, "scenes": set()})
        if r["status"].startswith("skipped"):
            t["skipped"] += 1
            continue
        t[r["check"] + "_rays"] += int(r["rays"])
        for k in ("raylab_wrong", "embree_wrong", "ties", "occlusion_disagree", "leak_rays", "leaks"):
            t[k] += int(r[k])
        if r["check"] == "verify":
            t["scenes"].add(r["scene"])
    return table


def markdown(table):
    lines = ["| structure | rays (verify + stress) | scenes | raylab wrong | Embree wrong | ties | any-hit vs closest | leaks (leak rays) |",
             "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for accel in sorted(table, key=lambda a: (a.split(":")[0], a)):
        t = table[accel]
        rays = t["verify_rays"] + t["stress_rays"]
        skipped = f" ({t['skipped']} skipped)" if t["skipped"] else ""
        lines.append(f"| `{accel}` | {rays:,} ({t['verify_rays']:,} + {t['stress_rays']:,}) | {len(t['scenes'])}{skipped} | "
                     f"{t['raylab_wrong']} | {t['embree_wrong']} | {t['ties']:,} | {t['occlusion_disagree']} | "
                     f"{t['leaks']} ({t['leak_rays']:,}) |")
    return "\n".join(lines) + "\n"


def provenance(rows):
    """One line naming where and when the rows were produced: machine, ISA, compiler, revisions, dates."""
    def values(key):
        return sorted({str(r.get(key, "")) for r in rows if r.get(key)})
    dates = sorted(d[:10] for d in values("date"))
    when = dates[0] if dates and dates[0] == dates[-1] else (f"{dates[0]} to {dates[-1]}" if dates else "unknown dates")
    revs = values("revision")
    return (f"Long check: {', '.join(values('cpu')) or 'unknown CPU'} ({', '.join(values('threads')) or '?'} hardware "
            f"threads), kernels {', '.join(values('kernel_isa')).upper() or '?'}, Embree {', '.join(values('embree')) or '?'}, "
            f"{', '.join(values('compiler')) or 'unknown compiler'}, revision{'s' if len(revs) > 1 else ''} "
            f"{', '.join(revs) or 'unknown'}, {when}; `scripts/long-check.sh` (docs/method.md).")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", nargs="?", help="the long check's output directory")
    ap.add_argument("--from-csv", help="read the rows from this CSV instead of the records")
    ap.add_argument("--csv", help="write one row per record here")
    ap.add_argument("--md", help="write the per-structure table here (default: stdout)")
    a = ap.parse_args()
    if bool(a.out) == bool(a.from_csv):
        ap.error("give the output directory or --from-csv")
    if a.from_csv:
        with open(a.from_csv) as f:
            rows = list(csv.DictReader(f))
    else:
        rows = rows_from_records(a.out)
    if not rows:
        print(f"long_check_summary: no records in {a.out or a.from_csv}", file=sys.stderr)
        return 2
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=COLUMNS)
            w.writeheader()
            w.writerows(rows)
    text = markdown(per_structure(rows))
    if a.md:
        with open(a.md, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
