# Thin wrapper: every target installs missing dependencies first.
BUILD ?= build
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
CMAKE_FLAGS ?=

.PHONY: all deps configure build test demo bench bench-full bench-slurm-local study docs docs-pages report microbench clean

all: build

deps:
	@bash scripts/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS)

build: configure
	cmake --build $(BUILD) -j $(JOBS)

test: build
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

demo: build
	mkdir -p out
	./$(BUILD)/raylab render --scene cornell --accel bvh --spp 64 --size 512x512 -o out/cornell.png
	./$(BUILD)/raylab bench --scene cornell --accel all --ray-sets primary,random --quiet

# The benchmark study (workflow/Snakefile, configured by workflow/config.yaml): one job per
# cell, merged into out/bench/*.json, *.csv, charts, summary.md, heatmaps/, structures/ and
# report.html. It writes only under out/: `git status` stays clean. A rerun with nothing
# changed does nothing. SNAKEFLAGS adds options (e.g. SNAKEFLAGS=--forceall, or -n for a dry run).
SNAKEMAKE = snakemake -s workflow/Snakefile --cores $(JOBS) --config raylab=$(BUILD)/raylab
SNAKEFLAGS ?=

bench: configure
	cmake --build $(BUILD) -j $(JOBS) --target raylab
	$(SNAKEMAKE) preset=quick $(SNAKEFLAGS)

bench-full: configure
	cmake --build $(BUILD) -j $(JOBS) --target raylab
	$(SNAKEMAKE) preset=full $(SNAKEFLAGS)

# The quick workflow through a one-node Slurm cluster started on this machine
# (scripts/slurm-local.sh), compared cell by cell with a local run.
bench-slurm-local: configure
	cmake --build $(BUILD) -j $(JOBS) --target raylab
	BUILD=$(BUILD) bash scripts/slurm-local.sh test

# The report page of the last `make bench` (out/report.html, self-contained, and out/report.md).
report: configure
	cmake --build $(BUILD) -j $(JOBS) --target raylab
	./$(BUILD)/raylab report out/bench -o out/report.html

# The study (workflow/study.smk, the `study:` entry of workflow/config.yaml; docs/results.md):
# every structure on the scene suite (SPD, interiors, scanned, axis-aligned, slivers, teapot in
# a stadium, procedural), verify and stress, the time model, verdicts and failure map, written
# to out/study/<ISA tag>/ and out/study/results.md. A rerun with nothing changed does nothing.
# STUDY_PRESET=full is the long run (out/study-full/; on Slurm: docs/cluster.md).
# STUDY_MARCH=x86-64-v3 runs it for another ISA: raylab built in $(BUILD)-x86-64-v3 without
# -march=native, Embree capped at STUDY_EMBREE_ISA (RAYLAB_EMBREE_ISA, e.g. avx2), written to
# out/study/x86-64-v3/; the page then shows both.
STUDY_PRESET ?= quick
STUDY_MARCH ?=
STUDY_EMBREE_ISA ?=
STUDY_BUILD = $(if $(STUDY_MARCH),$(BUILD)-$(STUDY_MARCH),$(BUILD))
STUDY_TAG = $(if $(STUDY_MARCH),$(STUDY_MARCH),native)
STUDY_ROOT = $(if $(filter quick,$(STUDY_PRESET)),out/study,out/study-$(STUDY_PRESET))

study: deps
	cmake -S . -B $(STUDY_BUILD) -DCMAKE_BUILD_TYPE=Release \
	      $(if $(STUDY_MARCH),-DRAYLAB_NATIVE=OFF -DCMAKE_CXX_FLAGS=-march=$(STUDY_MARCH)) $(CMAKE_FLAGS)
	cmake --build $(STUDY_BUILD) -j $(JOBS) --target raylab
	RAYLAB_EMBREE_ISA=$(STUDY_EMBREE_ISA) snakemake -s workflow/Snakefile study --cores $(JOBS) $(SNAKEFLAGS) \
	    --config raylab=$(STUDY_BUILD)/raylab study_preset=$(STUDY_PRESET) study_tag=$(STUDY_TAG)

# Rewrites docs/results.md (its charts in docs/results_files/study/) and the README's headline
# block from the study (every ISA run under out/study/), running `make study` first (nothing to
# do when it is up to date).
docs: study
	/usr/bin/python3 -B bench/study/page.py --out docs/results.md --assets docs/results_files/study \
	    $(if $(wildcard docs/correctness.csv),--long-check docs/correctness.csv) $(STUDY_ROOT)/*/analysis.json
	/usr/bin/python3 scripts/update-readme-results.py README.md docs/results.md
	$(MAKE) docs-pages

# The generated blocks of the structure pages (docs/structures/<name>.md): parameters and
# statistics from `raylab accels --json`, numbers from docs/results.md. No study run: after a
# parameter changes, this alone brings the pages (and the docs check of `make test`) up to date.
docs-pages: configure
	cmake --build $(BUILD) -j $(JOBS) --target raylab
	/usr/bin/python3 scripts/docs.py generate --raylab $(BUILD)/raylab

microbench: configure
	cmake --build $(BUILD) -j $(JOBS) --target raylab_microbench
	./$(BUILD)/raylab_microbench

clean:
	rm -rf $(BUILD) out
