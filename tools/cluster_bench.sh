#!/usr/bin/env bash
# What splitting a render costs, measured in one run on this machine:
#  1. CPU time (user + system) of 4 parts rendered one after another, with
#     --resume and checkpoints as Slurm tasks run them, over the CPU time of
#     one render of the same image (target: at most 1.1);
#  2. wall time of `luster merge` of an 8-megapixel image from 4 parts,
#     writing its PNG (target: under 1 s).
# Prints both figures; exits 1 when a target is missed.
#   LUSTER  the binary (default target/release/luster)
#   SCENE   the scene of (1) (default hw3 cornellbox_brushed_metal, 16 spp)
set -euo pipefail
cd "$(dirname "$0")/.."
luster=${LUSTER:-target/release/luster}
scene=${SCENE:-../shared/scenes/ceng795/hw3/xml/cornellbox_brushed_metal.xml}
[ -x "$luster" ] || { echo "no $luster: cargo build --release first" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
TIMEFORMAT='%U %S'

cpu() { # command...: prints user+system seconds of it and its children
    local t
    t=$({ time "$@" >/dev/null; } 2>&1 | tail -n 1)
    awk -v t="$t" 'BEGIN { split(t, a, " "); printf "%.3f", a[1] + a[2] }'
}

one=$(cpu "$luster" render -q "$scene" -o "$tmp/one")
parts=0
for k in 1 2 3 4; do
    c=$(cpu "$luster" render -q "$scene" -o "$tmp/parts" --part "$k/4" --resume --checkpoint 5)
    parts=$(awk -v a="$parts" -v b="$c" 'BEGIN { printf "%.3f", a + b }')
done
"$luster" merge "$tmp/parts" >/dev/null
cmp -s "$tmp/one/$(ls "$tmp/one")" "$tmp/parts/$(ls "$tmp/one")" || { echo "merged image differs" >&2; exit 1; }
ratio=$(awk -v a="$parts" -v b="$one" 'BEGIN { printf "%.3f", a / b }')
echo "cpu: one render $one s, 4 parts $parts s, ratio $ratio (target <= 1.1)  [$(basename "$scene")]"

cat >"$tmp/big.xml" <<'EOF'
<Scene>
  <BackgroundColor>10 20 30</BackgroundColor>
  <Cameras><Camera id="1"><Position>0 0 5</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-2 2 -1 1</NearPlane><NearDistance>2</NearDistance>
    <ImageResolution>4096 2048</ImageResolution><ImageName>big.png</ImageName></Camera></Cameras>
  <Lights><AmbientLight>20 20 20</AmbientLight>
    <PointLight id="1"><Position>3 3 5</Position><Intensity>400000 400000 400000</Intensity></PointLight></Lights>
  <Materials><Material id="1"><AmbientReflectance>1 1 1</AmbientReflectance>
    <DiffuseReflectance>0.8 0.5 0.3</DiffuseReflectance></Material></Materials>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Center>1</Center><Radius>1.5</Radius></Sphere></Objects>
</Scene>
EOF
for k in 1 2 3 4; do "$luster" render -q "$tmp/big.xml" -o "$tmp/big" --part "$k/4"; done
t0=$(date +%s.%N)
"$luster" merge "$tmp/big" >/dev/null
t1=$(date +%s.%N)
merge=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", b - a }')
echo "merge: 4096x2048 (8.4 Mpixel) from 4 parts in $merge s wall, PNG included (target < 1 s)"
awk -v r="$ratio" -v m="$merge" 'BEGIN { exit !(r <= 1.1 && m < 1.0) }'
