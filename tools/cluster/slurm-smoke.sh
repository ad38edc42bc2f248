#!/usr/bin/env bash
# The Slurm recipe of docs/studies.md ("Shards"), run for real on this machine, so that it keeps
# working:
#
#   bash tools/cluster/slurm-smoke.sh build/tools/cullide
#
# Starts a private single-node Slurm (Debian's slurm-wlm, 22.05 on Debian 12) with a generated
# configuration and its own munged (own key and socket), all in a scratch folder; submits
# tools/cluster/study-array.sbatch (the job script docs/studies.md shows, checked here to be the
# same text) as a 4-task array on a small sweep of the bundled scenes; waits; merges the shards
# with the recipe's `cullide study merge`; and checks that the merge equals the unsharded run but for the
# timing columns (`*_ms`; in the JSON lines also the per-call seconds, the provenance and the
# command line that ran the shard).
# It stops only the daemons it started (by their pid files) and removes the scratch folder, on
# every exit path; on failure it prints the daemons' logs and the jobs' output, and exits 1.
# Needs root (munged runs as the munge user, slurmd as root) and `bash tools/setup.sh` (slurm-wlm,
# munge, python3). CULLIDE_SLURM_KEEP=1 keeps the scratch folder.
set -euo pipefail

say() { echo "slurm-smoke: $*"; }
fail() {
  echo "slurm-smoke: FAILED: $*" >&2
  exit 1
}

[ $# -eq 1 ] || {
  echo "usage: bash tools/cluster/slurm-smoke.sh PATH/TO/cullide" >&2
  exit 2
}
[ -x "$1" ] || fail "$1: not an executable (build the cullide target first)"
cullide=$(realpath "$1")
repo=$(cd "$(dirname "$0")/../.." && pwd)
job_script=$repo/tools/cluster/study-array.sbatch
[ "$(id -u)" -eq 0 ] || fail "must run as root: the munge key must belong to the munge user and slurmd runs jobs as their submitter"
for c in slurmctld slurmd sbatch squeue sinfo scontrol scancel munged munge unmunge runuser python3; do
  command -v "$c" >/dev/null || fail "'$c' not found (bash tools/setup.sh installs slurm-wlm, munge and python3)"
done
id munge >/dev/null 2>&1 || fail "no 'munge' user (Debian's munge package creates it)"

# docs/studies.md shows the job script that is submitted below, verbatim: the recipe a reader
# copies is the one tested here.
python3 - "$repo/docs/studies.md" "$job_script" <<'EOF' || fail "docs/studies.md does not show tools/cluster/study-array.sbatch verbatim (a \`\`\`bash block holding the file); update docs/studies.md"
import sys
readme, script = open(sys.argv[1]).read(), open(sys.argv[2]).read()
blocks = [b.split("```", 1)[0] for b in readme.split("```bash\n")[1:]]
sys.exit(0 if script in blocks else 1)
EOF

scratch=$(mktemp -d /tmp/cullide-slurm.XXXXXX) # short: slurmd makes Unix sockets (108 bytes) in it
chmod 755 "$scratch" # munged (the munge user) must reach its folder inside
conf=$scratch/slurm.conf
mdir=$scratch/munge
work=$scratch/work
jobid=""
started=() # "name pid" of every daemon this script started, in start order

alive() { # pid name: is that pid still that daemon (not a reused pid)?
  [ -r "/proc/$1/comm" ] && [ "$(cat "/proc/$1/comm" 2>/dev/null)" = "$2" ]
}

stop_daemon() { # name pid: TERM, up to 20 s, then KILL
  local name=$1 pid=$2 i
  alive "$pid" "$name" || return 0
  kill -TERM "$pid" 2>/dev/null || true
  for i in $(seq 100); do
    alive "$pid" "$name" || return 0
    sleep 0.2
  done
  say "$name (pid $pid) did not stop on TERM within 20 s; KILL"
  kill -KILL "$pid" 2>/dev/null || true
}

