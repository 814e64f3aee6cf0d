"""The study's verdicts: the fastest structure per scene and ray set, per scene class, over the SPD
suite (Havran's "best efficiency scheme"), and the failure map.

Speed is the ratio to single-ray Embree timed in alternation in the same run (ratio_to_embree).
The noise of a cell is the range of its repeats: [ratio * slowest / median, ratio * fastest /
median]. A winner's margin over the runner-up is inside the noise when the two ranges overlap
(the winner's slowest repeat is no faster than the runner-up's fastest). Over a class the
ratios and both ends of the ranges are geometric means over the class's cells.
"""
from records import geomean, is_embree, structure_name
from time_model import mean_counts, why_slower

SLOW = 0.1  # the failure map's speed threshold: below 1/10 of Embree


def ratio_range(r):
    """(ratio to Embree, from the slowest repeat, from the fastest)."""
    ratio = r["ratio_to_embree"]
    med = r["mrays_per_s"]
    lo = ratio * r["mrays_min"] / med if r.get("mrays_min") else ratio
    hi = ratio * r["mrays_max"] / med if r.get("mrays_max") else ratio
    return ratio, lo, hi


def pick(candidates):
    """candidates: {accel: (ratio, lo, hi)}. The fastest, its runner-up, the margin (winner over
    runner-up - 1) and whether the margin is inside the noise (the ranges overlap)."""
    ranked = sorted(candidates.items(), key=lambda kv: -kv[1][0])
    if not ranked:
        return None
    (w, (wr, wlo, whi)) = ranked[0]
    out = {"winner": w, "ratio": wr, "range": [wlo, whi], "runner_up": None, "runner_up_ratio": None,
           "margin": None, "within_noise": False}
    if len(ranked) > 1:
        (ru, (rr, rlo, rhi)) = ranked[1]
        out.update(runner_up=ru, runner_up_ratio=rr, margin=wr / rr - 1.0 if rr > 0 else None,
                   within_noise=wlo <= rhi)
    return out


def per_scene(study, accels):
    """[{scene, ray_set, winner, ratio, runner_up, margin, within_noise}, ...] over the suite."""
    cells = study.by_key()
    out = []
    for name in study.scenes_run():
        for rs in study.ray_sets():
            cand = {a: ratio_range(cells[(name, a, rs)]) for a in accels
                    if not is_embree(a) and (name, a, rs) in cells}
            v = pick(cand)
            if v:
                out.append(dict(v, scene=name, ray_set=rs))
    return out


def group_ratios(study, accels, names):
    """{accel: (geomean ratio, geomean lo, geomean hi, cells)} over the scenes `names`, every ray set."""
    out = {}
    for a in accels:
        rows = [ratio_range(r) for r in study.records if r["accel"] == a and r["name"] in names]
        if rows:
            out[a] = (geomean([x[0] for x in rows]), geomean([x[1] for x in rows]), geomean([x[2] for x in rows]),
                      len(rows))
    return out


def per_class(study, accels):
    """Per class: the verdict over its scenes and ray sets, and every structure's mean."""
    out = []
    for c in study.classes():
        names = [n for n in study.scenes_run() if c in study.suite["scenes"][n]["classes"]]
        if not names:
            continue
        g = group_ratios(study, accels, names)
        cand = {a: v[:3] for a, v in g.items() if not is_embree(a)}
        v = pick(cand)
        if v:
            out.append(dict(v, **{"class": c, "scenes": names, "means": {a: x[0] for a, x in g.items()}}))
    return out


def compare_counts(study, accel, ref, names):
    """Mean (steps, triangle tests) of accel and ref over the cells both ran among `names`."""
    cells = study.by_key()
    mine, theirs = [], []
    for r in study.records:
        if r["accel"] != accel or r["name"] not in names or r.get("steps_per_ray") is None:
            continue
        o = cells.get((r["name"], ref, r["ray_set"]))
        if o is None or o.get("steps_per_ray") is None:
            continue
        mine.append(r)
        theirs.append(o)
    return mean_counts(mine), mean_counts(theirs), len(mine)


def explain(study, models, accel, ref, names):
    """Why accel is slower than ref over `names` (time model), with the counts."""
    if accel not in models or ref not in models:
        return None
    ca, cr, n = compare_counts(study, accel, ref, names)
    if n == 0:
        return None
    w = why_slower(models[accel], ca, models[ref], cr)
    if w is None:
        return None
    return dict(w, steps=ca[0], tris=ca[1], ref_steps=cr[0], ref_tris=cr[1], cells=n, ref=ref)


