"""The study's verdicts (bench/study/verdicts.py): noise marks, classes, the BES sentence and the
failure map, on synthetic bench records."""
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "bench", "study"))

import accuracy  # noqa: E402
import verdicts  # noqa: E402
from records import Study  # noqa: E402
from time_model import fit_records  # noqa: E402

SUITE = {"preset": "test", "tag": "native", "default_accels": ["embree", "bvh", "kdtree", "grid"],
         "variants": ["bvh:tri=mt"], "ray_sets": ["primary"],
         "scenes": {"teapot": {"spec": "../shared/scenes/spd/teapot_s6.obj", "classes": ["SPD"]},
                    "tetra": {"spec": "../shared/scenes/spd/tetra_s6.obj", "classes": ["SPD"]},
                    "stadium": {"spec": "stadium", "classes": ["teapot in a stadium"]}}}


def rec(scene, accel, ratio, spread=0.01, steps=None, tris=None, ray_set="primary", bytes_per_tri=60.0):
    """A one-thread record: Embree at 10 Mrays/s, this structure at ratio x that, its repeats
    within +-spread of the median."""
    m = 10.0 * ratio
    counted = not accel.startswith("embree")
    return {"scene": scene, "accel": accel, "ray_set": ray_set, "threads": 1, "triangles": 1000, "rays": 4096,
            "mrays_per_s": m, "mrays_min": m * (1 - spread), "mrays_max": m * (1 + spread),
            "embree_mrays_per_s": 10.0, "ratio_to_embree": ratio, "bytes_per_triangle": bytes_per_tri,
            "steps_per_ray": steps if counted else None, "tris_per_ray": tris if counted else None,
            "leaves_per_ray": 1.0 if counted else None, "empty_leaves_per_ray": 0.0 if counted else None}


def bench(records):
    return {"bvh_isa": "avx2", "embree_isa": "AVX2", "cpu": "test", "records": records}


class NoiseTest(unittest.TestCase):
    def test_margin_inside_the_noise_is_marked(self):
        # bvh 2 % ahead of kdtree, both repeating within +-5 %: the ranges overlap.
        s = Study(SUITE, bench([rec("../shared/scenes/spd/teapot_s6.obj", "embree", 1.0),
                                rec("../shared/scenes/spd/teapot_s6.obj", "bvh", 0.51, 0.05, 10, 5),
                                rec("../shared/scenes/spd/teapot_s6.obj", "kdtree", 0.50, 0.05, 20, 3),
                                rec("../shared/scenes/spd/teapot_s6.obj", "grid", 0.10, 0.05, 30, 40)]))
        [v] = verdicts.per_scene(s, SUITE["default_accels"])
        self.assertEqual(v["scene"], "teapot")
        self.assertEqual(v["winner"], "bvh")
        self.assertEqual(v["runner_up"], "kdtree")
        self.assertAlmostEqual(v["margin"], 0.02)
        self.assertTrue(v["within_noise"])

    def test_margin_beyond_the_noise_is_not_marked(self):
        s = Study(SUITE, bench([rec("stadium", "embree", 1.0), rec("stadium", "bvh", 0.8, 0.02, 10, 5),
                                rec("stadium", "kdtree", 0.5, 0.02, 20, 3), rec("stadium", "grid", 0.01, 0.02, 3, 900)]))
        [v] = verdicts.per_scene(s, SUITE["default_accels"])
        self.assertEqual(v["winner"], "bvh")
        self.assertAlmostEqual(v["margin"], 0.6)
        self.assertFalse(v["within_noise"])

    def test_embree_never_wins_and_variants_are_not_candidates(self):
        s = Study(SUITE, bench([rec("stadium", "embree", 1.0), rec("stadium", "bvh:tri=mt", 1.2, 0.01, 10, 5),
                                rec("stadium", "kdtree", 0.5, 0.01, 20, 3)]))
        [v] = verdicts.per_scene(s, SUITE["default_accels"])
        self.assertEqual(v["winner"], "kdtree")
        self.assertIsNone(v["runner_up"])


