"""The study's time model: per structure, time per ray = a * steps + b * triangle tests + c.

Fitted over every cell (scene x ray set) of the structure by non-negative least squares
(Lawson & Hanson; scipy.optimize.nnls) on relative residuals: each row is divided by the
cell's measured time, so a 40 ns cell and a 40 us cell weigh alike. a is the cost of one
traversal step, b of one triangle test, c of a ray's set-up, all in ns. R^2 is the share of the
(relatively weighted) variance of the time per ray that the model explains.

Why a structure loses to a reference (bvh): with mean counts (S, T) over the cells both ran,
    visits more          = model_s(S_s, T_s) / model_s(S_ref, T_ref)
    each visit costs more = model_s(S_ref, T_ref) / model_ref(S_ref, T_ref)
whose product is model_s(S_s, T_s) / model_ref(S_ref, T_ref); the larger factor names the cause.
"""
import math

import numpy as np
from scipy.optimize import nnls


def fit(steps, tris, ns):
    """Fits ns ~ a*steps + b*tris + c (a, b, c >= 0). Returns dict a, b, c (ns), r2, cells."""
    steps = np.asarray(steps, dtype=float)
    tris = np.asarray(tris, dtype=float)
    ns = np.asarray(ns, dtype=float)
    if len(ns) == 0:
        raise ValueError("time model: no cells to fit")
    if np.any(ns <= 0):
        raise ValueError("time model: times per ray must be positive")
    A = np.column_stack([steps, tris, np.ones_like(ns)])
    w = 1.0 / ns
    coef, _ = nnls(A * w[:, None], ns * w)
    pred = A @ coef
    # Weighted R^2 with the fit's weights (relative residuals).
    rel = (ns - pred) * w
    mean_w = np.sum(ns * w * w) / np.sum(w * w)
    tot = np.sum(((ns - mean_w) * w) ** 2)
    r2 = 1.0 - float(np.sum(rel ** 2) / tot) if tot > 0 else (1.0 if np.allclose(rel, 0) else 0.0)
    return {"a": float(coef[0]), "b": float(coef[1]), "c": float(coef[2]), "r2": r2, "cells": int(len(ns))}


def predict(model, steps, tris):
    return model["a"] * steps + model["b"] * tris + model["c"]


def fit_records(records):
    """The model of one structure from its bench records (those with counters)."""
    rows = [r for r in records if r.get("steps_per_ray") is not None and r.get("tris_per_ray") is not None]
    return fit([r["steps_per_ray"] for r in rows], [r["tris_per_ray"] for r in rows], [r["ns_per_ray"] for r in rows])


def why_slower(model_s, counts_s, model_ref, counts_ref):
    """Splits structure s's modelled time over the reference's into 'visits more' and 'each visit
    costs more' (see the module's comment). counts_* = (mean steps, mean triangle tests)."""
    t_ss = predict(model_s, *counts_s)
    t_sr = predict(model_s, *counts_ref)
    t_rr = predict(model_ref, *counts_ref)
    if t_sr <= 0 or t_rr <= 0:
        return None
    visits = t_ss / t_sr
    cost = t_sr / t_rr
    if visits <= 1 and cost <= 1:
        cause = "does not lose"
    else:
        cause = "visits more" if visits >= cost else "each visit costs more"
    return {"visits_more": visits, "costs_more": cost, "model_ratio": t_ss / t_rr, "cause": cause}


def mean_counts(records):
    """Arithmetic mean steps and triangle tests per ray over the records."""
    n = len(records)
    if n == 0:
        return (math.nan, math.nan)
    return (sum(r["steps_per_ray"] for r in records) / n, sum(r["tris_per_ray"] for r in records) / n)
