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
  --render FILE    `raylab render --timings` records (repeatable) for the equal-time chart; the
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

def registry(binary):
    """The accelerators as `raylab accels --json` lists them (name, params, capabilities), or None."""
    import subprocess
    try:
        out = subprocess.run([binary, "accels", "--json"], capture_output=True, text=True, check=True, timeout=60)
        return json.loads(out.stdout)
    except (OSError, subprocess.SubprocessError, ValueError):
        return None


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


def label_log_axes(fig):
    """Every log axis says so in its label: a reader who misses it reads distances as differences.
    (Log axes are for dot and line plots only; bar charts are not drawn on them.)"""
    for ax in fig.get_axes():
        for axis, scale, label, setter in (("x", ax.get_xscale(), ax.get_xlabel(), ax.set_xlabel),
                                           ("y", ax.get_yscale(), ax.get_ylabel(), ax.set_ylabel)):
            if scale in ("log", "symlog") and label and "log" not in label:
                lines = label.split("\n")
                lines[0] += " (symmetric log scale)" if scale == "symlog" else " (log scale)"
                setter("\n".join(lines))


def save(fig, out_dir, name, written):
    label_log_axes(fig)
    os.makedirs(out_dir, exist_ok=True)
    for ext in ("png", "svg"):
        path = os.path.join(out_dir, f"{name}.{ext}")
        fig.savefig(path, dpi=80 if ext == "png" else None, bbox_inches="tight")
        written.append(path)
    plt.close(fig)


def footer(fig, header):
    if not header:
        return
    # Only what the report records: no "?" placeholders for missing fields.
    parts = [header.get("cpu"), f"Embree {header['embree']}" if header.get("embree") else None,
             f"rev {header['revision']}" if header.get("revision") not in (None, "", "unknown") else None,
             header.get("date")]
    text = " | ".join(p for p in parts if p)
    if text:
        fig.text(0.01, -0.02, text, fontsize=7, color="gray", ha="left", va="top")


def single_thread(recs):
    one = [r for r in recs if r.get("threads") == 1]
    return one if one else recs


# One colour per structure in every chart: the registry's (`raylab accels --json` gives
# each structure's "colour", app/cmd_report_palette.h), with the same table here for runs
# without the binary. A variant (a spec with parameters) takes its structure's colour,
# lightened; line styles and markers then tell variants apart.
FIXED_COLOURS = {"embree": "#1f1f1f", "brute": "#8c8c8c", "bvh": "#1f77b4", "kdtree": "#d62728", "grid": "#2ca02c",
                 "hashgrid": "#98df8a", "grid2": "#006d2c", "octree": "#9467bd", "loose_octree": "#c5b0d5",
                 "hgrid": "#17becf", "bsp": "#ff7f0e", "hybrid": "#e377c2", "irgrid": "#bcbd22"}
SPARE_COLOURS = ["#8c564b", "#7f7f00", "#ff9896", "#aec7e8", "#c49c94", "#dbdb8d"]
REGISTRY_COLOURS = {}


def name_colour(name):
    if name in REGISTRY_COLOURS:
        return REGISTRY_COLOURS[name]
    if name in FIXED_COLOURS:
        return FIXED_COLOURS[name]
    h = 2166136261
    for ch in name.encode():
        h = ((h ^ ch) * 16777619) & 0xFFFFFFFF
    return SPARE_COLOURS[h % len(SPARE_COLOURS)]


def lighten(hex_colour, amount):
    c = [int(hex_colour[1 + 2 * i:3 + 2 * i], 16) for i in range(3)]
    return "#" + "".join(f"{int(v + (255 - v) * amount + 0.5):02x}" for v in c)


def colour_of(spec):
    name, params = parse_spec(spec)
    return name_colour(name) if not params else lighten(name_colour(name), 0.45)


MARKERS = "osD^v<>pPX*h"
LINESTYLES = ["-", "--", "-.", ":"]


def style_of(spec, specs):
    """Marker and line style that tell apart the specs of one structure (same colour)."""
    name = parse_spec(spec)[0]
    same = sorted(s for s in specs if parse_spec(s)[0] == name)
    i = same.index(spec) if spec in same else 0
    return dict(color=colour_of(spec), marker=MARKERS[i % len(MARKERS)], ls=LINESTYLES[i % len(LINESTYLES)])


