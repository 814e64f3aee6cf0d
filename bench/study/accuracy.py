"""Speed against accuracy: per structure or variant, its speed (geometric mean ratio to Embree over
the study's bench cells, one thread), its wrong hits per million rays (the exact oracle decided
against it: `raylab verify` on the study's scenes, `raylab stress` on its scenarios) and its
leaks per million (`raylab stress`, watertight scenarios: rays aimed at a closed mesh from
outside that passed through it).

verify's and stress's reference is Embree's robust mode, so `embree:robust=1` checked against
itself says nothing: its wrong hits are those the oracle found against the reference
(embree_wrong), the most any structure's comparison found per scene (scenario) and ray set.
"""
from records import geomean


def wrong_hits(records, spec):
    """(wrong hits, rays) of `spec` over verify or stress records; (0, 0) when not checked."""
    if spec == "embree:robust=1":
        worst = {}
        for v in records:
            key = (v.get("scenario") or v["scene"], v["ray_set"])
            n, rays = worst.get(key, (0, v["rays"]))
            worst[key] = (max(n, v.get("embree_wrong") or 0), max(rays, v["rays"]))
        return sum(w for w, _ in worst.values()), sum(r for _, r in worst.values())
    rows = [v for v in records if v["accel"] == spec]
    return sum(v.get("raylab_wrong") or 0 for v in rows), sum(v["rays"] for v in rows)


def wrong_hits_per_million(records, spec):
    """(wrong hits per million, rays); None when not checked."""
    n, rays = wrong_hits(records, spec)
    return (1e6 * n / rays if rays else None), rays


def leaks_per_million(stress, spec):
    """(leaks per million, leak rays) of `spec` over the stress records that aim leak rays."""
    rows = [s for s in stress if s["accel"] == spec and s.get("leak_rays")]
    if not rows:
        return None, 0
    leaks = sum(s.get("leaks") or 0 for s in rows)
    rays = sum(s["leak_rays"] for s in rows)
    return 1e6 * leaks / rays, rays


def points(study, specs):
    """One point per spec: speed, Mrays/s, wrong hits (verify, stress, both) and leaks per million."""
    out = []
    for spec in specs:
        rows = [r for r in study.records if r["accel"] == spec]
        if not rows:
            continue
        wv, rv = wrong_hits(study.verify, spec)
        ws, rs = wrong_hits(study.stress, spec)
        leaks, lrays = leaks_per_million(study.stress, spec)
        out.append({"accel": spec, "ratio": geomean([r["ratio_to_embree"] for r in rows]),
                    "mrays_per_s": geomean([r["mrays_per_s"] for r in rows]), "cells": len(rows),
                    "wrong_verify_per_million": 1e6 * wv / rv if rv else None, "verify_rays": rv,
                    "wrong_stress_per_million": 1e6 * ws / rs if rs else None, "stress_rays": rs,
                    "wrong_per_million": 1e6 * (wv + ws) / (rv + rs) if rv + rs else None,
                    "leaks_per_million": leaks, "leak_rays": lrays})
    return out
