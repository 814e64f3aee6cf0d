#!/usr/bin/python3
"""Charts from raylab's JSON reports (matplotlib; PNG and SVG).

  /usr/bin/python3 bench/plot.py --dir out/bench            # the files `make bench` writes
  /usr/bin/python3 bench/plot.py --bench b.json --out charts # any subset

Inputs (each optional; a chart whose inputs are missing is skipped with a note):
  --bench FILE     `raylab bench` records (the matrix): build vs trace, speed vs accuracy
  --verify FILE    `raylab verify` records (repeatable): disagreement rates per accelerator
  --stress FILE    `raylab stress` records (optional): watertight leaks per accelerator
  --sweep FILE     `raylab bench --sweep` records (repeatable): grid density, kd-tree cost, BVH leaf size
  --scaling FILE   `raylab bench --scale` records: time per ray and build time against triangles
  --render FILE    `raylab render --json` records (repeatable) for the equal-time chart; the
                   record whose image name contains "reference" is the reference image
--dir DIR reads DIR/bench.json, DIR/verify*.json, DIR/stress*.json, DIR/sweep_*.json,
DIR/scaling.json and DIR/equal_time/*.json. Charts go to --out (default: DIR/charts or
./charts) as NAME.png and NAME.svg; --table FILE writes a Markdown table of the bench
records (threads 1) for the README; --memory-table FILE one of the --scaling records with
their peak resident memory and the skipped cells with their reasons.
"""
import argparse
import glob
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


# ---------------------------------------------------------------- input

def load(path):
    with open(path) as f:
        return json.load(f)


def records(path):
    return load(path).get("records", [])


def parse_spec(spec):
    """'bvh:leaf=4,bins=16' -> ('bvh', {'leaf': '4', 'bins': '16'})."""
    name, _, rest = spec.partition(":")
    params = {}
    for item in rest.split(",") if rest else []:
        k, _, v = item.partition("=")
        params[k] = v
    return name, params


def geomean(values):
    values = [v for v in values if v and v > 0]
    return math.exp(sum(math.log(v) for v in values) / len(values)) if values else float("nan")


def family(scene):
    return scene.split(":")[0]


def save(fig, out_dir, name, written):
    os.makedirs(out_dir, exist_ok=True)
    for ext in ("png", "svg"):
        path = os.path.join(out_dir, f"{name}.{ext}")
        fig.savefig(path, dpi=80 if ext == "png" else None, bbox_inches="tight")
        written.append(path)
    plt.close(fig)


def footer(fig, header):
    if not header:
        return
    text = f"{header.get('cpu', '?')} | Embree {header.get('embree', '?')} | rev {header.get('revision', '?')} | {header.get('date', '?')}"
    fig.text(0.01, -0.02, text, fontsize=7, color="gray", ha="left", va="top")


def single_thread(recs):
    one = [r for r in recs if r.get("threads") == 1]
    return one if one else recs


# ---------------------------------------------------------------- charts

