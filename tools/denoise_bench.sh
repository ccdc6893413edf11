#!/usr/bin/env bash
# The figures of docs/denoising.md: what `--denoise` costs at 800x800, and
# the time to a clean image of the path-traced Cornell box
# (examples/scenes/cornell_path.xml at 128x128) with and without it.
#
# Renders a 4096-spp reference (seed 1), then 16, 64 and 256 spp and 16 spp
# denoised (seed 0), and prints each render's time and `luster compare`'s
# relative MSE and HDR-FLIP against the reference; then 800x800 at 1 spp
# with and without --denoise under /usr/bin/time (wall and CPU time, peak
# resident memory). The reference takes minutes on two cores.
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

[ -f "$out/ref/cornell_path.exr" ] || render ref --size 128x128 --spp 4096 --seed 1
for spp in 16 64 256; do
    render "s$spp" --size 128x128 --spp "$spp"
done
render d16 --size 128x128 --spp 16 --denoise
for name in s16 s64 s256 d16; do
    compare "$name"
done

for denoise in "" --denoise; do
    /usr/bin/time -f "800x800 1 spp ${denoise:-(no denoise)}: %e s wall, %U s user, %M KiB peak resident" \
        "$L" render "$scene" -o "$out/big" "${threads[@]}" --size 800x800 --spp 1 $denoise
done
