"""The study's analysis and page (bench/study/analyse.py, page.py) end to end on synthetic
records: the headline block, every section, the ISA named, and a second ISA's comparison."""
import copy
import os
import shutil
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "bench", "study"))

import analyse  # noqa: E402
import page  # noqa: E402
from test_verdicts import spd_study  # noqa: E402


class PageTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="study_page_")

    def tearDown(self):
        shutil.rmtree(self.dir)

    def test_page_has_every_section_and_names_the_isa(self):
        study = spd_study()
        a = analyse.analyse(study, os.path.join(self.dir, "charts"))
        for name in a["charts"].values():
            self.assertTrue(os.path.getsize(os.path.join(self.dir, "charts", name)) > 1000, name)
        b = copy.deepcopy(a)
        b["tag"], b["isa"] = "x86-64-v2", {"kernels": "SSE2", "embree": "SSE4.2"}
        b["cells"] = [c for c in b["cells"] if c[0] != "stadium"]  # fewer cells: compared on the common ones
        text = page.page([a, b], {"native": "native/charts", "x86-64-v2": "x86-64-v2/charts"})
        head = text[text.index("<!-- headline:begin -->"):text.index("<!-- headline:end -->")]
        self.assertIn("best efficiency scheme is `bvh`", head)
        self.assertIn("| SPD | 2 | `bvh` |", head)
        self.assertIn("Binary revision", head)
        for section in ("## The scene suite", "## Per scene and ray set", "## Per scene class",
                        "## Havran's best efficiency scheme", "## Havran's counts per ray", "## Time model",
                        "## Failure map", "## Speed against accuracy", "## Other instruction sets"):
            self.assertIn(section, text)
            body = text[text.index(section):]
            body = body[:body.index("\n## ", 3)] if "\n## " in body[3:] else body
            if section != "## The scene suite":  # the only section without a measured figure
                self.assertIn("kernels AVX2, Embree AVX2", body, section)
        self.assertIn("native/charts/time_model.png", text)
        self.assertIn("over the 6 scene and ray set cells every build ran", text)
        self.assertIn("x86-64-v2 (kernels SSE2, Embree SSE4.2)", text)

    def test_long_check_section_sums_the_rows_per_structure_and_names_its_run(self):
        a = analyse.analyse(spd_study(), os.path.join(self.dir, "charts"))
        prov = {"revision": "abc1234", "date": "2026-12-08T01:00:00Z", "cpu": "AMD EPYC", "threads": "2",
                "kernel_isa": "avx2", "embree": "3.13.5 AVX2", "compiler": "g++ 12.2.0"}

        def row(accel, scene, rays, wrong=0, ties=0, check="verify", leaks=0):
            return {"check": check, "scene": scene, "ray_set": "primary", "accel": accel, "rays": str(rays),
                    "hit_miss_disagree": "0", "prim_disagree": "0", "ties": str(ties), "raylab_wrong": str(wrong),
                    "embree_wrong": "0", "occlusion_disagree": "0", "leaks": str(leaks),
                    "leak_rays": "100" if check == "stress" else "0",
                    "status": "ok", **prov}
        rows = [row("bvh", "needles", 6000000, ties=3), row("bvh", "sponza", 5000000),
                row("kdtree", "needles", 4000000, wrong=1), row("bvh", "watertight_sphere", 1000, check="stress")]
        text = page.page([a], {"native": "native/charts"}, rows)
        section = text[text.index("## Ten million rays per structure"):]
        section = section[:section.index("\n## ", 3)]
        self.assertIn("| `bvh` | 11,001,000 (11,000,000 + 1,000) | 2 | 0 | 0 | 3 | 0 | 0 (100) |", section)
        self.assertIn("| `kdtree` | 4,000,000 (4,000,000 + 0) | 1 | 1 | 0 | 0 | 0 | 0 (0) |", section)
        self.assertIn("Long check: AMD EPYC (2 hardware threads), kernels AVX2, Embree 3.13.5 AVX2, g++ 12.2.0, "
                      "revision abc1234, 2026-12-08", section)
        self.assertIn("on 4,000,000 to 11,001,000 rays each (a run in progress", section)
        self.assertIn("on 2 scenes: needles, sponza;", section)
        self.assertNotIn("## Ten million rays", page.page([a], {"native": "native/charts"}))


if __name__ == "__main__":
    unittest.main()
