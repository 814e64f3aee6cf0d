# The study (`make study`; included by workflow/Snakefile, configured by the `study:` entry of
# workflow/config.yaml): Havran's comparison of spatial structures over one scene suite, with
# per-ray counts, a time model, verdicts, a failure map and speed against accuracy.
#
#   snakemake -s workflow/Snakefile study --cores 2                                # quick preset
#   snakemake -s workflow/Snakefile study --cores 2 --config study_preset=full
#   snakemake -s workflow/Snakefile study --profile workflow/profiles/slurm --config study_preset=full
#
# One job per scene times every structure of the preset on it (`raylab bench`, all ray sets,
# one thread): the scene is loaded and Embree built once per scene, which on the suite's
# 300k-800k-triangle meshes is most of the cost. Verify (the exact oracle's wrong hits) and
# stress (leaks) run the structures and their leaking variants. The analysis
# (bench/study/analyse.py) writes STUDY_OUT/analysis.json and its charts; the page
# (bench/study/page.py) reads every ISA's analysis under out/study/ and writes
# out/study/results.md, which `make docs` turns into docs/results.md and the README block.
#
# STUDY_OUT is out/study/<isa tag>/ (tag: `native` for the default build; `make study
# STUDY_MARCH=x86-64-v3` builds raylab for that ISA, caps Embree with RAYLAB_EMBREE_ISA and
# writes out/study/x86-64-v3/), out/study-<preset>/<tag>/ for presets other than quick.
import glob
import sys
import json

SC = config["study"]
STUDY_PRESET = config.get("study_preset", "quick")
if STUDY_PRESET not in SC["presets"]:
    raise ValueError(f"unknown study preset '{STUDY_PRESET}' (presets: {', '.join(SC['presets'])})")
SP = SC["presets"][STUDY_PRESET]
STUDY_ROOT = config.get("study_root") or ("out/study" if STUDY_PRESET == "quick" else f"out/study-{STUDY_PRESET}")
STUDY_TAG = str(config.get("study_tag") or "native")
STUDY_OUT = f"{STUDY_ROOT}/{STUDY_TAG}"
STUDY_PY = os.path.join(workflow.basedir, "..", "bench", "study")


def study_scene_missing(spec):
    """Why a scene of the suite cannot run here (its file, or a mesh its scene file names, is
    absent), or None."""
    if "/" not in spec and not spec.endswith((".json", ".ply", ".obj")):
        return None  # procedural
    if not os.path.exists(spec):
        return f"{spec} is absent"
    if spec.endswith(".json"):
        with open(spec) as f:
            scene = json.load(f)
        base = os.path.dirname(spec)
        for m in scene.get("meshes", []):
            if "file" in m and not os.path.exists(os.path.join(base, m["file"])):
                return f"{os.path.normpath(os.path.join(base, m['file']))} is absent"
    return None


# --config study_only=teapot,stadium runs those scenes of the suite only (a quick look).
STUDY_ONLY = [n for n in str(config.get("study_only") or "").split(",") if n]
for name in STUDY_ONLY:
    if name not in SC["scenes"]:
        raise ValueError(f"study_only: unknown scene '{name}' (scenes: {', '.join(SC['scenes'])})")
STUDY_SCENES = {name: s for name, s in SC["scenes"].items()
                if not study_scene_missing(s["spec"]) and (not STUDY_ONLY or name in STUDY_ONLY)}
for name, s in SC["scenes"].items():
    why = study_scene_missing(s["spec"])
    if why:
        print(f"study: scene {name} skipped: {why} (../shared/scenes beside the checkout provides it)",
              file=sys.stderr)
STUDY_VERIFY = [n for n in SP["verify"]["scenes"] if n in STUDY_SCENES]
STUDY_ACCELS = SP["accels"] + SP.get("variants", [])

wildcard_constraints:
    scene=r"[A-Za-z0-9_]+",


def study_bench_command(name, json_out):
    s = STUDY_SCENES[name]
    return (f"{RAYLAB} bench --scene '{s['spec']}' --accel '{','.join(STUDY_ACCELS)}' --threads 1 "
            f"{FLAG['bench_ray_sets']} {','.join(SP['ray_sets'])} {FLAG['bench_random_rays']} {SP['random_rays']} "
            f"{SP['bench_args']} --quiet {FLAG['out']} {json_out}")


rule study:
    """The study: every record, the analysis and the page (out/study/results.md)."""
    input: f"{STUDY_ROOT}/results.md"


rule study_suite:
    """The suite as run: each scene's spec and classes, and the scenes skipped with why."""
    output: f"{STUDY_OUT}/suite.json"
    params:
        suite=lambda w: json.dumps({name: dict(s, missing=study_scene_missing(s["spec"]))
                                    for name, s in SC["scenes"].items()}),
        preset=STUDY_PRESET, accels=STUDY_ACCELS, tag=STUDY_TAG,
    run:
        with open(output[0], "w") as f:
            json.dump({"preset": params.preset, "tag": params.tag, "accels": params.accels,
                       "default_accels": SP["accels"], "variants": SP.get("variants", []),
                       "ray_sets": SP["ray_sets"], "scenes": json.loads(params.suite)}, f, indent=1)


