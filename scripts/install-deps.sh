#!/usr/bin/env bash
# Installs raylab's build and test dependencies from Debian packages, only what is missing.
# Idempotent: a second run on a complete machine does nothing and touches no network.
set -euo pipefail

packages=(
  cmake g++ make pkg-config git
  ccache             # rebuilds of many worktrees/branches share one compiler cache
  libembree-dev      # Embree 3: the reference accelerator
  libeigen3-dev      # vector math
  libstb-dev         # stb_image_write for PNG
  libtinyexr-dev     # OpenEXR output (small, no OpenImageIO)
  libtbb-dev         # parallel builds and tiled rendering
  libgtest-dev libgmock-dev  # googletest alone ships only sources
  libbenchmark-dev   # microbenchmarks
  libcli11-dev       # command line
  libfreetype-dev fonts-dejavu-core  # labels of the pictures (show, render --aov): FreeType, DejaVu Sans embedded
  libfmt-dev         # formatting
  nlohmann-json3-dev # JSON output and scene files
  libassimp-dev      # mesh import
  libgmp-dev         # exact arithmetic for the edge/vertex oracle
  clang libclang-rt-14-dev  # libFuzzer targets (scripts/fuzz.sh)
  python3-matplotlib # charts (run with /usr/bin/python3)
  python3-scipy      # the study's time model: non-negative least squares (bench/study/)
  chromium           # headless browser: tests load `raylab report` pages and screenshot them
  assimp-testmodels  # Assimp's sample files in many formats (scripts/render-testmodels.sh)
  snakemake          # the benchmark workflow (make bench, workflow/Snakefile)
  slurm-wlm munge    # a one-node Slurm cluster for the workflow's cluster test (make bench-slurm-local)
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "install-deps: installing ${missing[*]}" >&2
if [ "$(id -u)" -eq 0 ]; then
  sudo_cmd=()
elif command -v sudo >/dev/null 2>&1; then
  sudo_cmd=(sudo)
else
  echo "install-deps: missing packages (${missing[*]}) and not root, no sudo" >&2
  exit 1
fi

export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -q
"${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
