#!/usr/bin/python3
"""Writes the study's results page (Markdown) from the analyses of one or more ISAs.

  page.py --out out/study/results.md out/study/native/analysis.json [other ISA's analysis.json...]
  page.py --out docs/results.md --assets docs/results_files/study out/study/*/analysis.json   (make docs)
  ... --long-check docs/correctness.csv    adds the long check's table (scripts/long-check.sh)

The first analysis tagged `native` (else the first given) is the page's answer; every other one
gets a section comparing its ISA. Charts are linked where the analyses keep them, or copied
under --assets and linked there. The headline (BES verdict, per-class table, provenance) sits
between <!-- headline:begin --> and <!-- headline:end --> for scripts/update-readme-results.py.
"""
import argparse
import json
import os
import shutil
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# scripts/long_check_summary.py: the long check's table (--long-check).
sys.path.insert(1, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))

from records import geomean  # noqa: E402

COMMAND = "make study && make docs"


def fmt_ratio(x):
    if x is None:
        return "n/a"
    return f"{x:.2f}" if x >= 0.095 else f"{x:.3f}" if x >= 0.001 else f"{x:.1e}"


def fmt_count(x):
    if x is None:
        return "n/a"
    return f"{x:,.0f}" if x >= 100 else f"{x:.1f}" if x >= 10 else f"{x:.2f}"


def fmt_margin(v):
    if v.get("margin") is None:
        return "n/a"
    s = f"+{100 * v['margin']:.0f} %"
    return s + " (inside the noise)" if v["within_noise"] else s


def isa_text(a):
    return f"kernels {a['isa']['kernels']}, Embree {a['isa']['embree']}"


def provenance(a):
    m = a["machine"]
    jobs = a.get("jobs") or {}
    when = (m.get("date") or "")[:10]
    t = (f"Machine: {m.get('cpu')} ({m.get('hardware_threads')} hardware threads, shared with other builds: timings "
         f"are noisy, ratios are to Embree timed in alternation in the same process). ISA: {isa_text(a)}. "
         f"Embree {m.get('embree')}. Compiler: {m.get('compiler')}; flags: {m.get('flags')}. Binary revision: "
         f"{m.get('revision')}. Run: {m.get('date')}, study preset {a.get('preset')}, `{COMMAND}`")
    if jobs.get("jobs"):
        t += f"; the study's {jobs['jobs']} timing and checking jobs took {jobs['wall_s'] / 60:.1f} min"
    return t + f" ({when})."


def table(head, rows, align=None):
    align = align or ["---"] * len(head)
    out = ["| " + " | ".join(head) + " |", "|" + "|".join(align) + "|"]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def class_table(a):
    rows = []
    for v in a["per_class"]:
        rows.append([v["class"], len(v["scenes"]), f"`{v['winner']}`", fmt_ratio(v["ratio"]),
                     f"`{v['runner_up']}` {fmt_ratio(v['runner_up_ratio'])}" if v["runner_up"] else "n/a",
                     fmt_margin(v)])
    return table(["class", "scenes", "fastest", "x Embree", "runner-up", "margin"], rows,
                 ["---", "---:", "---", "---:", "---", "---:"])


def link(charts, a, name):
    return charts[a["tag"]] + "/" + a["charts"][name]


def section_suite(a):
    rows = [[f"`{s['scene']}`", ", ".join(s["classes"]), fmt_count(s["triangles"]) if s["triangles"] else "n/a",
             f"`{s['spec']}`", s["status"]] for s in a["suite"]]
    return ("## The scene suite\n\nDeclared once in `workflow/config.yaml` (`study: scenes:`). The SPD scenes are Haines' "
            "Standard Procedural Databases at their default sizes, each with its own view (`NAME_sS.json` beside the "
            "mesh); the interiors are raylab's scene files with their benchmark views; the other meshes use their own "
            "framing. Scenes needing `../shared` are skipped when it is absent.\n\n"
            + table(["scene", "class", "triangles", "spec", "status"], rows, ["---", "---", "---:", "---", "---"]))


def section_per_scene(a):
    sets = a["ray_sets"]
    by = {}
    for v in a["per_scene"]:
        by.setdefault(v["scene"], {})[v["ray_set"]] = v
    rows = []
    classes = {s["scene"]: ", ".join(s["classes"]) for s in a["suite"]}
    for scene, cells in by.items():
        row = [f"`{scene}`", classes.get(scene, "")]
        for rs in sets:
            v = cells.get(rs)
            if not v:
                row.append("n/a")
                continue
            txt = f"**`{v['winner']}`** {fmt_ratio(v['ratio'])}"
            if v["runner_up"]:
                txt += f", {fmt_margin(v)} over `{v['runner_up']}`"
            row.append(txt)
        rows.append(row)
    return (f"## Per scene and ray set: the fastest structure\n\nEvery cell: the fastest structure other than "
            f"Embree, its speed relative to single-ray Embree (median of the repeats, one thread; {isa_text(a)}), "
            f"and its margin over the runner-up. *Inside the noise*: the two structures' ranges over the repeats "
            f"overlap, so this run cannot order them.\n\n"
            + table(["scene", "class"] + sets, rows))


