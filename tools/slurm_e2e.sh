#!/usr/bin/env bash
# End-to-end test of `luster slurm` on a real, private, single-node Slurm.
#
# Installs Debian's slurm-wlm and munge when absent, writes its own
# slurm.conf (localhost, all CPUs, select/cons_tres, proctrack/linuxproc,
# task/none) and munge key in a temporary folder, starts its own munged,
# slurmctld and slurmd, then:
#   (a) renders 8 frames of the statue orbit as 4 array tasks, merged by a
#       dependent job;
#   (b) renders one multi-sample hw3 scene in 4 parts, requeueing one task
#       while it runs (as a preemption does), which must resume from its
#       checkpoint;
# checks every merged image byte for byte against a local `luster render`,
# and stops only the daemons it started (by process id). It refuses to run
# beside a Slurm that is already configured or running on the machine.
#
# Needs root. Exit code 0 only when everything matched. Environment:
#   LUSTER  the binary (default target/release/luster, built if missing)
#   SCENES  the shared scenes folder (default ../shared/scenes)
#   KEEP=1  keep the temporary folder (logs, images)
set -euo pipefail
start=$(date +%s)
cd "$(dirname "$0")/.."
repo=$PWD
say() { echo "slurm_e2e: $*"; }
fail() {
    echo "slurm_e2e: FAIL: $*" >&2
    exit 1
}

[ "$(id -u)" = 0 ] || fail "needs root (it installs packages and starts daemons)"
if [ -n "${SLURM_CONF:-}" ] || [ -e /etc/slurm/slurm.conf ] || [ -e /etc/slurm-llnl/slurm.conf ]; then
    fail "a Slurm is configured on this machine (slurm.conf or SLURM_CONF); refusing to run beside it"
fi
running() { # name: whether a process of that name runs (procps may be absent)
    grep -qx "$1" /proc/[0-9]*/comm 2>/dev/null
}
if running slurmctld || running slurmd; then
    fail "slurmctld or slurmd is already running here; refusing to run beside it"
fi

if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v sbatch >/dev/null \
    || ! command -v munged >/dev/null; then
    say "installing slurm-wlm and munge"
    export DEBIAN_FRONTEND=noninteractive
    # A registry hiccup on a fresh CI machine should not fail the run: retry.
    for attempt in 1 2 3; do
        if apt-get update -qq >/dev/null \
            && apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null; then
            break
        fi
        [ "$attempt" = 3 ] && { echo "slurm_e2e: could not install slurm-wlm and munge" >&2; exit 1; }
        sleep 10
    done
fi

scenes=${SCENES:-$repo/../shared/scenes}
anim=$scenes/animations/camera_around_david
hw3=$scenes/ceng795/hw3/xml/cornellbox_brushed_metal.xml
[ -d "$anim" ] && [ -f "$hw3" ] || fail "the shared scenes are missing under $scenes"
luster=${LUSTER:-$repo/target/release/luster}
if [ ! -x "$luster" ]; then
    say "building luster"
    cargo build --release --quiet
fi

