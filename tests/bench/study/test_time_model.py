"""The study's time model (bench/study/time_model.py) on synthetic records with known costs."""
import os
import random
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "bench", "study"))

import time_model  # noqa: E402


def synthetic(a, b, c, n=60, noise=0.0, seed=1):
    rng = random.Random(seed)
    rows = []
    for _ in range(n):
        steps = rng.uniform(2, 400)
        tris = rng.uniform(1, 200)
        ns = (a * steps + b * tris + c) * (1 + rng.uniform(-noise, noise))
        rows.append({"steps_per_ray": steps, "tris_per_ray": tris, "ns_per_ray": ns})
    return rows


class TimeModelTest(unittest.TestCase):
    def test_recovers_known_coefficients(self):
        m = time_model.fit_records(synthetic(2.5, 7.0, 30.0))
        self.assertAlmostEqual(m["a"], 2.5, places=6)
        self.assertAlmostEqual(m["b"], 7.0, places=6)
        self.assertAlmostEqual(m["c"], 30.0, places=4)
        self.assertAlmostEqual(m["r2"], 1.0, places=9)
        self.assertEqual(m["cells"], 60)

    def test_close_under_noise_and_r2_below_one(self):
        m = time_model.fit_records(synthetic(1.2, 4.0, 50.0, n=400, noise=0.05, seed=7))
        self.assertAlmostEqual(m["a"], 1.2, delta=0.1)
        self.assertAlmostEqual(m["b"], 4.0, delta=0.3)
        self.assertLess(m["r2"], 1.0)
        self.assertGreater(m["r2"], 0.9)

    def test_coefficients_stay_non_negative(self):
        # Time that falls with the triangle tests: least squares would give b < 0; NNLS gives 0.
        rows = [{"steps_per_ray": s, "tris_per_ray": t, "ns_per_ray": 3.0 * s + 100.0 - 0.2 * t}
                for s, t in [(10, 5), (50, 100), (100, 20), (200, 300), (30, 250), (150, 60)]]
        m = time_model.fit_records(rows)
        self.assertGreaterEqual(m["b"], 0.0)
        self.assertEqual(m["b"], 0.0)
        self.assertGreater(m["a"], 0.0)

    def test_cause_visits_more_or_costs_more(self):
        ref = {"a": 2.0, "b": 5.0, "c": 10.0}
        # Same costs, ten times the steps: it loses because it visits more.
        w = time_model.why_slower(ref, (100.0, 10.0), ref, (10.0, 10.0))
        self.assertEqual(w["cause"], "visits more")
        self.assertAlmostEqual(w["costs_more"], 1.0)
        self.assertAlmostEqual(w["model_ratio"], (200 + 50 + 10) / (20 + 50 + 10))
        # Same counts, four times the cost per step and test: each visit costs more.
        dear = {"a": 8.0, "b": 20.0, "c": 10.0}
        w = time_model.why_slower(dear, (10.0, 10.0), ref, (10.0, 10.0))
        self.assertEqual(w["cause"], "each visit costs more")
        self.assertAlmostEqual(w["visits_more"], 1.0)
        # Faster on both counts: it does not lose.
        self.assertEqual(time_model.why_slower(ref, (5.0, 5.0), ref, (10.0, 10.0))["cause"], "does not lose")

    def test_rejects_empty_and_non_positive_times(self):
        with self.assertRaises(ValueError):
            time_model.fit([], [], [])
        with self.assertRaises(ValueError):
            time_model.fit([1.0], [1.0], [0.0])


if __name__ == "__main__":
    unittest.main()
