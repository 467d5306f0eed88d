#!/usr/bin/env bash
# Slurm: the tiles of a small plan as a job array on a one-node cluster started here, the
# merge as a job that depends on it; the result must equal a single-process run byte for
# byte. Run as root (munged and slurmd run as the invoking user); installs slurm-wlm and
# munge with apt-get when they are missing. Usage: .ci/slurm.sh [KARSTIC_BINARY]
set -euo pipefail
cd "$(dirname "$0")/.."
karstic="$(realpath "${1:-target/debug/karstic}")"
[ -x "$karstic" ] || { echo "slurm: $karstic is not a built karstic binary" >&2; exit 1; }

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    export DEBIAN_FRONTEND=noninteractive
    (apt-get update -qq && apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null) \
        || { echo "slurm: could not install slurm-wlm and munge" >&2; exit 1; }
fi

work="$(mktemp -d /tmp/karstic-slurm.XXXXXX)"
pids=()
stop() {
    # The daemons we started, by their PIDs, newest first.
    for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
        kill "${pids[i]}" 2>/dev/null || true
        wait "${pids[i]}" 2>/dev/null || true
    done
    rm -rf "$work"
}
trap stop EXIT
mkdir -p "$work/state" "$work/spool" "$work/logs" "$work/munge"
chmod 700 "$work/munge"

# munge: a fresh key, its own socket, in the foreground so that $! is its PID.
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$work/munge/munge.key"
munged --foreground --force --key-file="$work/munge/munge.key" \
    --socket="$work/munge/munge.socket" --pid-file="$work/munge/munged.pid" \
    --log-file="$work/munge/munged.log" --seed-file="$work/munge/munged.seed" \
    >"$work/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 150); do [ -S "$work/munge/munge.socket" ] && break; sleep 0.1; done

# One node: this machine with its CPUs; processes tracked through /proc, no cgroups.
node="$(hostname -s)"
export SLURM_CONF="$work/slurm.conf"
cat > "$SLURM_CONF" <<CONF
ClusterName=karstic
SlurmctldHost=$node
SlurmUser=$(id -un)
SlurmdUser=$(id -un)
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$work/munge/munge.socket
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
NodeName=$node CPUs=$(nproc) State=UNKNOWN
PartitionName=tiles Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -D -i -f "$SLURM_CONF" >"$work/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" >"$work/slurmd.out" 2>&1 &
pids+=($!)
for _ in $(seq 300); do
    sinfo -h -o %t 2>/dev/null | grep -qE '^(idle|mix|alloc)' && break
    sleep 0.2
done
sinfo -h -o %t | grep -qE '^(idle|mix|alloc)' \
    || { echo "slurm: the node did not come up" >&2; tail -n 20 "$work"/*.out >&2; exit 1; }

# The same plan twice: one folder for Slurm, one for a single process.
plan=(trees/ridge_tunnel.ron --job-region --cell 4 --tile 64 --levels 2)
"$karstic" tile plan "${plan[@]}" -o "$work/slurm" >/dev/null
"$karstic" tile plan "${plan[@]}" -o "$work/local" >/dev/null
n="$(grep -c '"level"' "$work/slurm/plan.json")"

# The tiles as an array job (one CPU, one thread each), then the merge once they all
# succeeded.
array="$(sbatch --parsable --wait --array=0-$((n - 1)) --cpus-per-task=1 \
    --output="$work/logs/tile_%a.out" --export=ALL,RAYON_NUM_THREADS=1 \
    --wrap="'$karstic' tile run '$work/slurm'")" \
    || { echo "slurm: the tile array failed" >&2; tail -n 5 "$work"/logs/* >&2; exit 1; }
sbatch --parsable --wait --dependency="afterok:$array" --kill-on-invalid-dep=yes \
    --output="$work/logs/merge.out" --wrap="'$karstic' tile merge '$work/slurm'" >/dev/null \
    || { echo "slurm: the merge failed" >&2; cat "$work/logs/merge.out" >&2; exit 1; }

"$karstic" tile run "$work/local" --all >/dev/null
"$karstic" tile merge "$work/local" >/dev/null
diff -r "$work/local" "$work/slurm" \
    || { echo "slurm: the Slurm run and the single-process run differ" >&2; exit 1; }
echo "slurm: $n tiles as array job $array, then the merge: identical to a single-process run ($(find "$work/slurm" -type f | wc -l) files)"
