#!/usr/bin/python3
"""Analyses one run of the study (workflow/study.smk): Havran's counts, the time model, the
verdicts, the failure map and speed against accuracy, written to one JSON with its charts.

  analyse.py --suite S.json --bench bench.json --stress stress.json --verify V.json... \\
             --out analysis.json --charts DIR
"""
import argparse
import json
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import accuracy  # noqa: E402
import charts  # noqa: E402
import time_model  # noqa: E402
import verdicts  # noqa: E402
from records import Study, geomean, is_embree  # noqa: E402

COUNTERS = ("steps_per_ray", "leaves_per_ray", "empty_leaves_per_ray", "tris_per_ray")


def counts_table(study, specs):
    """Per structure: median over every cell (scene x ray set) of each counter; null for Embree."""
    out = {}
    for a in specs:
        rows = [r for r in study.records if r["accel"] == a]
        if not rows:
            continue
        entry = {"cells": len(rows)}
        for k in COUNTERS:
            vals = [r[k] for r in rows if r.get(k) is not None]
            entry[k] = statistics.median(vals) if vals else None
        out[a] = entry
    return out


def models_of(study, specs):
    out = {}
    for a in specs:
        rows = [r for r in study.records if r["accel"] == a and r.get("steps_per_ray") is not None]
        if len(rows) >= 3:
            out[a] = time_model.fit_records(rows)
    return out


def cost_points(study, specs):
    """Per structure and ray set: geometric mean steps and ns per ray over the scenes."""
    out = []
    for a in specs:
        for rs in study.ray_sets():
            rows = [r for r in study.records if r["accel"] == a and r["ray_set"] == rs and r.get("steps_per_ray")]
            if rows:
                out.append({"accel": a, "ray_set": rs, "steps": geomean([r["steps_per_ray"] for r in rows]),
                            "ns": geomean([r["ns_per_ray"] for r in rows]), "scenes": len(rows)})
    return out


def suite_table(study):
    tris = {}
    for r in study.records:
        tris[r["name"]] = r["triangles"]
    out = []
    for name, s in study.suite["scenes"].items():
        status = "run" if name in tris else (f"skipped: {s['missing']}" if s.get("missing") else "no records")
        out.append({"scene": name, "spec": s["spec"], "classes": s["classes"], "triangles": tris.get(name),
                    "status": status})
    return out


def job_times(paths):
    """Wall seconds of the study's jobs (Snakemake's benchmark files): their sum is the study's
    wall time when the jobs ran one after another (each claims every core). (Their CPU column
    is sampled and misses short-lived children, so it is not used.)"""
    wall = 0.0
    for p in paths:
        with open(p) as f:
            lines = f.read().splitlines()
        if len(lines) < 2:
            continue
        row = dict(zip(lines[0].split("\t"), lines[-1].split("\t")))
        wall += float(row.get("s", 0) or 0)
    return {"jobs": len(paths), "wall_s": wall}


def analyse(study, charts_dir):
    accels = study.default_accels() or sorted({r["accel"] for r in study.records})
    specs = accels + [v for v in study.variants() if v not in accels]
    counted = [a for a in specs if not is_embree(a)]
    models = models_of(study, counted)
    all_names = study.scenes_run()
    for a, m in models.items():
        if a != "bvh":
            m["vs_bvh"] = verdicts.explain(study, models, a, "bvh", all_names)
    b = verdicts.bes(study, accels, models)
    result = {
        "tag": study.suite.get("tag"), "preset": study.suite.get("preset"), "isa": study.isa,
        "machine": study.machine, "accels": accels, "variants": study.variants(), "ray_sets": study.ray_sets(),
        "classes": study.classes(), "suite": suite_table(study),
        "counts": counts_table(study, counted), "models": models,
        "cost_points": cost_points(study, counted),
        "per_scene": verdicts.per_scene(study, accels), "per_class": verdicts.per_class(study, accels),
        "bes": b, "bes_sentence": verdicts.bes_sentence(b, study.isa),
        "failures": verdicts.failure_map(study, models),
        "accuracy": accuracy.points(study, ["embree"] + [a for a in specs if a != "embree"]),
        "overall": {a: geomean([r["ratio_to_embree"] for r in study.records if r["accel"] == a]) for a in specs},
        # Every cell's speed, so that runs of other ISAs are compared on the cells both ran.
        "cells": [[r["name"], r["accel"], r["ray_set"], r["ratio_to_embree"]] for r in study.records],
        "charts": {},
    }
    os.makedirs(charts_dir, exist_ok=True)
    isa = study.isa
    c = result["charts"]
    c["time_model"] = "time_model.png"
    charts.steps_vs_cost(result["cost_points"], counted, isa, os.path.join(charts_dir, c["time_model"]))
    fit_cells = [{"accel": r["accel"], "ns": r["ns_per_ray"],
                  "predicted": time_model.predict(models[r["accel"]], r["steps_per_ray"], r["tris_per_ray"])}
                 for r in study.records if r["accel"] in models and r.get("steps_per_ray") is not None]
    c["model_fit"] = "model_fit.png"
    charts.model_fit(fit_cells, counted, isa, os.path.join(charts_dir, c["model_fit"]))
    table = {v["class"]: v["means"] for v in result["per_class"]}
    c["per_class"] = "per_class.png"
    charts.per_class(table, [v["class"] for v in result["per_class"]], accels, isa,
                     os.path.join(charts_dir, c["per_class"]))
    c["speed_vs_accuracy"] = "speed_vs_accuracy.png"
    charts.speed_vs_accuracy(result["accuracy"], isa, os.path.join(charts_dir, c["speed_vs_accuracy"]))
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", required=True)
    ap.add_argument("--bench", required=True)
    ap.add_argument("--stress")
    ap.add_argument("--verify", nargs="*", default=[])
    ap.add_argument("--jobs", nargs="*", default=[], help="Snakemake benchmark files of the study's jobs")
    ap.add_argument("--out", required=True)
    ap.add_argument("--charts", required=True)
    a = ap.parse_args()
    for p in [a.suite, a.bench] + ([a.stress] if a.stress else []) + a.verify:
        if not os.path.isfile(p):
            print(f"analyse: {p}: no such file", file=sys.stderr)
            return 2
    study = Study.from_files(a.suite, a.bench, a.verify, a.stress)
    if not study.records:
        print(f"analyse: {a.bench}: no one-thread records of the suite's scenes", file=sys.stderr)
        return 2
    result = analyse(study, a.charts)
    result["jobs"] = job_times(a.jobs)
    tmp = a.out + ".tmp"
    with open(tmp, "w") as f:
        json.dump(result, f, indent=1)
    os.replace(tmp, a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