def section_per_class(a, charts):
    accels = list(a["accels"])
    rows = []
    for v in a["per_class"]:
        rows.append([v["class"]] + [fmt_ratio(v["means"].get(x)) if v["means"].get(x) else "n/a" for x in accels])
    return (f"## Per scene class\n\nGeometric mean over the class's scenes and ray sets of each structure's speed "
            f"relative to Embree (one thread; {isa_text(a)}); the verdict takes the fastest and its runner-up, inside "
            f"the noise when the geometric means of their repeat ranges overlap.\n\n" + class_table(a) + "\n\n"
            + f"![speed relative to Embree per class]({link(charts, a, 'per_class')})\n\n"
            + table(["class"] + [f"`{x}`" for x in accels], rows, ["---"] + ["---:"] * len(accels)))


def section_counts(a):
    rows = []
    for x, c in a["counts"].items():
        rows.append([f"`{x}`", fmt_count(c["steps_per_ray"]), fmt_count(c["leaves_per_ray"]),
                     fmt_count(c["empty_leaves_per_ray"]), fmt_count(c["tris_per_ray"]), c["cells"]])
    return ("## Havran's counts per ray\n\nMedian over every cell (scene x ray set) of each per-ray count, with one "
            "definition for every structure ([docs/json-reports.md](json-reports.md#per-ray-counters)): traversal "
            "steps (inner nodes or grid cells visited), leaves visited (leaves or cells whose triangles were "
            "tested), empty leaves (leaves or cells visited that hold no triangle), triangle tests. Embree has no "
            f"counters (its records say null). One thread; {isa_text(a)}.\n\n"
            + table(["structure", "steps", "leaves", "empty leaves", "triangle tests", "cells"], rows,
                    ["---", "---:", "---:", "---:", "---:", "---:"]))


def section_model(a, charts):
    rows = []
    for x, m in a["models"].items():
        v = m.get("vs_bvh")
        why = "(reference)" if x == "bvh" else "n/a"
        if v:
            why = (f"{v['cause']}: visits {v['visits_more']:.2f}x, cost per visit {v['costs_more']:.2f}x "
                   f"(model {v['model_ratio']:.2f}x)")
        rows.append([f"`{x}`", f"{m['a']:.2f}", f"{m['b']:.2f}", f"{m['c']:.1f}", f"{m['r2']:.3f}", m["cells"], why])
    return (f"## Time model: why a structure is fast or slow\n\nPer structure, over every cell of the study: time "
            f"per ray = a x steps + b x triangle tests + c, fitted by non-negative least squares on relative "
            f"residuals (bench/study/time_model.py); a, b, c in ns, R^2 of that fit (one thread; {isa_text(a)}). "
            f"Against `bvh`, the structure's modelled time at its own mean counts over its time at `bvh`'s counts "
            f"says how much it *visits more*; its time at `bvh`'s counts over `bvh`'s says how much *each visit "
            f"costs more*; the larger names the cause.\n\n"
            + table(["structure", "a (ns/step)", "b (ns/test)", "c (ns)", "R^2", "cells", "against bvh"], rows,
                    ["---", "---:", "---:", "---:", "---:", "---:", "---"])
            + f"\n\n![steps against cost per step]({link(charts, a, 'time_model')})\n\n"
            "Each point is a structure on one ray set: x its steps per ray, y its time per step (time per ray "
            "divided by steps, so the triangle tests of a step are in its cost), both geometric means over the "
            "scenes; grey curves join equal times per ray. Left: few steps; down: cheap steps.\n\n"
            f"![model against measurement]({link(charts, a, 'model_fit')})")


def section_bes(a):
    b = a.get("bes")
    out = "## Havran's best efficiency scheme, today\n\n" + a["bes_sentence"] + "\n"
    if b:
        rows = [[f"`{x}`", fmt_ratio(r)] for x, r in b["ranking"]]
        out += ("\nHavran (Heuristic Ray Shooting Algorithms, 2000) compared BSP trees, k-d trees, octrees, BVHs, "
                "uniform and hierarchical grids on the SPD scenes and named the k-d tree built with the surface area "
                f"heuristic the best efficiency scheme. Ranking over the SPD suite ({len(b['scenes'])} scenes, "
                f"{b['cells']} cells; geometric mean relative to Embree; {isa_text(a)}):\n\n"
                + table(["structure", "x Embree"], rows, ["---", "---:"]))
    return out