def bes(study, accels, models, havran="kdtree", suite_class="SPD"):
    """Havran's best efficiency scheme over the SPD suite: the structure with the best geometric
    mean, and how the SAH k-d tree (his verdict of 2000) compares."""
    names = [n for n in study.scenes_run() if suite_class in study.suite["scenes"][n]["classes"]]
    if not names:
        return None
    g = group_ratios(study, [a for a in accels if not is_embree(a)], names)
    if not g:
        return None
    ranked = sorted(g.items(), key=lambda kv: -kv[1][0])
    best, (best_ratio, _, _, cells) = ranked[0]
    out = {"class": suite_class, "scenes": names, "ray_sets": study.ray_sets(), "cells": cells, "best": best,
           "best_ratio": best_ratio, "havran": havran, "ranking": [[a, v[0]] for a, v in ranked]}
    if havran in g:
        out["havran_ratio"] = g[havran][0]
        out["holds"] = best == havran
        out["havran_slower"] = best_ratio / g[havran][0]
        out["why"] = None if best == havran else explain(study, models, havran, best, names)
    return out


def bes_sentence(b, isa):
    """The verdict in one sentence."""
    if not b:
        return "The SPD scenes were not run (../shared/scenes absent): no verdict."
    head = (f"Over the SPD suite ({len(b['scenes'])} scenes x {len(b['ray_sets'])} ray sets, one thread, kernels "
            f"{isa['kernels']}, Embree {isa['embree']}) the best efficiency scheme is `{b['best']}` at "
            f"{b['best_ratio']:.2f}x Embree (geometric mean)")
    if "havran_ratio" not in b:
        return head + f"; Havran's verdict of 2000, the SAH k-d tree, could not be checked (`{b['havran']}` not run)."
    if b["holds"]:
        return head + ": Havran's verdict of 2000, the SAH k-d tree, still holds."
    s = (head + f"; Havran's verdict of 2000, the SAH k-d tree, does not hold: `{b['havran']}` reaches "
         f"{b['havran_ratio']:.2f}x, {b['havran_slower']:.2f}x slower than `{b['best']}`")
    w = b.get("why")
    if w:
        if w["cause"] == "visits more":
            s += (f", because it visits more ({w['steps']:.1f} steps and {w['tris']:.1f} triangle tests per ray against "
                  f"{w['ref_steps']:.1f} and {w['ref_tris']:.1f}: {w['visits_more']:.2f}x the time at its own costs), "
                  f"not because each visit costs more ({w['costs_more']:.2f}x)")
        else:
            s += (f", because each visit costs more ({w['costs_more']:.2f}x the time at `{b['best']}`'s counts of "
                  f"{w['ref_steps']:.1f} steps and {w['ref_tris']:.1f} triangle tests per ray), more than it visits "
                  f"more ({w['steps']:.1f} steps and {w['tris']:.1f} triangle tests: {w['visits_more']:.2f}x)")
    return s + "."


def _fmt(x):
    if x is None:
        return "n/a"
    return f"{x:,.0f}" if x >= 100 else f"{x:.1f}" if x >= 10 else f"{x:.2f}"


def slow_cause(rows, ref_rows, model, bytes_per_tri, ref_bytes_per_tri):
    """The measured cause of slow cells: the time model's larger term first (steps or triangle
    tests), with the reference's counts, then memory when it is over twice the reference's."""
    steps = sum(r["steps_per_ray"] for r in rows) / len(rows)
    tris = sum(r["tris_per_ray"] for r in rows) / len(rows)
    rs = sum(r["steps_per_ray"] for r in ref_rows) / len(ref_rows) if ref_rows else None
    rt = sum(r["tris_per_ray"] for r in ref_rows) / len(ref_rows) if ref_rows else None
    step_part = f"{_fmt(steps)} steps per ray" + (f" (bvh {_fmt(rs)})" if rs is not None else "")
    tri_part = f"{_fmt(tris)} triangle tests per ray" + (f" (bvh {_fmt(rt)})" if rt is not None else "")
    if model:
        step_ns, tri_ns = model["a"] * steps, model["b"] * tris
        parts = [step_part, tri_part] if step_ns >= tri_ns else [tri_part, step_part]
        main = "steps" if step_ns >= tri_ns else "triangle tests"
    else:
        parts = [tri_part, step_part]
        main = "triangle tests"
    if bytes_per_tri and ref_bytes_per_tri and bytes_per_tri > 2 * ref_bytes_per_tri:
        parts.append(f"{bytes_per_tri:,.0f} bytes per triangle (bvh {ref_bytes_per_tri:,.0f})")
    return main, "; ".join(parts)


