"""The study's records: bench, verify and stress reports read once, each bench record named by
its scene of the suite (workflow/config.yaml, `study: scenes:`) and carrying the ISA of the run.

Only one-thread bench records are used (the study times one thread). Time per ray in ns is
1e3 / Mrays/s; Havran's counts are the records' steps_per_ray, leaves_per_ray,
empty_leaves_per_ray and tris_per_ray (null for Embree, which has no counters).
"""
import json
import math
import os


def geomean(values):
    """Geometric mean of the positive values; None when there are none."""
    vals = [v for v in values if v is not None and v > 0 and math.isfinite(v)]
    if not vals:
        return None
    return math.exp(sum(math.log(v) for v in vals) / len(vals))


def is_embree(spec):
    return spec == "embree" or spec.startswith("embree:")


def structure_name(spec):
    """'kdtree:tri=mt' -> 'kdtree'."""
    return spec.split(":", 1)[0]


def load_json(path):
    with open(path) as f:
        return json.load(f)


def isa_of(header):
    """The ISA of raylab's kernels and of Embree, from a report's header."""
    return {"kernels": str(header.get("bvh_isa") or "unknown").upper(),
            "embree": str(header.get("embree_isa") or "unknown").upper()}


def machine_of(header):
    return {"cpu": header.get("cpu"), "hardware_threads": header.get("hardware_threads"),
            "embree": header.get("embree"), "compiler": header.get("compiler"), "flags": header.get("flags"),
            "revision": header.get("revision"), "date": header.get("date")}


def scene_names(suite):
    """Record scene field -> suite name: by spec, and by the spec's file name."""
    out = {}
    for name, s in suite["scenes"].items():
        spec = s["spec"]
        out[spec] = name
        out[os.path.normpath(spec)] = name
        out.setdefault(os.path.basename(spec), name)
    return out


def name_scene(rec_scene, names):
    if rec_scene in names:
        return names[rec_scene]
    if os.path.normpath(rec_scene) in names:
        return names[os.path.normpath(rec_scene)]
    return names.get(os.path.basename(rec_scene))


class Study:
    """Everything the analysis reads: the suite, the one-thread bench records (with `name`,
    `classes`, `ns_per_ray`), skips, verify and stress records, ISA and machine."""

    def __init__(self, suite, bench, verify=(), stress=None):
        self.suite = suite
        self.isa = isa_of(bench)
        self.machine = machine_of(bench)
        names = scene_names(suite)
        self.records = []
        for r in bench.get("records", []):
            if r.get("threads") != 1 or not r.get("mrays_per_s"):
                continue
            name = name_scene(r["scene"], names)
            if name is None:
                continue
            r = dict(r)
            r["name"] = name
            r["classes"] = suite["scenes"][name]["classes"]
            r["ns_per_ray"] = 1e3 / r["mrays_per_s"]
            r["isa"] = self.isa
            self.records.append(r)
        self.skipped = []
        for s in bench.get("skipped", []):
            name = name_scene(s["scene"], names)
            self.skipped.append(dict(s, name=name))
        self.verify = []
        for v in verify:
            for r in v.get("records", []):
                self.verify.append(dict(r, name=name_scene(r["scene"], names)))
        self.stress = list(stress.get("records", [])) if stress else []

    @classmethod
    def from_files(cls, suite_path, bench_path, verify_paths=(), stress_path=None):
        return cls(load_json(suite_path), load_json(bench_path), [load_json(p) for p in verify_paths],
                   load_json(stress_path) if stress_path else None)

    def default_accels(self):
        return list(self.suite.get("default_accels", []))

    def variants(self):
        return list(self.suite.get("variants", []))

    def scenes_run(self):
        """Suite names with records, in the suite's order."""
        have = {r["name"] for r in self.records}
        return [n for n in self.suite["scenes"] if n in have]

    def classes(self):
        out = []
        for s in self.suite["scenes"].values():
            for c in s["classes"]:
                if c not in out:
                    out.append(c)
        return out

    def ray_sets(self):
        out = []
        for r in self.records:
            if r["ray_set"] not in out:
                out.append(r["ray_set"])
        return out

    def cell(self, name, accel, ray_set):
        for r in self.records:
            if r["name"] == name and r["accel"] == accel and r["ray_set"] == ray_set:
                return r
        return None

    def by_key(self):
        """(name, accel, ray_set) -> record."""
        return {(r["name"], r["accel"], r["ray_set"]): r for r in self.records}