def section_failures(a):
    rows = []
    for f in a["failures"]:
        cells = ", ".join(f"{rs} {fmt_ratio(r)}" for rs, r in f["cells"]) if f["cells"] else ""
        rows.append([f"`{f['accel']}`", f"`{f['scene']}`", f["kind"], cells, f["cause"]])
    if not rows:
        return "## Failure map\n\nNo cell below 1/10 of Embree, no wrong hit, no leak, nothing skipped."
    return ("## Failure map\n\nEvery structure and scene with a cell below 1/10 of Embree (`slow`: the ray sets with "
            "their speed relative to Embree; the cause is the measured count the time model charges most, against "
            "`bvh`'s on the same cells, then memory when over twice `bvh`'s), a wrong hit by the exact oracle "
            "(`raylab verify`), a leak (`raylab stress`), or a build skipped for memory "
            f"(one thread; {isa_text(a)}).\n\n"
            + table(["structure", "scene", "kind", "cells (x Embree)", "measured cause"], rows))


def section_accuracy(a, charts):
    def per_million(x):
        return "n/a" if x is None else f"{x:,.1f}" if x < 100 else f"{x:,.0f}"
    rows = []
    for p in a["accuracy"]:
        rows.append([f"`{p['accel']}`", fmt_ratio(p["ratio"]), f"{p['mrays_per_s']:.2f}",
                     per_million(p["wrong_verify_per_million"]), per_million(p["wrong_stress_per_million"]),
                     per_million(p["leaks_per_million"])])
    return (f"## Speed against accuracy\n\nEach structure and variant: speed (geometric mean over the study's cells, "
            f"one thread; {isa_text(a)}) against its wrong hits per million rays (decided by the exact oracle: "
            f"`raylab verify` on the study's scenes, `raylab stress` on its scenarios; `embree:robust=1`, the "
            f"reference of both, by the wrong answers the oracle found against it) and its leaks per million "
            f"(`raylab stress`, watertight scenarios). The variants that leak (`tri=mt`: Moller-Trumbore leaves; "
            f"`embree`: Embree's default mode) buy their speed with accuracy.\n\n"
            f"![speed against accuracy]({link(charts, a, 'speed_vs_accuracy')})\n\n"
            + table(["structure", "x Embree", "Mrays/s", "wrong hits per million (verify)",
                     "wrong hits per million (stress)", "leaks per million"], rows,
                    ["---", "---:", "---:", "---:", "---:", "---:"]))


def section_long_check(rows):
    """The long check's table per structure (scripts/long_check_summary.py) from its CSV."""
    if not rows:
        return None
    import long_check_summary as lcs
    table = lcs.per_structure(rows)
    rays = [t["verify_rays"] + t["stress_rays"] for t in table.values()]
    scenes = sorted({r["scene"] for r in rows if r["check"] == "verify"})
    done = "" if min(rays) >= 10_000_000 else " (a run in progress: the goal is 10^7 rays per structure)"
    return ("## Ten million rays per structure: the long check\n\nEvery registered structure's default and its "
            f"scalar variant judged by the exact oracle on {min(rays):,} to {max(rays):,} rays each{done} "
            f"(`raylab verify --judge-ties` with camera, diffuse, shadow and random rays on {len(scenes)} scenes: "
            f"{', '.join(scenes)}; `raylab stress` for leaks), from `docs/correctness.csv`. "
            "`raylab wrong` and `Embree wrong` are the oracle's verdicts on every disagreement; `ties` are "
            "disagreements where float arithmetic may answer either way (docs/method.md).\n\n"
            + lcs.markdown(table) + "\n" + lcs.provenance(rows))


def common_cell_means(runs):
    """Per run, each structure's geometric mean ratio to Embree over the cells every run has."""
    keys = None
    for r in runs:
        mine = {(c[0], c[1], c[2]) for c in r["cells"]}
        keys = mine if keys is None else keys & mine
    out = []
    for r in runs:
        by = {}
        for name, accel, rs, ratio in r["cells"]:
            if (name, accel, rs) in keys:
                by.setdefault(accel, []).append(ratio)
        out.append({a: geomean(v) for a, v in by.items()})
    return out, len({(k[0], k[2]) for k in keys})


