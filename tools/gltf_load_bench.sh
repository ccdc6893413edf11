#!/usr/bin/env bash
# Loading a 1.31M-triangle mesh from glTF (GLB) against the same mesh from
# PLY: seconds and peak resident memory, one process per measurement,
# alternating A B A B, medians of REPS (default 7) each. See docs/gltf.md.
#
#   tools/gltf_load_bench.sh [REPS]
#
# Needs python3 with numpy (PYTHON=..., default python3) for the mesh
# generator in ../shared/bench/genmesh.py and tools/ply_to_glb.py.
set -euo pipefail
REPS=${1:-7}
PY=${PYTHON:-python3}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
"$PY" "$ROOT/../shared/bench/genmesh.py" 8 "$WORK" >/dev/null
"$PY" "$ROOT/tools/ply_to_glb.py" "$WORK/bumpy_sphere_L8.ply" "$WORK/bumpy_sphere_L8.glb" >/dev/null
cargo build --release --example load_time -q --manifest-path "$ROOT/Cargo.toml"
BIN=${CARGO_TARGET_DIR:-$ROOT/target}/release/examples/load_time
ls -l "$WORK"/bumpy_sphere_L8.{ply,glb} | awk '{print $5, $9}'
for _ in $(seq "$REPS"); do
    echo "gltf $("$BIN" gltf "$WORK/bumpy_sphere_L8.glb")"
    echo "ply $("$BIN" ply "$WORK/bumpy_sphere_L8.ply")"
done | tee "$WORK/runs"
median() { sort -n | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
for k in gltf ply; do
    s=$(awk -v k=$k '$1==k {print $2}' "$WORK/runs" | median)
    m=$(awk -v k=$k '$1==k {print $3}' "$WORK/runs" | median)
    echo "$k: median $s s, median peak RSS $((m / 1024)) MiB"
done