def log_ticks(ax, axis="both"):
    """Readable log axes: within three decades ticks at 1, 2, 5 x 10^k as plain numbers;
    wider ranges one tick per decade as powers of ten (never one lone label, never overlaps)."""
    from matplotlib.ticker import FuncFormatter, LogFormatterSciNotation, LogLocator
    for which in (["x", "y"] if axis == "both" else [axis]):
        a = ax.xaxis if which == "x" else ax.yaxis
        if (ax.get_xscale() if which == "x" else ax.get_yscale()) != "log":
            continue
        lo, hi = sorted(ax.get_xlim() if which == "x" else ax.get_ylim())
        decades = math.log10(hi / lo) if lo > 0 and hi > lo else 1.0
        if decades <= 3:
            a.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0), numticks=12))
            a.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        else:
            a.set_major_locator(LogLocator(base=10, numticks=12))
            a.set_major_formatter(LogFormatterSciNotation())
        a.set_minor_formatter(FuncFormatter(lambda v, _: ""))


def error_bars(recs, value, lo, hi):
    """(values, [below, above]) for matplotlib's yerr from each record's min and max."""
    vals = [value(r) for r in recs]
    below = [max(v - lo(r), 0) if lo(r) is not None else 0 for v, r in zip(vals, recs)]
    above = [max(hi(r) - v, 0) if hi(r) is not None else 0 for v, r in zip(vals, recs)]
    return vals, [below, above]


def ratio_range(r):
    """(min, max) ratio to Embree from the slowest and fastest repeats, or (None, None)."""
    e = r.get("embree_mrays_per_s")
    if not e or r.get("mrays_min") is None or r.get("mrays_max") is None:
        return None, None
    return r["mrays_min"] / e, r["mrays_max"] / e


# ---------------------------------------------------------------- charts

def chart_speed_vs_accuracy(bench, verify_files, stress_files, out, written, header):
    """Ratio to Embree (geometric mean over scenes and ray sets, 1 thread) against
    disagreement rates (verify), distance error and watertight leaks (stress), one point per
    configuration. Zero is a real value on these axes (symlog: linear near 0, log above), the
    names are in the legend (no overlapping labels), and a configuration measured on fewer
    scenes than the others says so in its label."""
    recs = single_thread(bench)
    all_scenes = {r["scene"] for r in recs}
    speed, cover = {}, {}
    for r in recs:
        speed.setdefault(r["accel"], []).append(r["ratio_to_embree"])
        cover.setdefault(r["accel"], set()).add(r["scene"])
    speed = {k: geomean(v) for k, v in speed.items()}

    wrong, disagree, terr, source = {}, {}, {}, "bench agreement with Embree"
    vrecs = [r for f in verify_files for r in records(f)]
    if vrecs:
        source = "raylab verify"
        tot = {}
        for r in vrecs:
            t = tot.setdefault(r["accel"], [0, 0, 0])
            t[0] += r["rays"]
            t[1] += r["raylab_wrong"]
            t[2] += r.get("hit_miss_disagree", 0) + r.get("prim_disagree", 0) + r.get("ties", 0)
            terr[r["accel"]] = max(terr.get(r["accel"], 0.0), r.get("max_rel_t_err") or 0.0)
        for k, (n, w, d) in tot.items():
            wrong[k] = w / n if n else 0.0
            disagree[k] = d / n if n else 0.0
    else:
        tot = {}
        for r in bench:
            t = tot.setdefault(r["accel"], [0.0, 0])
            t[0] += (1.0 - (r.get("embree_agreement") or 1.0)) * r["rays"]
            t[1] += r["rays"]
        for k, (d, n) in tot.items():
            disagree[k] = d / n if n else 0.0
    srecs = [r for f in stress_files for r in records(f)]
    leaks, leak_rays = {}, {}
    for r in srecs:
        leaks[r["accel"]] = leaks.get(r["accel"], 0) + int(r.get("leaks", 0) or 0)
        leak_rays[r["accel"]] = leak_rays.get(r["accel"], 0) + int(r.get("leak_rays", 0) or 0)

    panels = [("disagree", disagree, f"fraction of rays answered differently from Embree ({source}, ties included)", 1e-6)]
    if terr:
        panels.append(("terr", terr, "largest relative hit-distance difference from Embree (raylab verify)", 1e-7))
    if srecs:
        lpm = {k: leaks[k] / leak_rays[k] * 1e6 if leak_rays.get(k) else 0.0 for k in leaks}
        panels.append(("leaks", lpm, "watertight leaks per million rays (raylab stress)", 1.0))
    fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels) + 2.5, 4.8), squeeze=False)
    specs = sorted(speed)
    handles = {}
    for ax, (_, xs, xlabel, linthresh) in zip(axes[0], panels):
        for k in specs:
            if k not in xs:
                continue
            st = style_of(k, specs)
            label = k
            if len(cover.get(k, ())) < len(all_scenes):
                label += f" ({len(cover[k])} of {len(all_scenes)} scenes)"
            if k in wrong:
                label += f", wrong {wrong[k]:.1e}" if wrong[k] > 0 else ", wrong 0"
            h = ax.scatter([xs[k]], [speed[k]], s=45, zorder=3, color=st["color"], marker=st["marker"],
                           edgecolors="black", linewidths=0.4, label=label)
            handles.setdefault(label, h)
        ax.set_xscale("symlog", linthresh=linthresh)
        ax.set_xlim(left=0)
        ax.set_yscale("log")
        log_ticks(ax, "y")
        ax.set_xlabel(xlabel, fontsize=8)
        ax.set_ylabel("speed: ratio to Embree (geomean, 1 thread)")
        ax.axhline(1.0, color="gray", lw=0.8, ls="--")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].set_title("Speed against accuracy (0 = no disagreement; symmetric-log x axis)", fontsize=9)
    fig.legend(list(handles.values()), list(handles.keys()), loc="center left", bbox_to_anchor=(1.0, 0.5), fontsize=7)
    fig.tight_layout()
    footer(fig, header)
    save(fig, out, "speed_vs_accuracy", written)


