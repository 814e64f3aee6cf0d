#!/usr/bin/env bash
# Renders a contact sheet of Debian's assimp-testmodels in several formats and up-axis
# conventions (Y-up Collada/OBJ/PLY, the duck with its own camera; Z-up Blender, 3DS, Q3D and
# binary STL with --up z; the wuson in DXF and .X is -Z-up), to check the importer's framing,
# cameras and up axes by eye.
# Usage: scripts/render-testmodels.sh [OUT_DIR (default out/testmodels)] [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/testmodels}
build=${2:-build}
models=/usr/share/assimp/models
bash scripts/install-deps.sh
[ -x "$build/raylab" ] || { echo "render-testmodels: build raylab first (make build)" >&2; exit 2; }
mkdir -p "$out"
# file:up — the up axis each file was authored with.
list=(
  Collada/duck.dae:y OBJ/spider.obj:y PLY/cube.ply:y STL/Spider_binary.stl:z
  BLEND/HUMAN.blend:z BLEND/Suzanne_248.blend:z 3DS/fels.3ds:z
  DXF/wuson.dxf:-z X/Testwuson.X:-z Q3D/E-AT-AT.q3o:z
)
images=()
for item in "${list[@]}"; do
  file=${item%:*} up=${item##*:}
  name=$(echo "$file" | tr '/.' '__')
  "$build/raylab" render "$models/$file" --up "$up" -s 16 --size 256x256 -t 0 -q -o "$out/$name.png"
  images+=("$out/$name.png")
done
/usr/bin/python3 - "$out/sheet.png" "${images[@]}" <<'PY'
import sys, matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt, matplotlib.image as mpimg
out, files = sys.argv[1], sys.argv[2:]
cols = 5
rows = (len(files) + cols - 1) // cols
fig, axes = plt.subplots(rows, cols, figsize=(3 * cols, 3.2 * rows))
for ax in axes.flat:
    ax.axis("off")
for ax, f in zip(axes.flat, files):
    ax.imshow(mpimg.imread(f))
    ax.set_title(f.split("/")[-1][:-4], fontsize=8)
fig.tight_layout()
fig.savefig(out, dpi=80)
PY
echo "render-testmodels: $out/sheet.png"