rule study_bench:
    """Every structure and variant of the preset on one scene, every ray set, one thread."""
    input: RAYLAB
    output: f"{STUDY_OUT}/bench/{{scene}}.json"
    log: f"{STUDY_OUT}/bench/{{scene}}.txt"
    benchmark: f"{STUDY_OUT}/jobs/bench_{{scene}}.tsv"
    params: cmd=lambda w, output: study_bench_command(w.scene, output[0])
    threads: NODE_CORES
    resources:
        # Every structure is built in the job: memory for the hungriest one's build.
        mem_mb=lambda w: job_mem_mb("bench", STUDY_SCENES[w.scene]["spec"], ";".join(STUDY_ACCELS), SP["random_rays"],
                                     len(SP["ray_sets"])),
        runtime=lambda w: 4 * cell_runtime_min(STUDY_SCENES[w.scene]["spec"]),
        exclusive=1,
    shell: "{params.cmd} > {log} 2>&1"


rule study_merge:
    input: expand(f"{STUDY_OUT}/bench/{{scene}}.json", scene=STUDY_SCENES)
    output: json=f"{STUDY_OUT}/bench.json", csv=f"{STUDY_OUT}/bench.csv"
    params: preset=STUDY_PRESET
    shell: "{PY} {SCRIPTS}/merge_records.py --preset {params.preset} --out {output.json} {input}"


rule study_verify:
    """Hit-by-hit agreement with the exact oracle (wrong hits per million), structures and variants."""
    input: RAYLAB
    output: f"{STUDY_OUT}/verify/{{scene}}.json"
    log: f"{STUDY_OUT}/verify/{{scene}}.txt"
    benchmark: f"{STUDY_OUT}/jobs/verify_{{scene}}.tsv"
    params:
        spec=lambda w: STUDY_SCENES[w.scene]["spec"],
        accels=";".join(STUDY_ACCELS),
        sets=f"{FLAG['verify_ray_sets']} {','.join(SP['ray_sets'])} {FLAG['verify_rays']} {SP['verify']['rays']}",
    threads: NODE_CORES
    resources:
        mem_mb=lambda w: job_mem_mb("verify", STUDY_SCENES[w.scene]["spec"], ";".join(STUDY_ACCELS),
                                    SP["verify"]["rays"], len(SP["ray_sets"])),
        runtime=60,
    # Exit code 1 = disagreements found: recorded in the JSON, not a failure of the run.
    shell: "{RAYLAB} verify --scene '{params.spec}' --accel '{params.accels}' {params.sets} --threads {threads} {FLAG[out]} {output} > {log} 2>&1 || [ $? -eq 1 ]"


rule study_stress:
    """Watertight scenarios: leaks per million for every structure and variant."""
    input: RAYLAB
    output: f"{STUDY_OUT}/stress.json"
    log: f"{STUDY_OUT}/stress.txt"
    benchmark: f"{STUDY_OUT}/jobs/stress.tsv"
    params: accels=",".join(STUDY_ACCELS), args=SP["stress"]
    threads: NODE_CORES
    resources: mem_mb=2048, runtime=60
    # Exit code 1 = a watertight accelerator leaked or gave a wrong hit: recorded and charted.
    shell: "{RAYLAB} stress {params.args} --accel '{params.accels}' --threads {threads} {FLAG[out]} {output} > {log} 2>&1 "
           "|| [ $? -eq 1 ]"


rule study_analysis:
    """Time model, verdicts, failure map, speed against accuracy: analysis.json and the charts."""
    input:
        suite=f"{STUDY_OUT}/suite.json", bench=f"{STUDY_OUT}/bench.json", stress=f"{STUDY_OUT}/stress.json",
        verify=expand(f"{STUDY_OUT}/verify/{{scene}}.json", scene=STUDY_VERIFY),
        jobs=[f"{STUDY_OUT}/jobs/stress.tsv"] + expand(f"{STUDY_OUT}/jobs/bench_{{scene}}.tsv", scene=STUDY_SCENES)
             + expand(f"{STUDY_OUT}/jobs/verify_{{scene}}.tsv", scene=STUDY_VERIFY),
        code=glob.glob(os.path.join(STUDY_PY, "*.py")),
    output: json=f"{STUDY_OUT}/analysis.json", charts=directory(f"{STUDY_OUT}/charts")
    threads: 1
    resources: mem_mb=2048, runtime=30
    shell: "{PY} -B {STUDY_PY}/analyse.py --suite {input.suite} --bench {input.bench} --stress {input.stress} "
           "--verify {input.verify} --jobs {input.jobs} --out {output.json} --charts {output.charts}"


def study_analyses(wildcards):
    """This ISA's analysis and every other ISA's already under the study's root."""
    found = sorted(glob.glob(f"{STUDY_ROOT}/*/analysis.json"))
    mine = f"{STUDY_OUT}/analysis.json"
    return [mine] + [a for a in found if a != mine]


rule study_page:
    """The results page from every ISA's analysis (this one first)."""
    input: analyses=study_analyses, code=glob.glob(os.path.join(STUDY_PY, "*.py"))
    output: f"{STUDY_ROOT}/results.md"
    threads: 1
    shell: "{PY} -B {STUDY_PY}/page.py --out {output} {input.analyses}"