def chart_speed_vs_memory(bench, out, written, header):
    """Every structure's speed (ratio to Embree, geomean over scenes and ray sets, 1 thread,
    whiskers from the slowest and fastest repeats) against its memory (bytes per triangle,
    geomean over scenes): the trade-off in one picture."""
    recs = single_thread(bench)
    by = {}
    for r in recs:
        by.setdefault(r["accel"], []).append(r)
    if not by:
        return False
    specs = sorted(by)
    all_scenes = {r["scene"] for r in recs}
    fig, ax = plt.subplots(figsize=(8.5, 5))
    for k in specs:
        rs = by[k]
        scenes = {r["scene"] for r in rs}
        # A mean over fewer scenes is not comparable with the others: hollow marker, and the label says so.
        fewer = len(scenes) < len(all_scenes)
        x = geomean([r.get("bytes_per_triangle") for r in rs])
        y = geomean([r["ratio_to_embree"] for r in rs])
        lo = geomean([ratio_range(r)[0] for r in rs])
        hi = geomean([ratio_range(r)[1] for r in rs])
        st = style_of(k, specs)
        yerr = [[max(y - lo, 0)], [max(hi - y, 0)]] if lo == lo and hi == hi else None
        ax.errorbar([x], [y], yerr=yerr, fmt=st["marker"], color=st["color"], ms=7, mec="black", mew=0.4,
                    mfc="none" if fewer else st["color"], capsize=3,
                    label=f"{k} ({len(scenes)} of {len(all_scenes)} scenes)" if fewer else k)
    ax.set_xscale("log")
    ax.set_yscale("log")
    log_ticks(ax)
    ax.axhline(1.0, color="gray", lw=0.8, ls="--")
    ax.set_xlabel("memory: bytes per triangle (geomean over scenes)")
    ax.set_ylabel("speed: ratio to Embree (geomean, 1 thread)\nwhiskers: slowest-fastest repeat")
    ax.set_title("Speed against memory, every structure", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.0, 0.5))
    footer(fig, header)
    save(fig, out, "speed_vs_memory", written)
    return True