tmp=$(mktemp -d /tmp/luster-slurm-e2e.XXXXXX)
chmod 755 "$tmp"
pids=()
jobs_submitted=()
cleanup() {
    local code=$?
    if [ ${#jobs_submitted[@]} -gt 0 ]; then
        scancel "${jobs_submitted[@]}" 2>/dev/null || true
        sleep 1
    fi
    for pid in "${pids[@]}"; do
        kill "$pid" 2>/dev/null || true
    done
    for pid in "${pids[@]}"; do
        wait "$pid" 2>/dev/null || true
    done
    if [ "$code" != 0 ]; then
        for log in "$tmp"/slurmctld.log "$tmp"/slurmd.log "$tmp"/*/logs/*.log; do
            [ -f "$log" ] && { echo "--- $log (last lines)"; tail -n 15 "$log"; }
        done
    fi
    if [ "${KEEP:-0}" = 1 ]; then say "kept $tmp"; else rm -rf "$tmp"; fi
    say "$( [ "$code" = 0 ] && echo PASS || echo FAIL ) in $(($(date +%s) - start)) s"
}
trap cleanup EXIT

# munge, on its own key and socket.
mkdir -p "$tmp/munge" "$tmp/state" "$tmp/spool"
chmod 700 "$tmp/munge"
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge/munge.key"
socket=$tmp/munge/munge.socket
munged --foreground --force --socket="$socket" --key-file="$tmp/munge/munge.key" \
    --log-file="$tmp/munge/munged.log" --pid-file="$tmp/munge/munged.pid" \
    --seed-file="$tmp/munge/munged.seed" 2>"$tmp/munge/stderr" &
pids+=($!)

host=$(hostname -s)
cpus=$(nproc)
port=$((20000 + RANDOM % 20000))
export SLURM_CONF=$tmp/slurm.conf
cat >"$SLURM_CONF" <<EOF
ClusterName=lustere2e
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
JobRequeue=1
MinJobAge=600
MailProg=/bin/true
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=e2e Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
sleep 0.5
slurmctld -D -i -f "$SLURM_CONF" 2>>"$tmp/slurmctld.stderr" &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$host" 2>>"$tmp/slurmd.stderr" &
pids+=($!)
for _ in $(seq 60); do
    state=$(sinfo -h -o %t 2>/dev/null || true)
    [ "$state" = idle ] && break
    sleep 0.5
done
[ "$state" = idle ] || fail "the node did not come up (sinfo: '$state')"
say "Slurm up: node $host, $cpus CPUs, port $port"

frames=()
for f in 000 045 090 135 180 225 270 315; do frames+=("$anim/davids_camera_$f.json"); done
submit() { # outdir, args...: submits, prints "array merge" ids
    local out=$1
    shift
    "$luster" slurm "$@" -o "$out" --submit >"$out.submit"
    sed -n 's/^submitted array job \([0-9]*\) .* merge job \([0-9]*\)$/\1 \2/p' "$out.submit"
}
# 64 samples a pixel (the file asks for 16): each part must run for several
# checkpoint intervals, or it can finish, and remove its checkpoint, between
# two looks for one (at 16 a part took 1.1-1.3 s against a 1 s interval).
hw3_spp=64
read -r hw3_array hw3_merge < <(submit "$tmp/hw3" "$hw3" --tasks 4 --cpus-per-task 1 --checkpoint 1 --spp "$hw3_spp")
jobs_submitted+=("$hw3_array" "$hw3_merge")
read -r anim_array anim_merge < <(submit "$tmp/anim" "${frames[@]}" --tasks 4 --cpus-per-task 1)
jobs_submitted+=("$anim_array" "$anim_merge")
[ -n "$hw3_merge" ] && [ -n "$anim_merge" ] || fail "luster slurm --submit printed no job ids"
grep -q -- '--array=1-4' "$tmp/hw3/luster.sbatch" || fail "the array script has no --array=1-4"
say "submitted hw3 $hw3_array (+merge $hw3_merge), orbit $anim_array (+merge $anim_merge)"

# Preempt one hw3 task once it has checkpointed: Slurm requeues it, and the
# rerun must resume rather than start over.
requeued=
for _ in $(seq 600); do
    ckpt=$(find "$tmp/hw3" -name '*.checkpoint' 2>/dev/null | head -n 1)
    if [ -n "$ckpt" ]; then
        requeued=${ckpt##*.part-}
        requeued=${requeued%%-of-*}
        scontrol requeue "${hw3_array}_$requeued"
        say "requeued task $requeued of $hw3_array while it ran (checkpoint $(basename "$ckpt"))"
        # Slurm holds a requeued job back for a couple of minutes (its
        # BeginTime, set once the killed task has finished completing); a
        # test need not wait for that, but not none either: slurmd refuses a
        # launch whose credential is from the second it revoked the old one
        # ("Job credential revoked", the task then fails and its merge never
        # runs), so the rerun starts a few seconds on.
        for _ in $(seq 150); do
            if [ "$(squeue -h -j "${hw3_array}_$requeued" -o %T 2>/dev/null)" = PENDING ]; then
                scontrol update JobId="${hw3_array}_$requeued" StartTime=now+3
                break
            fi
            sleep 0.2
        done
        break
    fi
    sleep 0.2
done
[ -n "$requeued" ] || fail "no hw3 task wrote a checkpoint within 120 s"

# Local references while Slurm works.
"$luster" render -q "$hw3" --spp "$hw3_spp" -o "$tmp/local-hw3"
"$luster" render -q "${frames[@]}" -o "$tmp/local-anim"

for _ in $(seq 900); do
    left=$(squeue -h -j "$hw3_array,$hw3_merge,$anim_array,$anim_merge" 2>/dev/null | wc -l)
    [ "$left" = 0 ] && break
    sleep 1
done
[ "$left" = 0 ] || fail "jobs still queued after 15 minutes"
"$luster" slurm status "$tmp/hw3"
for j in "$hw3_merge" "$anim_merge"; do
    state=$(scontrol show job "$j" -o | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
    [ "$state" = COMPLETED ] || fail "merge job $j ended $state"
done
grep -q "resumed from a checkpoint" "$tmp/hw3/logs/part-$requeued.log" \
    || fail "the requeued task $requeued did not resume from its checkpoint"

compared=0
for pair in "local-hw3 hw3" "local-anim anim"; do
    read -r ref got <<<"$pair"
    for f in "$tmp/$ref"/*; do
        cmp -s "$f" "$tmp/$got/$(basename "$f")" || fail "$got/$(basename "$f") differs from a local render"
        compared=$((compared + 1))
    done
done
[ "$compared" = 9 ] || fail "compared $compared images, expected 9"
say "all $compared merged images are byte-identical to local renders; requeued task $requeued resumed"