def spd_study():
    teapot, tetra = "../shared/scenes/spd/teapot_s6.obj", "../shared/scenes/spd/tetra_s6.obj"
    recs = []
    # bvh: 2 ns per step, 5 ns per test, 20 ns set-up; kdtree: the same costs, three times the steps.
    for scene, steps, tris in ((teapot, 20.0, 4.0), (tetra, 30.0, 12.0), ("stadium", 40.0, 5.0)):
        for accel, k, ct in (("bvh", 1.0, 1.0), ("kdtree", 3.0, 1.0)):
            ns = 2.0 * steps * k + 5.0 * tris * ct + 20.0
            recs.append(rec(scene, accel, 1000.0 / ns / 10.0, 0.01, steps * k, tris * ct))
        recs.append(rec(scene, "embree", 1.0))
        recs.append(rec(scene, "grid", 0.05, 0.01, 10.0, 2000.0, bytes_per_tri=500.0))
    # Two more ray sets' worth of cells for each fit.
    extra = []
    for r in recs:
        if r["accel"] in ("bvh", "kdtree", "grid"):
            for rs, f in (("random", 2.0), ("shadow", 0.5)):
                e = dict(r, ray_set=rs, steps_per_ray=r["steps_per_ray"] * f, tris_per_ray=r["tris_per_ray"] * f)
                k = {"bvh": (2.0, 5.0, 20.0), "kdtree": (2.0, 5.0, 20.0), "grid": (1.0, 4.0, 30.0)}[r["accel"]]
                ns = k[0] * e["steps_per_ray"] + k[1] * e["tris_per_ray"] + k[2]
                e.update(mrays_per_s=1000.0 / ns, mrays_min=990.0 / ns, mrays_max=1010.0 / ns,
                         ratio_to_embree=100.0 / ns)
                extra.append(e)
    return Study(SUITE, bench(recs + extra))


class VerdictTest(unittest.TestCase):
    def test_bes_names_the_winner_and_why_the_kdtree_loses(self):
        s = spd_study()
        models = {a: fit_records([r for r in s.records if r["accel"] == a]) for a in ("bvh", "kdtree", "grid")}
        b = verdicts.bes(s, SUITE["default_accels"], models)
        self.assertEqual(b["best"], "bvh")
        self.assertEqual(b["scenes"], ["teapot", "tetra"])
        self.assertFalse(b["holds"])
        self.assertGreater(b["havran_slower"], 1.5)
        self.assertEqual(b["why"]["cause"], "visits more")
        self.assertAlmostEqual(b["why"]["costs_more"], 1.0, places=3)
        sentence = verdicts.bes_sentence(b, s.isa)
        self.assertIn("does not hold", sentence)
        self.assertIn("because it visits more", sentence)
        self.assertIn("AVX2", sentence)

    def test_classes_take_their_own_scenes(self):
        s = spd_study()
        by = {v["class"]: v for v in verdicts.per_class(s, SUITE["default_accels"])}
        self.assertEqual(set(by), {"SPD", "teapot in a stadium"})
        self.assertEqual(by["teapot in a stadium"]["scenes"], ["stadium"])
        self.assertEqual(by["SPD"]["winner"], "bvh")
        self.assertEqual(by["SPD"]["runner_up"], "kdtree")

    def test_failure_map_names_the_slow_cells_and_their_cause(self):
        s = spd_study()
        models = {a: fit_records([r for r in s.records if r["accel"] == a]) for a in ("bvh", "kdtree", "grid")}
        fails = verdicts.failure_map(s, models)
        slow = [f for f in fails if f["kind"] == "slow"]
        self.assertEqual({f["accel"] for f in slow}, {"grid"})
        self.assertEqual({f["scene"] for f in slow}, {"teapot", "tetra", "stadium"})
        for f in slow:
            self.assertEqual(f["main"], "triangle tests")
            self.assertIn("triangle tests per ray (bvh", f["cause"])
            self.assertIn("bytes per triangle", f["cause"])

    def test_accuracy_points_count_wrong_hits_and_leaks(self):
        s = spd_study()
        s.verify = [{"scene": "stadium", "accel": "bvh", "ray_set": "primary", "rays": 1000, "raylab_wrong": 0,
                     "embree_wrong": 2},
                    {"scene": "stadium", "accel": "embree", "ray_set": "primary", "rays": 1000, "raylab_wrong": 3,
                     "embree_wrong": 0}]
        s.stress = [{"accel": "bvh", "scenario": "watertight_box", "ray_set": "stress", "rays": 1000, "leak_rays": 1000,
                     "leaks": 0, "raylab_wrong": 0, "embree_wrong": 0},
                    {"accel": "embree", "scenario": "watertight_box", "ray_set": "stress", "rays": 2000,
                     "leak_rays": 2000, "leaks": 5, "raylab_wrong": 1, "embree_wrong": 0}]
        pts = {p["accel"]: p for p in accuracy.points(s, ["embree", "bvh"])}
        self.assertEqual(pts["bvh"]["wrong_per_million"], 0.0)
        self.assertEqual(pts["embree"]["wrong_verify_per_million"], 3000.0)
        self.assertEqual(pts["embree"]["wrong_stress_per_million"], 500.0)
        self.assertEqual(pts["embree"]["wrong_per_million"], 4 / 3000 * 1e6)
        self.assertEqual(pts["embree"]["leaks_per_million"], 2500.0)
        self.assertEqual(accuracy.wrong_hits_per_million(s.verify, "embree:robust=1")[0], 2000.0)


if __name__ == "__main__":
    unittest.main()