def chart_build_vs_trace(bench, out, written, header):
    """Build plus trace time against rays traced, one line per accelerator. A MODEL: each
    line is build_ms + rays / (measured Mrays/s), drawn solid up to the rays the bench
    actually traced per repeat and dotted beyond (an extrapolation). Every line has its own
    marker and dash, so lines that coincide stay visible."""
    recs = single_thread(bench)
    scenes = sorted({r["scene"] for r in recs}, key=lambda s: max(r["triangles"] for r in recs if r["scene"] == s))
    scene = scenes[-1]
    sets = [r["ray_set"] for r in recs if r["scene"] == scene]
    ray_set = "diffuse" if "diffuse" in sets else sets[0]
    sel = [r for r in recs if r["scene"] == scene and r["ray_set"] == ray_set and r["mrays_per_s"] > 0]
    specs = sorted(r["accel"] for r in sel)
    n = np.logspace(2, 9, 120)
    fig, ax = plt.subplots(figsize=(8.5, 5))
    for r in sorted(sel, key=lambda r: r["accel"]):
        st = style_of(r["accel"], specs)
        total = r["build_ms"] * 1e-3 + n / (r["mrays_per_s"] * 1e6)
        measured = n <= max(r.get("rays", 0), 1)
        ax.plot(n[measured], total[measured], color=st["color"], ls=st["ls"], lw=1.6)
        ax.plot(n[~measured], total[~measured], color=st["color"], ls=":", lw=1.0)
        ax.plot(n[::12], total[::12], color=st["color"], marker=st["marker"], ls="none", ms=4,
                label=f"{r['accel']} (build {fmt_ms(r['build_ms'])} ms, {r['mrays_per_s']:.2f} Mrays/s)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    log_ticks(ax)
    ax.set_xlabel(f"rays traced ({ray_set} rays)")
    ax.set_ylabel("model: build + rays / measured speed (s), 1 thread")
    ax.set_title(f"Build against trace, a model from measured build time and speed: {scene} "
                 f"({sel[0]['triangles'] if sel else 0} triangles)\nsolid: up to the rays measured; dotted: extrapolated",
                 fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.0, 0.5))
    footer(fig, header)
    save(fig, out, "build_vs_trace", written)


def swept_parameters(recs):
    """{(structure, param): [records]} for every parameter whose value varies among one
    structure's records (the sweeps found in the records, whatever the config names)."""
    by_name = {}
    for r in recs:
        by_name.setdefault(parse_spec(r["accel"])[0], []).append(r)
    found = {}
    for name, rs in by_name.items():
        keys = set()
        for r in rs:
            keys |= set(parse_spec(r["accel"])[1])
        for k in sorted(keys):
            values = {parse_spec(r["accel"])[1].get(k) for r in rs}
            if len(values - {None}) >= 2:
                found.setdefault(k, []).extend(rs)
    return found


