"""The study's charts (matplotlib, PNG): the time model's steps against cost per step with
iso-time curves, the model against the measured times, the per-class speeds, and speed against
accuracy. Each title names the ISA of the run."""
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MARKERS = {"primary": "o", "diffuse": "s", "shadow": "^", "random": "D"}


def colours(accels):
    cmap = plt.get_cmap("tab20")
    return {a: cmap(i % 20) for i, a in enumerate(accels)}


def isa_label(isa):
    return f"kernels {isa['kernels']}, Embree {isa['embree']}"


def save(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def steps_vs_cost(points, accels, isa, path):
    """points: [{accel, ray_set, steps, ns}] (geometric means over the scenes): x = steps per ray,
    y = ns per step = ns per ray / steps; a point's time per ray is x * y, so the iso-time
    curves are hyperbolas."""
    col = colours(accels)
    fig, ax = plt.subplots(figsize=(8.5, 6))
    pts = [p for p in points if p["steps"] and p["steps"] > 0 and p["ns"]]
    if not pts:
        ax.text(0.5, 0.5, "no counted cells", ha="center", transform=ax.transAxes)
        save(fig, path)
        return
    xs = [p["steps"] for p in pts]
    ys = [p["ns"] / p["steps"] for p in pts]
    x0, x1 = min(xs) / 2, max(xs) * 2
    y0, y1 = min(ys) / 2, max(ys) * 2
    for t in (10, 30, 100, 300, 1000, 3000, 10000, 30000, 100000):
        xx = [x0 * (x1 / x0) ** (i / 50) for i in range(51)]
        ax.plot(xx, [t / x for x in xx], color="0.85", lw=0.8, zorder=0)
        # Labelled where the curve leaves the plot: the top edge, else the right edge.
        xl = t / (y1 / 1.15)
        if not x0 <= xl <= x1:
            xl = x1 / 1.6
        if x0 <= xl <= x1 and y0 <= t / xl <= y1:
            ax.annotate(f"{t:g} ns/ray", (xl, t / xl), fontsize=7, color="0.5")
    for p, x, y in zip(pts, xs, ys):
        ax.scatter([x], [y], color=col.get(p["accel"], "k"), marker=MARKERS.get(p["ray_set"], "o"), s=36,
                   edgecolor="k", linewidth=0.4, zorder=3)
        if p["ray_set"] == "primary":
            ax.annotate(p["accel"], (x, y), fontsize=7, xytext=(4, 3), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_xlabel("traversal steps per ray (inner nodes or cells visited)")
    ax.set_ylabel("ns per step (time per ray / steps per ray)")
    ax.set_title(f"Steps against cost per step, grey: equal time per ray (1 thread; {isa_label(isa)})", fontsize=9)
    for rs, m in MARKERS.items():
        ax.scatter([], [], marker=m, color="w", edgecolor="k", label=rs)
    ax.legend(fontsize=7, loc="lower left", title="ray set", title_fontsize=7)
    save(fig, path)


def model_fit(cells, accels, isa, path):
    """cells: [{accel, ns, predicted}]: measured against modelled time per ray."""
    col = colours(accels)
    fig, ax = plt.subplots(figsize=(6.5, 6))
    for a in accels:
        mine = [c for c in cells if c["accel"] == a]
        if mine:
            ax.scatter([c["ns"] for c in mine], [max(c["predicted"], 1e-3) for c in mine], s=10, color=col[a],
                       label=a, edgecolor="none")
    vals = [c["ns"] for c in cells] + [c["predicted"] for c in cells if c["predicted"] > 0]
    if vals:
        lo, hi = min(vals) / 2, max(vals) * 2
        ax.plot([lo, hi], [lo, hi], color="0.5", lw=0.8)
        ax.set_xlim(lo, hi)
        ax.set_ylim(lo, hi)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("measured ns per ray")
    ax.set_ylabel("a*steps + b*triangle tests + c (ns per ray)")
    ax.set_title(f"Time model against the measurement, every cell ({isa_label(isa)})", fontsize=9)
    ax.legend(fontsize=6, ncol=2)
    save(fig, path)


def per_class(table, classes, accels, isa, path):
    """Heat map: class x structure, geometric mean ratio to Embree (log colour scale)."""
    acc = [a for a in accels if any(table.get(c, {}).get(a) for c in classes)]
    fig, ax = plt.subplots(figsize=(1.0 + 0.62 * len(acc), 0.9 + 0.42 * len(classes)))
    data = [[table.get(c, {}).get(a) or float("nan") for a in acc] for c in classes]
    logd = [[math.log10(v) if v == v and v > 0 else float("nan") for v in row] for row in data]
    ax.imshow(logd, cmap="RdYlGn", vmin=-2, vmax=0.2, aspect="auto")
    for i, row in enumerate(data):
        best = max((v for a, v in zip(acc, row) if v == v and not a.startswith("embree")), default=None)
        for j, v in enumerate(row):
            if v == v:
                ax.text(j, i, f"{v:.2f}" if v >= 0.1 else f"{v:.3f}", ha="center", va="center", fontsize=7,
                        fontweight="bold" if v == best else "normal")
    ax.set_xticks(range(len(acc)))
    ax.set_xticklabels(acc, rotation=45, ha="right", fontsize=8)
    ax.set_yticks(range(len(classes)))
    ax.set_yticklabels(classes, fontsize=8)
    ax.set_title(f"Speed relative to Embree per scene class (geometric mean, 1 thread; {isa_label(isa)})",
                 fontsize=9)
    save(fig, path)


def speed_vs_accuracy(points, isa, path):
    """Two panels: wrong hits per million (verify) and leaks per million (stress) against speed."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.8), sharey=True)
    for ax, key, label in ((axes[0], "wrong_per_million", "wrong hits per million rays (exact oracle: verify, stress)"),
                           (axes[1], "leaks_per_million", "leaks per million rays (stress, watertight scenarios)")):
        for p in points:
            if p[key] is None:
                continue
            leaky = p[key] > 0
            ax.scatter([p[key]], [p["ratio"]], s=40, color="tab:red" if leaky else "tab:blue", edgecolor="k",
                       linewidth=0.4, zorder=3)
            ax.annotate(p["accel"], (p[key], p["ratio"]), fontsize=7, xytext=(4, 2), textcoords="offset points")
        ax.set_xscale("symlog", linthresh=1.0)
        ax.set_xlim(-0.5, max([10.0] + [3 * p[key] for p in points if p[key]]))
        ax.set_yscale("log")
        ax.set_xlabel(label + "; 0 is drawn at 0")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("speed relative to Embree (geometric mean, 1 thread)")
    fig.suptitle(f"Speed against accuracy ({isa_label(isa)}); red: answers wrong or leaks", fontsize=10)
    save(fig, path)

