#!/bin/sh
# Builds the fuzz targets (libFuzzer, stable Rust) and runs each for RUNS
# executions (default 1000000) or SECONDS of time, whichever ends first, on
# the seeded corpus, logging to logs/. Scene builds run on one thread
# (RAYON_NUM_THREADS=1): parallel BVH builds of tiny scenes only add overhead.
# usage: fuzz/run.sh [TARGET...]     (all of them when none is given)
# Crashing inputs land in artifacts/<target>/; replay one with
#   fuzz/target/<host triple>/release/<target> artifacts/<target>/crash-...
set -eu
cd "$(dirname "$0")"
. ./env.sh
# With an explicit --target, RUSTFLAGS reach only the target code, not build
# scripts and proc macros (which would miss libFuzzer's symbols).
host=$(rustc -vV | sed -n 's/^host: //p')
cargo build --release --bins --target "$host"
bin=${CARGO_TARGET_DIR:-target}/$host/release
[ -d corpus ] || ./seed.sh
runs=${RUNS:-1000000}
seconds=${SECONDS_PER_TARGET:-0}
export RAYON_NUM_THREADS=${RAYON_NUM_THREADS:-1}
targets=${*:-scene_xml scene_json ply obj image shader partfile watch_request}
mkdir -p logs
for t in $targets; do
    mkdir -p "artifacts/$t"
    "$bin/$t" -runs="$runs" -max_total_time="$seconds" -max_len=65536 -rss_limit_mb=2048 -timeout=10 \
        -artifact_prefix="artifacts/$t/" -print_final_stats=1 "corpus/$t" >"logs/$t.log" 2>&1 || true
    echo "$t: $(grep -E 'stat::number_of_executed_units' "logs/$t.log" | tail -1) \
crashes: $(ls "artifacts/$t" | wc -l)"
done