def accuracy_cause(spec):
    if spec == "embree":
        return "Embree's default (non-robust) traversal and triangle test"
    if spec.startswith("embree:"):
        return "Embree's robust mode, not watertight by construction"
    if "tri=mt" in spec:
        return "Moller-Trumbore triangle test (not watertight)"
    return "a watertight structure: a defect to fix"


def failure_map(study, models, ref="bvh"):
    """Every cell below 1/10 of Embree, with a wrong hit (verify) or a leak (stress), or skipped for
    memory, each with its measured cause. One entry per structure and scene (its ray sets listed)."""
    cells = study.by_key()
    out = []
    groups = {}
    for r in study.records:
        if is_embree(r["accel"]) or r["ratio_to_embree"] >= SLOW:
            continue
        groups.setdefault((r["accel"], r["name"]), []).append(r)
    for (accel, name), rows in groups.items():
        counted = [r for r in rows if r.get("steps_per_ray") is not None]
        ref_rows = [cells[(name, ref, r["ray_set"])] for r in counted if (name, ref, r["ray_set"]) in cells]
        ref_rows = [r for r in ref_rows if r.get("steps_per_ray") is not None]
        bpt = rows[0].get("bytes_per_triangle")
        ref_bpt = ref_rows[0].get("bytes_per_triangle") if ref_rows else None
        if counted:
            main, cause = slow_cause(counted, ref_rows, models.get(accel), bpt, ref_bpt)
        else:
            main, cause = "n/a", "no counters"
        out.append({"kind": "slow", "accel": accel, "scene": name, "main": main, "cause": cause,
                    "cells": [[r["ray_set"], r["ratio_to_embree"]] for r in rows]})
    wrong = {}
    for v in study.verify:
        w = wrong.setdefault((v["accel"], v["name"] or v["scene"]), [0, 0, []])
        w[0] += v.get("raylab_wrong") or 0
        w[1] += v["rays"]
        if v.get("raylab_wrong"):
            w[2].append(v["ray_set"])
    for v in study.stress:
        w = wrong.setdefault((v["accel"], "stress: " + (v.get("scenario") or v["scene"])), [0, 0, []])
        w[0] += v.get("raylab_wrong") or 0
        w[1] += v["rays"]
        if v.get("raylab_wrong"):
            w[2].append("stress rays")
    for (accel, name), (n, rays, sets) in wrong.items():
        if n == 0:
            continue
        out.append({"kind": "wrong", "accel": accel, "scene": name, "main": "wrong hits",
                    "cause": f"{n} wrong hits in {rays} rays ({1e6 * n / rays:,.0f} per million; {', '.join(sets)}): "
                             + accuracy_cause(accel), "cells": []})
    leaks = {}
    for s in study.stress:
        if s.get("leak_rays"):
            e = leaks.setdefault(s["accel"], {"leaks": 0, "rays": 0, "scenarios": []})
            e["leaks"] += s.get("leaks") or 0
            e["rays"] += s["leak_rays"]
            if s.get("leaks"):
                e["scenarios"].append(f"{s.get('scenario', s.get('scene'))} {1e6 * s['leaks'] / s['leak_rays']:,.0f}")
    for accel, e in leaks.items():
        if e["leaks"]:
            out.append({"kind": "leak", "accel": accel, "scene": "stress: watertight scenarios", "main": "leaks",
                        "cause": f"{e['leaks']} leaks in {e['rays']} rays ({1e6 * e['leaks'] / e['rays']:,.0f} per "
                                 f"million; per scenario: {', '.join(e['scenarios'])}): " + accuracy_cause(accel),
                        "cells": []})
    for s in study.skipped:
        out.append({"kind": "memory", "accel": s["accel"], "scene": s.get("name") or s["scene"], "main": "memory",
                    "cause": f"not built: {s['reason']}", "cells": []})
    order = {"memory": 0, "slow": 1, "wrong": 2, "leak": 3}
    out.sort(key=lambda e: (order[e["kind"]], structure_name(e["accel"]), e["accel"], e["scene"]))
    return out
