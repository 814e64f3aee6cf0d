#!/usr/bin/python3
"""Checks that two runs of the benchmark workflow recorded the same cells and the same hits.

  compare_records.py DIR_A DIR_B

Times differ between runs; what must not: the set of cells, and every figure that depends
only on the scene, the structure and the rays. Per file kind:
  bench.json, scaling.json, sweep_*.json  cells (scene, accel, ray set, threads) and their
      triangles, rays, agreement with Embree, nodes and triangles per ray, bytes, nodes,
      leaves, depth; the skipped cells and their reasons' structure. One exception: Embree's
      bytes in a cell built on more than one thread agree within 10 %, not exactly (its
      allocator hands each build thread its own blocks, so the total depends on scheduling)
  verify_*.json   every counter of every (scene, accel, ray set) (build_ms aside)
  stress.json     every (scenario, accel), its status (slow counted as ok: that one is a speed
                  ratio) and verdict; the counters when neither run subsampled (the time budget
                  subsamples slow structures)
  equal_time/     the same renders (rays, shadow rays) and byte-identical images
Exit status 0 when all agree, 1 with one line per difference otherwise.
"""
import glob
import hashlib
import json
import os
import sys

BENCH_SAME = ["triangles", "rays", "embree_agreement", "nodes_per_ray", "tris_per_ray", "bytes", "nodes",
              "leaves", "max_depth"]
STRESS_COUNTS = ["rays", "hit_miss_disagree", "prim_disagree", "ties", "raylab_wrong", "embree_wrong",
                 "occlusion_disagree", "leak_rays", "leaks"]

problems = []


def load(path):
    with open(path) as f:
        return json.load(f)


def keyed(records, fields, what):
    out = {}
    for r in records:
        k = tuple(r.get(f) for f in fields)
        if k in out:
            problems.append(f"{what}: duplicate cell {k}")
        out[k] = r
    return out


def embree_multithread_bytes_agree(x, y):
    """Embree's builder allocates per-thread blocks (its FastAllocator), so with several build
    threads the bytes it reports vary a few per cent from run to run; the hits do not."""
    if x.get("accel") != "embree" or (x.get("threads") or 1) <= 1:
        return False
    bx, by = x.get("bytes"), y.get("bytes")
    if not isinstance(bx, (int, float)) or not isinstance(by, (int, float)) or max(bx, by) <= 0:
        return False
    return abs(bx - by) <= 0.10 * max(bx, by)


def compare_keyed(a, b, what, same):
    for k in sorted(set(a) | set(b), key=str):
        if k not in a or k not in b:
            problems.append(f"{what}: cell {k} only in {'second' if k not in a else 'first'} run")
            continue
        for f in same(a[k], b[k]):
            if f == "bytes" and embree_multithread_bytes_agree(a[k], b[k]):
                continue
            if a[k].get(f) != b[k].get(f):
                problems.append(f"{what}: {k}: {f} {a[k].get(f)!r} != {b[k].get(f)!r}")


def compare_bench(pa, pb, what):
    a, b = load(pa), load(pb)
    fields = ("scene", "accel", "ray_set", "threads")
    compare_keyed(keyed(a["records"], fields, what), keyed(b["records"], fields, what), what, lambda x, y: BENCH_SAME)
    sa = sorted((s.get("scene"), s.get("accel")) for s in a.get("skipped", []))
    sb = sorted((s.get("scene"), s.get("accel")) for s in b.get("skipped", []))
    if sa != sb:
        problems.append(f"{what}: skipped cells differ: {sa} != {sb}")


def compare_verify(pa, pb, what):
    fields = ("scene", "accel", "ray_set")
    a, b = keyed(load(pa)["records"], fields, what), keyed(load(pb)["records"], fields, what)
    compare_keyed(a, b, what, lambda x, y: sorted((set(x) | set(y)) - {"build_ms"}))


def compare_stress(pa, pb, what):
    fields = ("scenario", "accel")
    a, b = keyed(load(pa)["records"], fields, what), keyed(load(pb)["records"], fields, what)

    def same(x, y):
        # "slow" is "ok" below a speed ratio to Embree: a timing, not a hit.
        for r in (x, y):
            if r.get("status") == "slow":
                r["status"] = "ok"
        fixed = ["status", "ok", "triangles", "watertight_test"]
        return fixed + (STRESS_COUNTS if not x.get("subsampled") and not y.get("subsampled") else [])

    compare_keyed(a, b, what, same)


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def compare_renders(da, db):
    na = sorted(os.path.basename(p) for p in glob.glob(os.path.join(da, "*.json")))
    nb = sorted(os.path.basename(p) for p in glob.glob(os.path.join(db, "*.json")))
    if na != nb:
        problems.append(f"equal_time: different renders: {sorted(set(na) ^ set(nb))}")
    for name in sorted(set(na) & set(nb)):
        ra, rb = load(os.path.join(da, name))["records"][0], load(os.path.join(db, name))["records"][0]
        for f in ("scene", "accel", "spp", "seed", "width", "height", "rays", "shadow_rays"):
            if ra.get(f) != rb.get(f):
                problems.append(f"equal_time/{name}: {f} {ra.get(f)!r} != {rb.get(f)!r}")
        pfm = name[:-5] + ".pfm"
        if digest(os.path.join(da, pfm)) != digest(os.path.join(db, pfm)):
            problems.append(f"equal_time/{pfm}: images differ")
    return len(na)


def pair(da, db, name):
    """Both paths when the file is in both runs; None when in neither; a problem when in one."""
    pa, pb = os.path.join(da, name), os.path.join(db, name)
    if os.path.exists(pa) and os.path.exists(pb):
        return pa, pb
    if os.path.exists(pa) or os.path.exists(pb):
        problems.append(f"{name}: only in {da if os.path.exists(pa) else db}")
    return None


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    da, db = sys.argv[1], sys.argv[2]
    counts = {}

    def names(pattern):
        return sorted({os.path.basename(p) for d in (da, db) for p in glob.glob(os.path.join(d, pattern))})

    for name in ["bench.json", "scaling.json"] + names("sweep_*.json"):
        if (p := pair(da, db, name)):
            compare_bench(*p, name)
            counts[name] = len(load(p[0])["records"])
    for name in names("verify_*.json"):
        if (p := pair(da, db, name)):
            compare_verify(*p, name)
            counts[name] = len(load(p[0])["records"])
    if (p := pair(da, db, "stress.json")):
        compare_stress(*p, "stress.json")
        counts["stress.json"] = len(load(p[0])["records"])
    if os.path.isdir(os.path.join(da, "equal_time")) or os.path.isdir(os.path.join(db, "equal_time")):
        counts["equal_time"] = compare_renders(os.path.join(da, "equal_time"), os.path.join(db, "equal_time"))
    if not counts:
        problems.append(f"no records in {da} or {db}")
    for line in problems:
        print(line)
    summary = ", ".join(f"{k} {v}" for k, v in counts.items())
    if problems:
        print(f"compare_records: {len(problems)} differences ({summary})")
        sys.exit(1)
    print(f"compare_records: same cells and hits ({summary})")


if __name__ == "__main__":
    main()
