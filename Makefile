# Thin wrapper: every target installs missing dependencies first.
BUILD ?= build
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
CMAKE_FLAGS ?=

.PHONY: all deps configure build test demo bench bench-full bench-slurm-local docs docs-pages report microbench clean

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
	./$(BUILD)/raylab render --scene cornell --accel bvh --spp 64 --size 512x512 --out out/cornell.png
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

# Regenerates what the README and docs/results.md show, explicitly: runs the quick study,
# then writes docs/results.md (+ its charts in docs/results_files/), copies the plot.py charts
# there and the pictures to docs/pictures/, and replaces the README's headline block.
docs: bench
	./$(BUILD)/raylab report out/bench -o out/report.html --md docs/results.md
	mkdir -p docs/results_files docs/pictures
	cp out/bench/charts/*.png docs/results_files/
	cp out/bench/heatmaps/*.png out/bench/structures/*.png docs/pictures/
	sed -i -e 's|(\.\./out/bench/heatmaps/|(pictures/|' -e 's|(\.\./out/bench/structures/|(pictures/|' \
	       -e 's|(\.\./out/bench/charts/\([^)]*\)\.svg)|(results_files/\1.png)|' docs/results.md
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
