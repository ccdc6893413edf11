#!/usr/bin/env bash
# The figures of docs/denoising.md: what `--denoise` costs at 800x800, and
# the time to a clean image of the path-traced Cornell box
# (examples/scenes/cornell_path.xml at half size, 200x200) with and without it.
#
# Renders a 4096-spp reference (seed 1), then 16, 64, 256 and 1024 spp and
# 4 and 16 spp denoised (seed 0), and prints each render's time and
# `luster compare`'s relative MSE and HDR-FLIP against the reference; then
# 800x800 at 16 spp with and without --denoise under /usr/bin/time (wall
# time, peak resident memory). Takes 10 to 20 minutes on two cores.
#
# Needs a luster built with the feature (docs/denoising.md). Environment:
#   LUSTER   the binary (default target/release/luster)
#   OUT      the work folder (default target/denoise-bench)
#   THREADS  worker threads (default: all cores)
set -euo pipefail
cd "$(dirname "$0")/.."
L=${LUSTER:-target/release/luster}
out=${OUT:-target/denoise-bench}
threads=(${THREADS:+--threads "$THREADS"})
scene=examples/scenes/cornell_path.xml
mkdir -p "$out"

render() { # name, options...: renders into $out/name, prints its summary line
    local name=$1
    shift
    "$L" render "$scene" -o "$out/$name" "${threads[@]}" "$@" | sed "s|^|$name: |"
}
compare() { # name: relative MSE and HDR-FLIP of $out/name against the reference
    "$L" compare "$out/ref/cornell_path.exr" "$out/$1/cornell_path.exr" |
        awk -v n="$1" '/^rel\. MSE/ {m = $3} /^FLIP/ {f = $2} END {print n ": rel. MSE " m ", HDR-FLIP " f}'
}

[ -f "$out/ref/cornell_path.exr" ] || render ref --scale 0.5 --spp 4096 --seed 1
for spp in 16 64 256 1024; do
    render "s$spp" --scale 0.5 --spp "$spp"
done
for spp in 4 16; do
    render "d$spp" --scale 0.5 --spp "$spp" --denoise
done
for name in s16 s64 s256 s1024 d4 d16; do
    compare "$name"
done

for denoise in "" --denoise; do
    /usr/bin/time -f "800x800 16 spp ${denoise:-(no denoise)}: %e s wall, %M KiB peak resident" \
        "$L" render "$scene" -o "$out/big" "${threads[@]}" --size 800x800 --spp 16 $denoise
done