def chart_speed_vs_accuracy(bench, verify_files, stress_files, out, written, header):
    """Ratio to Embree (geometric mean over scenes and ray sets, 1 thread) against
    disagreement rates (verify) and watertight leaks (stress), one point per configuration."""
    speed = {}
    for r in single_thread(bench):
        speed.setdefault(r["accel"], []).append(r["ratio_to_embree"])
    speed = {k: geomean(v) for k, v in speed.items()}

    # Accuracy per configuration: from verify (oracle-referred) when given,
    # else from the bench's own agreement with Embree.
    wrong, disagree, terr, source = {}, {}, {}, "bench agreement with Embree"
    vrecs = [r for f in verify_files for r in records(f)]
    if vrecs:
        source = "raylab verify"
        tot = {}
        for r in vrecs:
            t = tot.setdefault(r["accel"], [0, 0, 0, 0])
            t[0] += r["rays"]
            t[1] += r["raylab_wrong"]
            t[2] += r.get("hit_miss_disagree", 0) + r.get("prim_disagree", 0) + r.get("ties", 0)
            t[3] += r.get("embree_wrong", 0)
            terr[r["accel"]] = max(terr.get(r["accel"], 0.0), r.get("max_rel_t_err", 0.0))
        for k, (n, w, d, _) in tot.items():
            wrong[k] = w / n if n else 0.0
            disagree[k] = d / n if n else 0.0
    else:
        tot = {}
        for r in bench:
            t = tot.setdefault(r["accel"], [0.0, 0])
            t[0] += (1.0 - r.get("embree_agreement", 1.0)) * r["rays"]
            t[1] += r["rays"]
        for k, (d, n) in tot.items():
            disagree[k] = d / n if n else 0.0
    srecs = [r for f in stress_files for r in records(f)]
    leaks = {}
    for r in srecs:
        leaks[r["accel"]] = leaks.get(r["accel"], 0) + int(r.get("leaks", 0) or 0)
        if r.get("ratio_to_embree") and r["accel"] not in speed:
            speed[r["accel"]] = r["ratio_to_embree"]

    panels = 1 + (1 if terr else 0) + (1 if srecs else 0)
    fig, axes = plt.subplots(1, panels, figsize=(6.0 * panels, 4.8), squeeze=False, constrained_layout=True)
    names = sorted(set(speed) | set(disagree) | set(terr) | set(leaks))
    colour = {k: f"C{i % 10}" for i, k in enumerate(names)}
    ax = axes[0][0]
    floor = 1e-7
    for k in sorted(speed):
        if k not in disagree:
            continue
        y = speed[k]
        x = max(disagree[k], floor)
        ax.scatter([x], [y], s=40, zorder=3, color=colour[k])
        label = k if len(k) < 40 else k[:38] + ".."
        if k in wrong:
            label += f"  (wrong {wrong[k]:.1e})" if wrong[k] > 0 else "  (wrong 0)"
        ax.annotate(label, (x, y), fontsize=7, xytext=(4, 3), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axvline(floor, color="lightgray", lw=0.8)
    ax.set_xlabel(f"fraction of rays answered differently from Embree\n({source}, ties included; 0 drawn at {floor:g})")
    ax.set_ylabel("speed: ratio to Embree (geomean, 1 thread)")
    ax.set_title("Speed against accuracy" + (" (wrong = oracle says the accelerator erred)" if wrong else ""), fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    if terr:
        ax = axes[0][1]
        for k in sorted(terr):
            if k not in speed:
                continue
            x = max(terr[k], 1e-9)
            ax.scatter([x], [speed[k]], s=40, zorder=3, color=colour[k])
            ax.annotate(k if len(k) < 40 else k[:38] + "..", (x, speed[k]), fontsize=7, xytext=(4, 3),
                        textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("largest relative hit-distance difference from Embree\n(raylab verify, rays where both hit)")
        ax.set_ylabel("speed: ratio to Embree")
        ax.set_title("Speed against distance accuracy", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    if srecs:
        ax = axes[0][panels - 1]
        for k in sorted(leaks):
            if k not in speed:
                continue
            x = max(leaks[k], 0.5)
            ax.scatter([x], [speed[k]], s=40, zorder=3, color=colour[k])
            ax.annotate(k, (x, speed[k]), fontsize=7, xytext=(4, 3), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("watertight leaks in raylab stress (0 drawn at 0.5)")
        ax.set_ylabel("speed: ratio to Embree")
        ax.set_title("Speed against leaks")
        ax.grid(True, which="both", alpha=0.3)
    footer(fig, header)
    save(fig, out, "speed_vs_accuracy", written)


def chart_build_vs_trace(bench, out, written, header):
    """Total time (build + trace) against the number of rays, one line per accelerator."""
    recs = single_thread(bench)
    scenes = sorted({r["scene"] for r in recs}, key=lambda s: max(r["triangles"] for r in recs if r["scene"] == s))
    scene = scenes[-1]
    sets = [r["ray_set"] for r in recs if r["scene"] == scene]
    ray_set = "diffuse" if "diffuse" in sets else sets[0]
    sel = [r for r in recs if r["scene"] == scene and r["ray_set"] == ray_set]
    n = np.logspace(2, 10, 200)
    fig, ax = plt.subplots(figsize=(7, 4.8))
    for r in sorted(sel, key=lambda r: r["accel"]):
        if r["mrays_per_s"] <= 0:
            continue
        total = r["build_ms"] * 1e-3 + n / (r["mrays_per_s"] * 1e6)
        ax.plot(n, total, label=f"{r['accel']} (build {r['build_ms']:.1f} ms, {r['mrays_per_s']:.1f} Mrays/s)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(f"rays traced ({ray_set} rays)")
    ax.set_ylabel("build + trace time (s), 1 thread")
    ax.set_title(f"Build against trace: {scene} ({sel[0]['triangles'] if sel else 0} triangles)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    footer(fig, header)
    save(fig, out, "build_vs_trace", written)


def sweep_chart(recs, names, param, out, name, title, xlabel, written, header, mark=None, xfun=None, second=None):
    """One line per (accelerator, ray set): ratio to Embree against a parameter."""
    lines = {}
    for r in single_thread(recs):
        acc, params = parse_spec(r["accel"])
        if acc not in names:
            continue
        x = xfun(params) if xfun else (float(params[param]) if param in params else None)
        if x is None:
            continue
        rest = ",".join(f"{k}={v}" for k, v in sorted(params.items()) if k not in (param, "ct", "ci"))
        lines.setdefault((acc + (":" + rest if rest else ""), r["ray_set"]), []).append((x, r))
    lines = {k: sorted(v, key=lambda p: p[0]) for k, v in lines.items() if len({p[0] for p in v}) >= 2}
    if not lines:
        return False
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
    for (acc, rs), pts in sorted(lines.items()):
        xs = [p[0] for p in pts]
        axes[0].plot(xs, [p[1]["ratio_to_embree"] for p in pts], marker="o", ms=3, label=f"{acc} {rs}")
        yfun, ylabel = second
        axes[1].plot(xs, [yfun(p[1]) for p in pts], marker="o", ms=3, label=f"{acc} {rs}")
    axes[0].set_ylabel("ratio to Embree (1 thread)")
    axes[1].set_ylabel(second[1])
    for ax in axes:
        ax.set_xscale("log", base=2)
        ax.set_xlabel(xlabel)
        ax.grid(True, which="both", alpha=0.3)
        if mark is not None:
            ax.axvline(mark[0], color="red", ls="--", lw=1)
            ax.annotate(mark[1], (mark[0], 0.98), xycoords=("data", "axes fraction"), color="red", fontsize=8,
                        xytext=(3, -10), textcoords="offset points")
    axes[1].set_yscale("log")
    axes[0].legend(fontsize=7)
    scene = recs[0]["scene"] if recs else ""
    fig.suptitle(f"{title} ({scene})")
    footer(fig, header)
    save(fig, out, name, written)
    return True


def chart_scaling(recs, out, written, header):
    """Time per ray, build time and peak resident memory against triangles, log-log, with
    N log N and log N guides; one line per accelerator and scene family (soup solid, others
    dashed), so a 10^8-triangle terrain point sits next to the soups."""
    recs = single_thread(recs)
    fams = sorted({family(r["scene"]) for r in recs}, key=lambda f: (f != "soup", f))
    sets = sorted({r["ray_set"] for r in recs})
    ray_set = "random" if "random" in sets else sets[0]
    by_acc = {}
    for r in recs:
        if r["ray_set"] == ray_set:
            by_acc.setdefault((r["accel"], family(r["scene"])), []).append(r)
    has_rss = any(r.get("rss_peak_bytes") for r in recs)
    fig, axes = plt.subplots(1, 3 if has_rss else 2, figsize=(18 if has_rss else 12, 4.8))
    all_n = sorted({r["triangles"] for r in recs if family(r["scene"]) == fams[0]})
    colors = {}
    for (acc, fam), rs in sorted(by_acc.items(), key=lambda kv: (fams.index(kv[0][1]), kv[0][0])):
        rs = sorted(rs, key=lambda r: r["triangles"])
        n = [r["triangles"] for r in rs]
        style = dict(marker="o" if fam == fams[0] else "s", ms=3, ls="-" if fam == fams[0] else "--",
                     label=acc if fam == fams[0] else f"{acc} ({fam})")
        if acc in colors:
            style["color"] = colors[acc]
        line, = axes[0].plot(n, [1e3 / r["mrays_per_s"] if r["mrays_per_s"] > 0 else float("nan") for r in rs], **style)
        colors.setdefault(acc, line.get_color())
        style["color"] = colors[acc]
        axes[1].plot(n, [max(r["build_ms"], 1e-3) for r in rs], **style)
        if has_rss:
            axes[2].plot(n, [r.get("rss_peak_bytes", 0) / 2**30 or float("nan") for r in rs], **style)
    n = np.array(all_n, dtype=float)
    first = [sorted(v, key=lambda r: r["triangles"]) for (a, f), v in by_acc.items() if f == fams[0]]
    if len(n) >= 2 and first:
        # Guides anchored at the geometric mean of the first points.
        first_t = geomean([1e3 / rs[0]["mrays_per_s"] for rs in first if rs[0]["mrays_per_s"] > 0])
        axes[0].plot(n, first_t * np.log2(n) / math.log2(n[0]), "k:", lw=1.2, label="log N guide")
        first_b = geomean([max(rs[0]["build_ms"], 1e-3) for rs in first])
        axes[1].plot(n, first_b * (n * np.log2(n)) / (n[0] * math.log2(n[0])), "k:", lw=1.2, label="N log N guide")
    axes[0].set_ylabel(f"time per ray (ns), {ray_set} rays, 1 thread")
    axes[1].set_ylabel("build time (ms), median of builds")
    if has_rss:
        axes[2].set_ylabel("peak resident set of the process (GiB)")
    for ax in axes:
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(f"triangles ({', '.join(fams)})")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"Scaling with scene size ({', '.join(fams)})")
    footer(fig, header)
    save(fig, out, "scaling", written)


def read_pfm(path):
    with open(path, "rb") as f:
        if f.readline().strip() != b"PF":
            raise ValueError(f"{path}: not an RGB PFM")
        w, h = (int(x) for x in f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return data.reshape(h, w, 3).astype(np.float64)


def chart_equal_time(render_files, out, written):
    """RMSE against a high-sample Embree reference against wall time (build + render)."""
    recs = []
    for f in render_files:
        for r in records(f):
            r = dict(r)
            if not os.path.isabs(r["image"]) and not os.path.exists(r["image"]):
                r["image"] = os.path.join(os.path.dirname(f), os.path.basename(r["image"]))
            recs.append(r)
    refs = [r for r in recs if "reference" in os.path.basename(r["image"])]
    if not refs:
        print("plot.py: equal-time chart skipped: no reference render", file=sys.stderr)
        return False
    ref = read_pfm(refs[0]["image"])
    curves = {}
    for r in recs:
        if r in refs or not r["image"].endswith(".pfm"):
            continue
        img = read_pfm(r["image"])
        if img.shape != ref.shape:
            continue
        rmse = float(np.sqrt(np.mean((img - ref) ** 2)))
        curves.setdefault(r["accel"], []).append((r["wall_s"], rmse, r["spp"]))
    if not curves:
        return False
    fig, ax = plt.subplots(figsize=(7, 4.8))
    for acc, pts in sorted(curves.items()):
        pts.sort()
        ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", ms=3, label=acc)
    last = sorted(curves.items())[0][1]
    for wall, err, spp in last:
        ax.annotate(f"{spp} spp", (wall, err), fontsize=6, xytext=(3, 3), textcoords="offset points", color="gray")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time: build + render (s)")
    ax.set_ylabel("RMSE against the reference image")
    ref_rec = refs[0]
    ax.set_title(f"Equal-time rendering: {ref_rec['scene']} {ref_rec['width']}x{ref_rec['height']} "
                 f"(reference {ref_rec['accel']} {ref_rec['spp']} spp)", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    save(fig, out, "equal_time", written)
    return True


def fmt_ms(ms):
    return f"{ms:,.0f}" if ms >= 100 else f"{ms:.3g}"


def markdown_table(bench, header):
    recs = single_thread(bench)
    lines = [f"Quick preset, {header.get('cpu', '?')}, Embree {header.get('embree', '?')}, revision "
             f"{header.get('revision', '?')}, {header.get('date', '?')}; 1 thread; Mrays/s (ratio to Embree "
             "timed back to back with each accelerator in the same process, so the embree row is a separate "
             "measurement).", ""]
    sets = []
    for r in recs:
        if r["ray_set"] not in sets:
            sets.append(r["ray_set"])
    lines.append("| scene | triangles | accel | build ms | bytes/tri | " + " | ".join(sets) + " |")
    lines.append("|---|---:|---|---:|---:|" + "---:|" * len(sets))
    seen = []
    for r in recs:
        key = (r["scene"], r["accel"])
        if key not in seen:
            seen.append(key)
    for scene, acc in seen:
        rs = {r["ray_set"]: r for r in recs if r["scene"] == scene and r["accel"] == acc}
        any_r = next(iter(rs.values()))
        cells = []
        for s in sets:
            r = rs.get(s)
            cells.append(f"{r['mrays_per_s']:.2f} ({r['ratio_to_embree']:.2f})" if r else "")
        lines.append(f"| {scene} | {any_r['triangles']} | {acc} | {fmt_ms(any_r['build_ms'])} | "
                     f"{any_r['bytes_per_triangle']:.0f} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def markdown_scaling_table(recs):
    recs = [r for r in single_thread(recs) if r["ray_set"] == "random"]
    if not recs:
        return ""
    sizes = sorted({r["triangles"] for r in recs})
    accels = []
    for r in recs:
        if r["accel"] not in accels:
            accels.append(r["accel"])
    lines = ["", f"Scaling ({family(recs[0]['scene'])}, random rays, 1 thread): build ms / ns per ray (ratio to Embree).", "",
             "| accel | " + " | ".join(f"{n:,} tris" for n in sizes) + " |", "|---|" + "---:|" * len(sizes)]
    for acc in accels:
        cells = []
        for n in sizes:
            r = next((r for r in recs if r["accel"] == acc and r["triangles"] == n), None)
            cells.append(f"{fmt_ms(r['build_ms'])} / {1e3 / r['mrays_per_s']:.0f} ({r['ratio_to_embree']:.2f})"
                         if r and r["mrays_per_s"] > 0 else "")
        lines.append(f"| {acc} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def markdown_memory_table(report):
    """Every cell of a scaling report with its peak resident set, then the skipped cells and why."""
    recs = report.get("records", [])
    lines = ["| scene | triangles | accel | threads | build ms | peak RSS GiB | "
             + " | ".join(f"{s} Mrays/s (ratio)" for s in sorted({r["ray_set"] for r in recs})) + " |"]
    sets = sorted({r["ray_set"] for r in recs})
    lines.append("|---|---:|---|---:|---:|---:|" + "---:|" * len(sets))
    cells = {}
    for r in recs:
        cells.setdefault((r["scene"], r["triangles"], r["accel"], r["threads"]), {})[r["ray_set"]] = r
    for (scene, tris, acc, thr), by_set in cells.items():
        any_r = next(iter(by_set.values()))
        note = " (Embree timed first)" if any_r.get("extra", {}).get("embree_timed_first") else ""
        rss = any_r.get("rss_peak_bytes", 0) / 2**30
        row = [f"{by_set[s]['mrays_per_s']:.2f} ({by_set[s]['ratio_to_embree']:.2f})" if s in by_set else "" for s in sets]
        lines.append(f"| {scene} | {tris:,} | {acc}{note} | {thr} | {fmt_ms(any_r['build_ms'])} | {rss:.1f} | "
                     + " | ".join(row) + " |")
    for sk in report.get("skipped", []):
        lines.append(f"| {sk['scene']} | {sk['triangles']:,} | {sk['accel']} | | skipped: {sk['reason']} | | "
                     + " | ".join("" for _ in sets) + " |")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------- main

def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dir")
    ap.add_argument("--bench")
    ap.add_argument("--verify", action="append", default=[])
    ap.add_argument("--stress", action="append", default=[])
    ap.add_argument("--sweep", action="append", default=[])
    ap.add_argument("--scaling")
    ap.add_argument("--render", action="append", default=[])
    ap.add_argument("--out")
    ap.add_argument("--table")
    ap.add_argument("--memory-table", help="Markdown table of the --scaling records with peak memory and skips")
    a = ap.parse_args()
    if a.dir:
        d = a.dir
        if not a.bench and os.path.exists(os.path.join(d, "bench.json")):
            a.bench = os.path.join(d, "bench.json")
        a.verify += sorted(glob.glob(os.path.join(d, "verify*.json")))
        a.stress += sorted(glob.glob(os.path.join(d, "stress*.json")))
        a.sweep += sorted(glob.glob(os.path.join(d, "sweep_*.json")))
        if not a.scaling and os.path.exists(os.path.join(d, "scaling.json")):
            a.scaling = os.path.join(d, "scaling.json")
        a.render += sorted(glob.glob(os.path.join(d, "equal_time", "*.json")))
    out = a.out or (os.path.join(a.dir, "charts") if a.dir else "charts")
    for f in [a.bench, a.scaling] + a.verify + a.stress + a.sweep + a.render:
        if f and not os.path.exists(f):
            print(f"plot.py: error: no such file {f}", file=sys.stderr)
            return 2
    written, skipped = [], []
    if a.memory_table and a.scaling:
        with open(a.memory_table + ".tmp", "w") as f:
            f.write(markdown_memory_table(load(a.scaling)))
        os.replace(a.memory_table + ".tmp", a.memory_table)
    header = load(a.bench) if a.bench else {}
    bench = records(a.bench) if a.bench else []
    if bench:
        chart_speed_vs_accuracy(bench, a.verify, a.stress, out, written, header)
        chart_build_vs_trace(bench, out, written, header)
        if a.table:
            os.makedirs(os.path.dirname(os.path.abspath(a.table)), exist_ok=True)
            with open(a.table + ".tmp", "w") as f:
                f.write(markdown_table(bench, header))
                if a.scaling:
                    f.write(markdown_scaling_table(records(a.scaling)))
            os.replace(a.table + ".tmp", a.table)
    else:
        skipped += ["speed_vs_accuracy", "build_vs_trace"]
    sweep = [r for f in a.sweep for r in records(f)]
    sweep_header = load(a.sweep[0]) if a.sweep else {}
    if not sweep_chart(sweep, {"grid", "hashgrid", "grid2"}, "density", out, "density_sweep",
                       "Grid density sweep", "density (cells per triangle; 1 = the n^(1/3) rule)", written,
                       sweep_header, mark=(1.0, "n^(1/3) rule"),
                       second=(lambda r: r["bytes_per_triangle"], "bytes per triangle")):
        skipped.append("density_sweep")

    def kd_ratio(p):
        if "ct" not in p and "ci" not in p:
            return None
        return float(p.get("ct", 15)) / float(p.get("ci", 20))

    if not sweep_chart(sweep, {"kdtree"}, None, out, "kdtree_cost_sweep", "k-d tree cost constants",
                       "traversal / intersection cost ratio ct/ci (default 15/20)", written, sweep_header,
                       mark=(0.75, "default"), xfun=kd_ratio,
                       second=(lambda r: max(r["nodes_per_ray"], 1e-3), "nodes visited per ray")):
        skipped.append("kdtree_cost_sweep")
    if not sweep_chart(sweep, {"bvh"}, "leaf", out, "bvh_leaf_sweep", "BVH leaf size", "max triangles per leaf",
                       written, sweep_header,
                       second=(lambda r: max(r["tris_per_ray"], 1e-3), "triangle tests per ray")):
        skipped.append("bvh_leaf_sweep")
    if a.scaling and records(a.scaling):
        chart_scaling(records(a.scaling), out, written, load(a.scaling))
    else:
        skipped.append("scaling")
    if not (a.render and chart_equal_time(a.render, out, written)):
        skipped.append("equal_time")
    for p in written:
        print(p)
    if skipped:
        print("plot.py: skipped (inputs missing): " + ", ".join(skipped), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