show_logs() {
  local f
  for f in "$scratch"/log/*.log "$work"/slurm-*.out; do
    [ -f "$f" ] || continue
    echo "---- ${f#"$scratch"/} (last 60 lines)" >&2
    tail -n 60 "$f" >&2
  done
}

cleanup() {
  local rc=$? i entry
  trap - EXIT INT TERM
  set +e
  if [ -n "$jobid" ] && [ -n "$(squeue -h -j "$jobid" -o %i 2>/dev/null)" ]; then
    say "cancelling job $jobid"
    scancel "$jobid" 2>/dev/null
    for i in $(seq 30); do
      [ -z "$(squeue -h -j "$jobid" -o %i 2>/dev/null)" ] && break
      sleep 1
    done
  fi
  [ "$rc" -eq 0 ] || show_logs
  for ((i = ${#started[@]} - 1; i >= 0; i--)); do # the reverse of the start order
    entry=${started[i]}
    stop_daemon "${entry% *}" "${entry#* }"
  done
  if [ "${CULLIDE_SLURM_KEEP:-0}" = "1" ]; then say "kept $scratch"; else rm -rf "$scratch"; fi
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

wait_for() { # seconds description command...: poll the command every second until it succeeds
  local secs=$1 what=$2 i
  shift 2
  for i in $(seq "$secs"); do
    "$@" && return 0
    sleep 1
  done
  fail "timed out after $secs s waiting for $what"
}

start_daemon() { # name pidfile command...: start a forking daemon, record its pid from its pid file
  local name=$1 pidfile=$2 pid
  shift 2
  "$@" || fail "$name did not start: $* exited with status $?"
  wait_for 30 "$name's pid file $pidfile" test -s "$pidfile"
  pid=$(cat "$pidfile")
  alive "$pid" "$name" || fail "$name exited right after starting (pid $pid)"
  started+=("$name $pid")
  say "started $name (pid $pid)"
}

# munge: a private munged (own key, socket, pid file) so that a system munged, if any, is neither
# used nor disturbed. munged checks that its key and folders belong to the user it runs as.
mkdir -p "$mdir" "$scratch/log" "$scratch/state" "$scratch/spool" "$work"
dd if=/dev/urandom of="$mdir/munge.key" bs=1024 count=1 status=none
chown -R munge:munge "$mdir"
chmod 755 "$mdir" # clients reach the socket in it; the key itself is 0400
chmod 400 "$mdir/munge.key"
start_daemon munged "$mdir/munged.pid" runuser -u munge -- munged --socket="$mdir/munge.socket" \
  --key-file="$mdir/munge.key" --pid-file="$mdir/munged.pid" --seed-file="$mdir/munged.seed" \
  --log-file="$mdir/munged.log" --origin=127.0.0.1
ln -s "$mdir/munged.log" "$scratch/log/munged.log"
munge -n -S "$mdir/munge.socket" | unmunge -S "$mdir/munge.socket" >/dev/null ||
  fail "munge -n | unmunge on the private socket did not succeed"

# Slurm: one node (this machine, reached at 127.0.0.1 so that its name need not resolve; named
# node0, not after the host, because slurmd names its Unix sockets after the node and a long host
# name overflows their 108 bytes), one partition, ports the kernel found free, every path in the
# scratch folder. linuxproc process tracking and no task plugin: no cgroups needed (containers
# often have none writable).
host=$(hostname -s)
cpus=$(nproc)
read -r ctld_port slurmd_port < <(python3 -c '
import socket
a, b = socket.socket(), socket.socket()
a.bind(("127.0.0.1", 0)); b.bind(("127.0.0.1", 0))
print(a.getsockname()[1], b.getsockname()[1])')
cat >"$conf" <<EOF
# Generated by tools/cluster/slurm-smoke.sh: a private single-node cluster, removed afterwards.
ClusterName=cullide-smoke
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$mdir/munge.socket
StateSaveLocation=$scratch/state
SlurmdSpoolDir=$scratch/spool
SlurmctldPidFile=$scratch/slurmctld.pid
SlurmdPidFile=$scratch/slurmd.pid
SlurmctldLogFile=$scratch/log/slurmctld.log
SlurmdLogFile=$scratch/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MailProg=/bin/true
# finished jobs stay visible to squeue (there is no accounting database to ask)
MinJobAge=3600
NodeName=node0 NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=smoke Nodes=node0 Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$conf
say "Slurm $(sinfo --version | awk '{print $2}') on $host ($cpus CPUs), ports $ctld_port and $slurmd_port, in $scratch"

start_daemon slurmctld "$scratch/slurmctld.pid" slurmctld -f "$conf"
wait_for 30 "slurmctld to answer (scontrol ping)" bash -c 'scontrol ping 2>/dev/null | grep -q UP'
start_daemon slurmd "$scratch/slurmd.pid" slurmd -f "$conf" -N node0
node_idle() { [ "$(sinfo -h -n node0 -o %T 2>/dev/null)" = idle ]; }
wait_for 60 "node0 to be idle (sinfo)" node_idle
say "sinfo: $(sinfo -h -o '%P %a %D %T %N')"

# The sweep: the two bundled scenes (frame 0), both methods, two resolutions: 8 runs, 2 per shard.
cat >"$scratch/sweep.json" <<EOF
{"scenes": ["$repo/data/scenes/bunny_through_cow.json@0", "$repo/data/scenes/two_cows_and_bunny.json@0"],
 "methods": ["original", "modified"], "resolutions": [64, 128], "repeats": 1}
EOF
cd "$work"
t0=$(date +%s)
# The job script as docs/studies.md shows it; the command line overrides its #SBATCH sizes for this node.
jobid=$(CULLIDE=$cullide sbatch --parsable --array=0-3 --cpus-per-task=1 --time=00:10:00 \
  "$job_script" "$scratch/sweep.json" results) || fail "sbatch refused the job"
jobid=${jobid%%;*}
say "submitted job array $jobid (4 tasks)"

# The unsharded run, meanwhile, outside Slurm.
"$cullide" study "$scratch/sweep.json" -o "$work/unsharded.csv" -q >/dev/null ||
  fail "the unsharded study failed"

tasks_done() { # every task of the array in a final state; a task Slurm could not launch fails now
  local states held
  held=$(squeue -h -r -j "$jobid" -t PENDING -o '%i %r' 2>/dev/null | grep -iE 'held|launch failed') || true
  [ -z "$held" ] || fail "Slurm could not launch: $held"
  states=$(squeue -h -r -j "$jobid" --states=all -o %T 2>/dev/null) || return 1
  [ "$(wc -l <<<"$states")" -eq 4 ] || return 1
  ! grep -qvE '^(COMPLETED|FAILED|CANCELLED|TIMEOUT|NODE_FAIL|OUT_OF_MEMORY|BOOT_FAIL|DEADLINE|PREEMPTED)$' <<<"$states"
}
wait_for 600 "the job array $jobid to finish (squeue)" tasks_done
say "array finished in $(($(date +%s) - t0)) s: $(squeue -h -r -j "$jobid" --states=all -o '%i=%T' | tr '\n' ' ')"
if squeue -h -r -j "$jobid" --states=all -o %T | grep -qv '^COMPLETED$'; then
  fail "not every task of job $jobid COMPLETED"
fi

# The recipe's merge, then: the merge equals the unsharded run but for the timings.
for i in 0 1 2 3; do
  [ "$(wc -l <"results/shard$i.csv")" -ge 2 ] || fail "results/shard$i.csv holds no run"
done
"$cullide" study merge results/shard*.csv -o results/all.csv || fail "cullide study merge failed"
python3 - "$work/unsharded" "$work/results/all" <<'EOF' || fail "the merge differs from the unsharded run"
import csv, json, sys

def rows(stem):  # CSV rows as dicts, without the timing columns
    with open(stem + ".csv", newline="") as f:
        return [{k: v for k, v in r.items() if not k.endswith("_ms")} for r in csv.DictReader(f)]

def records(stem):  # JSON lines without timings (and per-call seconds), provenance and command
    out = []
    for line in open(stem + ".jsonl"):
        # "command" is the study's own command line: each shard's names its --shard and output.
        r = {k: v for k, v in json.loads(line).items()
             if not k.endswith("_ms") and k not in ("provenance", "command")}
        for p in r.get("passes", []):
            p.pop("seconds", None)
        out.append(r)
    return out

a, b = sys.argv[1], sys.argv[2]
ok = open(a + ".csv").readline() == open(b + ".csv").readline()
if not ok:
    print("the CSV headers differ", file=sys.stderr)
for what, x, y in (("CSV", rows(a), rows(b)), ("JSON lines", records(a), records(b))):
    if len(x) != len(y):
        ok = False
        print(f"{what}: the unsharded run has {len(x)} runs, the merge {len(y)}", file=sys.stderr)
    for i, (p, q) in enumerate(zip(x, y)):
        diff = {k: (p.get(k), q.get(k)) for k in p.keys() | q.keys() if p.get(k) != q.get(k)}
        if diff:
            ok = False
            print(f"{what}, run {i}: unsharded vs merged {diff}"[:2000], file=sys.stderr)
n = len(rows(a))
if n != 8:
    ok = False
    print(f"the unsharded run has {n} runs, not 8", file=sys.stderr)
if ok:
    print(f"slurm-smoke: the merge of 4 shards equals the unsharded run ({n} runs; CSV and JSON lines, timings aside)")
sys.exit(0 if ok else 1)
EOF
say "passed in $(($(date +%s) - t0)) s after the daemons were up"