def numeric(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def chart_sweep(recs, param, out, written, header):
    """One chart per swept parameter: ratio to Embree (error bars: slowest-fastest repeat)
    and the work per ray (nodes or triangle tests) against the parameter, one line per
    (configuration without the parameter, ray set)."""
    lines = {}
    for r in single_thread(recs):
        name, params = parse_spec(r["accel"])
        if param not in params or numeric(params[param]) is None:
            continue
        rest = ",".join(f"{k}={v}" for k, v in sorted(params.items()) if k != param)
        lines.setdefault((name + (":" + rest if rest else ""), r["ray_set"]), []).append((numeric(params[param]), r))
    lines = {k: sorted(v, key=lambda p: p[0]) for k, v in lines.items() if len({p[0] for p in v}) >= 2}
    if not lines:
        return False
    specs = sorted({k[0] for k in lines})
    sets = sorted({k[1] for k in lines})
    work_key = "tris_per_ray" if param in ("leaf",) else "nodes_per_ray"
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.6))
    for (acc, rs), pts in sorted(lines.items()):
        st = style_of(acc, specs)
        ls = LINESTYLES[sets.index(rs) % len(LINESTYLES)]
        xs = [p[0] for p in pts]
        rr = [p[1] for p in pts]
        vals, yerr = error_bars(rr, lambda r: r["ratio_to_embree"], lambda r: ratio_range(r)[0], lambda r: ratio_range(r)[1])
        axes[0].errorbar(xs, vals, yerr=yerr, color=st["color"], marker=st["marker"], ls=ls, ms=4, capsize=2,
                         label=f"{acc} {rs}")
        axes[1].plot(xs, [max(r.get(work_key) or 0, 1e-3) for r in rr], color=st["color"], marker=st["marker"], ls=ls, ms=4)
        axes[2].plot(xs, [r.get("bytes_per_triangle") or float("nan") for r in rr], color=st["color"],
                     marker=st["marker"], ls=ls, ms=4)
    axes[0].set_ylabel("ratio to Embree (1 thread)\nbars: slowest-fastest repeat")
    axes[1].set_ylabel(work_key.replace("_", " "))
    axes[2].set_ylabel("bytes per triangle")
    xs_all = sorted({p[0] for pts in lines.values() for p in pts})
    for ax in axes:
        if xs_all[0] > 0 and xs_all[-1] / xs_all[0] >= 8:
            ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        log_ticks(ax, "y")
        ax.set_xlabel(param)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=7)
    scenes = sorted({r["scene"] for pts in lines.values() for _, r in pts})
    fig.suptitle(f"Sweep of {param} ({', '.join(scenes)})")
    footer(fig, header)
    save(fig, out, f"sweep_{param}", written)
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
    for (acc, fam), rs in sorted(by_acc.items(), key=lambda kv: (fams.index(kv[0][1]), kv[0][0])):
        rs = sorted(rs, key=lambda r: r["triangles"])
        n = [r["triangles"] for r in rs]
        style = dict(marker="o" if fam == fams[0] else "s", ms=3, ls="-" if fam == fams[0] else "--",
                     label=acc if fam == fams[0] else f"{acc} ({fam})")
        style["color"] = colour_of(acc)
        ns = [1e3 / r["mrays_per_s"] if r["mrays_per_s"] > 0 else float("nan") for r in rs]
        # Error bars: time per ray of the fastest and slowest repeats.
        below = [max(v - 1e3 / r["mrays_max"], 0) if r.get("mrays_max") else 0 for v, r in zip(ns, rs)]
        above = [max(1e3 / r["mrays_min"] - v, 0) if r.get("mrays_min") else 0 for v, r in zip(ns, rs)]
        axes[0].errorbar(n, ns, yerr=[below, above], capsize=2, **style)
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
        log_ticks(ax)
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
        ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", ms=3, label=acc, color=colour_of(acc))
    last = sorted(curves.items())[0][1]
    for wall, err, spp in last:
        ax.annotate(f"{spp} spp", (wall, err), fontsize=6, xytext=(3, 3), textcoords="offset points", color="gray")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time: build + render (s)")
    ax.set_ylabel("RMSE against the reference image")
    ref_rec = refs[0]
    ax.set_title(f"Equal-time rendering: {ref_rec['scene']} {ref_rec['width']}x{ref_rec['height']} "
                 f"(reference {ref_rec['accel']} {ref_rec['spp']} spp)\none render per point, build included", fontsize=9)
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
    ap.add_argument("--raylab", default=os.environ.get("RAYLAB", "build/raylab"),
                    help="the binary asked for the accelerator registry (raylab accels --json)")
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
    reg = registry(a.raylab)
    for entry in reg or []:
        if entry.get("colour"):
            REGISTRY_COLOURS[entry["name"]] = entry["colour"]
    header = load(a.bench) if a.bench else {}
    bench = records(a.bench) if a.bench else []
    if bench:
        chart_speed_vs_accuracy(bench, a.verify, a.stress, out, written, header)
        chart_build_vs_trace(bench, out, written, header)
        chart_speed_vs_memory(bench, out, written, header)
        if a.table:
            os.makedirs(os.path.dirname(os.path.abspath(a.table)), exist_ok=True)
            with open(a.table + ".tmp", "w") as f:
                f.write(markdown_table(bench, header))
                if a.scaling:
                    f.write(markdown_scaling_table(records(a.scaling)))
            os.replace(a.table + ".tmp", a.table)
    else:
        skipped += ["speed_vs_accuracy", "build_vs_trace", "speed_vs_memory"]
    sweep = [r for f in a.sweep for r in records(f)]
    sweep_header = load(a.sweep[0]) if a.sweep else {}
    params = swept_parameters(sweep)
    if not params:
        skipped.append("sweep_*")
    for param in sorted(params):
        if not chart_sweep(params[param], param, out, written, sweep_header):
            skipped.append(f"sweep_{param}")
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
