# Thin wrapper: every target installs missing dependencies first.
BUILD ?= build
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
CMAKE_FLAGS ?=

.PHONY: all deps configure build test demo bench bench-full microbench clean

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

# Timing sweeps and charts (scripts/run_bench.sh): out/bench/*.json, *.csv,
# out/bench/charts/*.png|svg; the quick preset also refreshes docs/charts/.
bench: configure
	cmake --build $(BUILD) -j $(JOBS) --target raylab
	BUILD=$(BUILD) bash scripts/run_bench.sh quick

bench-full: configure
	cmake --build $(BUILD) -j $(JOBS) --target raylab
	BUILD=$(BUILD) OUT=out/bench-full bash scripts/run_bench.sh full

microbench: configure
	cmake --build $(BUILD) -j $(JOBS) --target raylab_microbench
	./$(BUILD)/raylab_microbench

clean:
	rm -rf $(BUILD) out