def section_isas(main, others):
    if not others:
        return ("## Other instruction sets\n\nOnly this build's ISA was run. `make study STUDY_MARCH=x86-64-v3 "
                "STUDY_EMBREE_ISA=avx2` builds raylab for another ISA (build-x86-64-v3, `-DRAYLAB_NATIVE=OFF`), caps "
                "Embree at it (`RAYLAB_EMBREE_ISA`) and writes `out/study/x86-64-v3/`; the page then compares them here.")
    runs = [main] + others
    means, cells = common_cell_means(runs)
    head = ["structure"] + [f"{r['tag']} ({isa_text(r)})" for r in runs]
    rows = [[f"`{x}`"] + [fmt_ratio(m.get(x)) for m in means] for x in main["accels"]]
    out = (f"## Other instruction sets\n\nEach structure's speed relative to Embree on the same ISA (geometric mean "
           f"over the {cells} scene and ray set cells every build ran, one thread), per build: raylab's kernels "
           f"compiled for the build's `-march`, Embree capped at the same ISA (`RAYLAB_EMBREE_ISA`).\n\n"
           + table(head, rows, ["---"] + ["---:"] * len(runs)))
    for r in others:
        out += f"\n\n{r['tag']}: " + r["bes_sentence"] + "\n\n" + class_table(r) + "\n\n" + provenance(r)
    return out


def page(analyses, charts, long_check_rows=None):
    main, others = analyses[0], analyses[1:]
    hl = ("<!-- headline:begin -->\n"
          + main["bes_sentence"] + "\n\n"
          + f"The fastest structure per scene class (speed relative to Embree, geometric mean over the class's scenes "
          f"and ray sets, one thread; {isa_text(main)}):\n\n"
          + f"![speed relative to Embree per class]({link(charts, main, 'per_class')})\n\n"
          + class_table(main) + "\n\n"
          + provenance(main) + "\n<!-- headline:end -->")
    parts = [
        "# Results: the study",
        "Generated by `make docs` from `out/study/` (written by `make study`: workflow/study.smk, "
        "bench/study/). Which spatial partitioning wins on which kind of scene, by how much, where it fails, and "
        "why, in Havran's manner: a fixed scene suite, per-ray counts next to the time, a verdict per scene, per "
        "class and overall.",
        hl,
        section_suite(main), section_per_scene(main), section_per_class(main, charts), section_bes(main),
        section_counts(main), section_model(main, charts), section_failures(main), section_accuracy(main, charts),
        section_long_check(long_check_rows),
        section_isas(main, others),
        "## Reproduce\n\n```sh\nmake study && make docs                      # quick preset, out/study/native/\n"
        "make study STUDY_PRESET=full                  # out/study-full/native/ (hours)\n"
        "snakemake -s workflow/Snakefile study --profile workflow/profiles/slurm --config study_preset=full\n"
        "make study STUDY_MARCH=x86-64-v3 STUDY_EMBREE_ISA=avx2   # another ISA: out/study/x86-64-v3/\n```",
    ]
    return "\n\n".join(p for p in parts if p) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--assets", help="copy the charts here (one folder per ISA tag) and link them there")
    ap.add_argument("--long-check", help="the long check's CSV (docs/correctness.csv): its table per structure")
    ap.add_argument("analyses", nargs="+")
    a = ap.parse_args()
    long_check_rows = None
    if a.long_check:
        if not os.path.isfile(a.long_check):
            print(f"page: {a.long_check}: no such file", file=sys.stderr)
            return 2
        import csv
        with open(a.long_check) as f:
            long_check_rows = list(csv.DictReader(f))
    runs = []
    for p in a.analyses:
        if not os.path.isfile(p):
            print(f"page: {p}: no such file (run `make study` first)", file=sys.stderr)
            return 2
        with open(p) as f:
            r = json.load(f)
        r["_dir"] = os.path.dirname(os.path.abspath(p))
        runs.append(r)
    runs.sort(key=lambda r: r.get("tag") != "native")
    out_dir = os.path.dirname(os.path.abspath(a.out))
    charts = {}
    for r in runs:
        src = os.path.join(r["_dir"], "charts")
        if a.assets:
            dst = os.path.join(a.assets, r["tag"])
            os.makedirs(dst, exist_ok=True)
            for name in r["charts"].values():
                shutil.copyfile(os.path.join(src, name), os.path.join(dst, name))
            charts[r["tag"]] = os.path.relpath(os.path.abspath(dst), out_dir)
        else:
            charts[r["tag"]] = os.path.relpath(src, out_dir)
    text = page(runs, charts, long_check_rows)
    tmp = a.out + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
