#!/usr/bin/env bash
# studyrun on a real Slurm: a one-node cluster in a temporary directory runs the job
# array of tests/slurm/array.sbatch (the job script the README shows) and the merge,
# with the accidents of a real cluster on the way:
#
#   1. installs slurmctld, slurmd, slurm-client and munge (Debian, --no-install-recommends;
#      a temporary policy-rc.d keeps the packages from starting their own daemons);
#   2. starts munged, slurmctld and slurmd from the temporary directory on private ports;
#   3. submits a 2-task array over an 8-case study (-j ${SLURM_CPUS_PER_TASK:-1} with
#      --cpus-per-task=1), requeues task 1 (`scontrol requeue`, as preemption does) and
#      cancels task 2 (`scancel`, as a time limit does) each after its first case; the
#      requeued task reruns the script and resumes from its journal; task 2 is resubmitted
#      (`sbatch --array=2`) and resumes too; the merge is a job with
#      --dependency=afterok on the requeued task and on the resubmitted job;
#   4. resubmits a finished task: it must leave its file as it is;
#   5. a 3-task array over a 2-case study whose case 0 fails (the tasks exit 0 by
#      --allow-failed) and whose task 3 has no case (an empty shard), --cpus-per-task=2
#      (-j 2), merged by a job with --dependency=afterok on the whole array;
#   6. checks each merged file equals a single run of its study value for value (every
#      variable but wall_time, the attributes but created/history/git_commit);
#   7. stops its daemons (and any job still running) by pid, also when it fails.
#
# Exit status: 0 passed; 77 skipped (not root, no apt/dpkg, the packages cannot be
# installed), with "slurm test: skipped: <reason>"; anything else failed, after the
# daemons' logs and the jobs' output. Takes 65-90 s on two cores (plus the install).
#
# Environment: STUDYRUN, the binary (default target/release/studyrun, built with
# `cargo build --release --locked` if missing); PYTHON, a Python with h5py (default
# .venv/bin/python; else /usr/bin/python3, with Debian's python3-h5py installed if
# needed); KEEP=1 keeps the temporary directory (it is kept anyway on failure).
# shellcheck disable=SC2015 # A && B || fail: B is a test
set -euo pipefail

say() { echo "slurm test: $*"; }
skip() {
  echo "slurm test: skipped: $*"
  exit 77
}
fail() {
  echo "slurm test: FAILED: $*" >&2
  exit 1
}

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
here=$repo/tests/slurm
started=$SECONDS

# State the cleanup needs; it runs on every exit.
tmp='' made_policy='' munged_pid='' ctld_pid='' slurmd_pid=''

[ "$(id -u)" -eq 0 ] || skip "not root (it installs Debian packages and starts daemons)"
command -v apt-get >/dev/null && command -v dpkg-query >/dev/null ||
  skip "apt-get or dpkg-query not found (not Debian)"

# --- the binary and a Python with h5py ----------------------------------------------
if [ -z "${STUDYRUN:-}" ]; then
  STUDYRUN=$repo/target/release/studyrun
  if [ ! -x "$STUDYRUN" ]; then
    say "building $STUDYRUN"
    (cd "$repo" && cargo build --release --locked)
  fi
fi
[ -x "$STUDYRUN" ] || fail "STUDYRUN=$STUDYRUN is not an executable"
STUDYRUN=$(realpath "$STUDYRUN")

packages=(slurmctld slurmd slurm-client munge)
PYTHON=${PYTHON:-$repo/.venv/bin/python}
if ! "$PYTHON" -c 'import h5py' 2>/dev/null; then
  PYTHON=/usr/bin/python3
  "$PYTHON" -c 'import h5py' 2>/dev/null || packages+=(python3-h5py)
fi

# --- cleanup, on every exit: jobs, daemons (by pid), policy-rc.d, the directory -------
cleanup() {
  local rc=$?
  trap - EXIT INT TERM
  set +e
  if [ -n "$ctld_pid" ] && kill -0 "$ctld_pid" 2>/dev/null; then
    # Jobs first, so that no slurmstepd or studyrun outlives the cluster.
    local ids
    ids=$(squeue -h -o %A 2>/dev/null | sort -u)
    if [ -n "$ids" ]; then
      say "cancelling jobs still queued: ${ids//$'\n'/ }"
      # shellcheck disable=SC2086
      scancel $ids 2>/dev/null
      local end=$((SECONDS + 30))
      while [ -n "$(squeue -h -o %A 2>/dev/null)" ] && [ $SECONDS -lt $end ]; do sleep 1; done
    fi
    if [ -n "$slurmd_pid" ] && kill -0 "$slurmd_pid" 2>/dev/null; then
      for p in $(scontrol listpids 2>/dev/null | awk 'NR > 1 && $1 ~ /^[0-9]+$/ { print $1 }'); do
        kill -KILL "$p" 2>/dev/null
      done
    fi
  fi
  if [ "$rc" -ne 0 ] && [ "$rc" -ne 77 ] && [ -n "$tmp" ]; then
    show_logs
  fi
  local name pid
  for name in slurmd ctld munged; do
    eval "pid=\$${name}_pid"
    [ -n "$pid" ] || continue
    kill -TERM "$pid" 2>/dev/null
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
    kill -KILL "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
  done
  [ -n "$made_policy" ] && rm -f /usr/sbin/policy-rc.d
  if [ -n "$tmp" ]; then
    if [ "$rc" -eq 0 ] && [ -z "${KEEP:-}" ]; then
      rm -rf "$tmp"
    else
      say "kept $tmp"
    fi
  fi
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

show_logs() {
  local f
  echo "---- squeue / jobs ----"
  scontrol show job -o 2>&1 | tr ' ' '\n' |
    awk -F= '/^JobId=/ && NR > 1 { print line; line = "" }
      $1 ~ /^(JobId|ArrayJobId|ArrayTaskId|JobState|Reason|Dependency|Restarts|ExitCode|RunTime)$/ { line = line " " $0 }
      END { print line }'
  for f in "$tmp"/log/*.log "$tmp"/log/*.out; do
    # A daemon's .out repeats its .log (-D also logs to stderr) unless it failed early.
    [ -s "$f" ] && { [ "${f%.out}" = "$f" ] || [ ! -s "${f%.out}.log" ]; } || continue
    echo "---- $f (last 40 lines) ----"
    tail -n 40 "$f"
  done
  for f in "$tmp"/*/slurm-*.out "$tmp"/*/merge-*.out; do
    [ -e "$f" ] || continue
    echo "---- $f ----"
    cat "$f"
  done
}

# --- the packages ---------------------------------------------------------------------
installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q 'ok installed'; }
missing=()
for p in "${packages[@]}"; do installed "$p" || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  say "installing ${missing[*]}"
  if [ ! -e /usr/sbin/policy-rc.d ]; then
    printf '#!/bin/sh\nexit 101\n' >/usr/sbin/policy-rc.d
    chmod 755 /usr/sbin/policy-rc.d
    made_policy=1
  fi
  apt_log=$(mktemp)
  export DEBIAN_FRONTEND=noninteractive
  apt_install() { apt-get install -y -q --no-install-recommends "${missing[@]}" >>"$apt_log" 2>&1; }
  if ! apt_install && ! { apt-get update -q >>"$apt_log" 2>&1 && apt_install; }; then
    tail -n 20 "$apt_log"
    rm -f "$apt_log"
    skip "cannot install ${missing[*]} with apt-get"
  fi
  rm -f "$apt_log"
  if [ -n "$made_policy" ]; then
    rm -f /usr/sbin/policy-rc.d
    made_policy=''
  fi
fi
for c in munged munge unmunge slurmctld slurmd sbatch squeue scontrol scancel; do
  command -v "$c" >/dev/null || fail "$c not found after installing ${packages[*]}"
done

# --- the cluster ----------------------------------------------------------------------
tmp=$(mktemp -d "${TMPDIR:-/tmp}/studyrun-slurm.XXXXXX")
chmod 755 "$tmp"
mkdir -p "$tmp"/{munge,state,spool,log,bin,main,tiny,single}
chmod 711 "$tmp/munge" # munged wants its socket directory searchable by all
ln -s "$STUDYRUN" "$tmp/bin/studyrun"
export PATH=$tmp/bin:$PATH # the jobs inherit it (sbatch exports the environment)
export SLURM_CONF=$tmp/slurm.conf
say "cluster in $tmp, studyrun $STUDYRUN ($("$STUDYRUN" --version))"

wait_until() { # SECONDS DESCRIPTION COMMAND...: polls COMMAND until it succeeds
  local end=$((SECONDS + $1)) what=$2
  shift 2
  until "$@"; do
    [ $SECONDS -lt $end ] || fail "timed out waiting for $what"
    sleep 0.3
  done
}

sock=$tmp/munge/munged.sock
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge/munge.key"
munged --foreground --force --socket="$sock" --key-file="$tmp/munge/munge.key" \
  --pid-file="$tmp/munge/munged.pid" --log-file="$tmp/log/munged.log" \
  --seed-file="$tmp/munge/munged.seed" >"$tmp/log/munged.out" 2>&1 &
munged_pid=$!
munge_works() { munge -n -S "$sock" 2>/dev/null | unmunge -S "$sock" >/dev/null 2>&1; }
wait_until 20 "munged" munge_works

port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
for _ in $(seq 50); do
  port=$((20000 + RANDOM % 30000))
  port_free "$port" && port_free $((port + 1)) && break
done
host=$(hostname -s)
# The node as slurmd sees it (CPUs, sockets, cores, threads, RealMemory).
node=$(slurmd -C 2>/dev/null | head -n 1)
case $node in
  "NodeName=$host "*) ;;
  *) node="NodeName=$host CPUs=$(nproc) RealMemory=$(free -m | awk '/^Mem:/ { print $2 }')" ;;
esac
cpus=$(sed -n 's/.* CPUs=\([0-9]*\).*/\1/p' <<<"$node")
[ "${cpus:-0}" -ge 2 ] || fail "the node has ${cpus:-?} CPUs; the test needs 2"
cat >"$SLURM_CONF" <<EOF
ClusterName=studyrun-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$sock,cred_expire=10
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=2,bf_interval=2
MpiDefault=none
SwitchType=switch/none
MailProg=/bin/true
PropagateResourceLimits=NONE
ReturnToService=2
JobRequeue=1
KillWait=5
MinJobAge=3600
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF

slurmctld -D -f "$SLURM_CONF" >"$tmp/log/slurmctld.out" 2>&1 &
ctld_pid=$!
ctld_up() { kill -0 "$ctld_pid" 2>/dev/null && scontrol ping 2>/dev/null | grep -q 'is UP'; }
wait_until 30 "slurmctld (port $port)" ctld_up
slurmd -D -f "$SLURM_CONF" >"$tmp/log/slurmd.out" 2>&1 &
slurmd_pid=$!
node_idle() {
  kill -0 "$slurmd_pid" 2>/dev/null || fail "slurmd exited"
  [ "$(sinfo -h -n "$host" -o %T 2>/dev/null)" = idle ]
}
wait_until 60 "node $host to be idle" node_idle
say "slurmctld (pid $ctld_pid, port $port), slurmd (pid $slurmd_pid), munged (pid $munged_pid) up in $((SECONDS - started)) s"

# --- helpers for jobs -----------------------------------------------------------------
# Field NAME of job ID (an array task as JOB_TASK), e.g. JobState.
field() { scontrol show job -o "$1" 2>/dev/null | head -n 1 | tr ' ' '\n' | sed -n "s/^$2=//p"; }
state_is() { # ID STATE...
  local s
  s=$(field "$1" JobState)
  for want in "${@:2}"; do [ "$s" = "$want" ] && return 0; done
  return 1
}
ended() { state_is "$1" COMPLETED FAILED CANCELLED TIMEOUT NODE_FAIL OUT_OF_MEMORY BOOT_FAIL DEADLINE PREEMPTED; }
merge_ended() { # ID: a merge job ended; it fails at once if its dependency cannot be met
  [ "$(field "$1" Reason)" != DependencyNeverSatisfied ] ||
    fail "the merge job $1 will never run: a job it depends on (afterok) did not exit 0"
  ended "$1"
}
expect_ok() { # ID DESCRIPTION: waited for, must have completed with exit 0
  local s e
  s=$(field "$1" JobState) e=$(field "$1" ExitCode)
  [ "$s" = COMPLETED ] && [ "$e" = 0:0 ] || fail "$2 (job $1): state $s, exit code $e"
}
# The journal beside OUT is created (header only) before the first case ends and grows
# by a record per case: grown past its size when first seen = a case is journaled.
declare -A journal_start
journaled() { # OUT
  local j=$1.journal size
  [ -e "$j" ] || return 1
  size=$(stat -c %s "$j")
  [ -n "${journal_start[$j]:-}" ] || journal_start[$j]=$size
  [ "$size" -gt "${journal_start[$j]}" ]
}
alive() { # JOB_TASK: fails the test if the task has ended
  ! ended "$1" || fail "task $1 ended ($(field "$1" JobState), exit code $(field "$1" ExitCode)) too early"
}
started() { # JOB_TASK OUT ...: each task's journal exists (the first sight records its size)
  while [ $# -gt 0 ]; do
    alive "$1"
    journaled "$2" || [ -e "$2.journal" ] || return 1
    shift 2
  done
}
mid_run() { # JOB_TASK OUT: running, at least one case journaled, not finished
  alive "$1"
  [ ! -e "$2" ] || fail "$2 was finished before the test could interrupt it (cases too short?)"
  state_is "$1" RUNNING && journaled "$2"
}
count() { grep -c -- "$1" "$2" || true; }

# --- the studies ------------------------------------------------------------------------
# main: 8 cases of about 3 s each on one core. tiny: 2 cases of milliseconds; case 0
# fails (RK4 at 1 ms hits a singular configuration), so the tasks need --allow-failed.
cat >"$tmp/main/study.yaml" <<'EOF'
name: slurm_main
description: the Slurm test's study - eight cases of a few seconds
duration: 2.0
sample_rate: 500
transient: "0.1 s"
solver: {method: rk4, step: "0.2 us"}   # slow on purpose: about 3 s a case
grid:
  location: [crank_ground, crank_rod]
  waviness_amplitude: ["0 um", "4 um"]
  ball_count: [8, 9]
  rpm: [600]
EOF
cat >"$tmp/tiny/study.yaml" <<'EOF'
name: slurm_tiny
description: the Slurm test's small study - two cases (one fails), three shards
duration: 0.05
sample_rate: 1000
transient: "0.01 s"
solver: {method: rk4, step: "1 ms"}
grid:
  location: [crank_ground, ideal]
  rpm: [600]
EOF

# --- the main array: requeue task 1, cancel and resubmit task 2 -------------------------
sb() { sbatch --parsable "$@" | cut -d';' -f1; }
main=$(sb --chdir="$tmp/main" --array=1-2 --cpus-per-task=1 "$here/array.sbatch" study.yaml 2)
say "main array: job $main (2 shards of 8 cases, --cpus-per-task=1)"

wait_until 120 "both tasks to start" started "${main}_1" "$tmp/main/part_1.h5" "${main}_2" "$tmp/main/part_2.h5"
wait_until 120 "task ${main}_1 to journal a case" mid_run "${main}_1" "$tmp/main/part_1.h5"
scontrol requeue "${main}_1" || fail "scontrol requeue ${main}_1"
say "requeued task ${main}_1 after its first case"
wait_until 120 "task ${main}_2 to journal a case" mid_run "${main}_2" "$tmp/main/part_2.h5"
scancel "${main}_2" || fail "scancel ${main}_2"
wait_until 60 "task ${main}_2 to be cancelled" ended "${main}_2"
state_is "${main}_2" CANCELLED || fail "task ${main}_2 is $(field "${main}_2" JobState), not CANCELLED"
[ ! -e "$tmp/main/part_2.h5" ] || fail "the cancelled task 2 left a finished part_2.h5"
[ -e "$tmp/main/part_2.h5.journal" ] || fail "the cancelled task 2 left no journal"
say "cancelled task ${main}_2 after its first case"

again=$(sb --chdir="$tmp/main" --array=2 --cpus-per-task=1 "$here/array.sbatch" study.yaml 2)
say "resubmitted task 2: job $again"
# The array as a whole is not ok (task 2 was cancelled), so the merge waits for the
# requeued task and the resubmission.
merge=$(sb --chdir="$tmp/main" --dependency="afterok:${main}_1:$again" --output=merge-%j.out \
  --wrap 'studyrun merge merged.h5 part_1.h5 part_2.h5')
say "merge: job $merge, --dependency=afterok:${main}_1:$again"
wait_until 240 "the merge job $merge" merge_ended "$merge"
expect_ok "${main}_1" "requeued task 1"
expect_ok "${again}_2" "resubmitted task 2"
expect_ok "$merge" "merge"
[ -s "$tmp/main/merged.h5" ] || fail "the merge job wrote no merged.h5"

log1=$tmp/main/slurm-${main}_1.out
[ "$(field "${main}_1" Restarts)" -ge 1 ] || fail "task ${main}_1 was not restarted"
[ "$(count 'restart 0,' "$log1")" -eq 1 ] && [ "$(count 'restart 1,' "$log1")" -eq 1 ] ||
  fail "$log1 does not hold both runs of task 1 (--open-mode=append, one requeue)"
grep -q 'from the journal' "$log1" || fail "the requeued task 1 did not resume from its journal ($log1)"
grep -q 'from the journal' "$tmp/main/slurm-${again}_2.out" ||
  fail "the resubmitted task 2 did not resume from its journal"
say "the requeued and the resubmitted task resumed; merged after afterok"

# A finished task submitted again leaves its file alone.
before=$(stat -c '%i %s %Y' "$tmp/main/part_1.h5")
rerun=$(sb --chdir="$tmp/main" --array=1 --cpus-per-task=1 "$here/array.sbatch" study.yaml 2)
wait_until 60 "the rerun of finished task 1 (job $rerun)" ended "${rerun}_1"
expect_ok "${rerun}_1" "the rerun of finished task 1"
[ "$(stat -c '%i %s %Y' "$tmp/main/part_1.h5")" = "$before" ] ||
  fail "the rerun of finished task 1 changed part_1.h5"
say "a rerun of the finished task 1 exited 0 and left part_1.h5 alone"

# --- the tiny array: a failed case, an empty shard, -j 2, afterok on the array ----------
tiny=$(sb --chdir="$tmp/tiny" --array=1-3 --cpus-per-task=2 "$here/array.sbatch" study.yaml 3)
tmerge=$(sb --chdir="$tmp/tiny" --dependency="afterok:$tiny" --output=merge-%j.out \
  --wrap 'studyrun merge merged.h5 part_1.h5 part_2.h5 part_3.h5')
say "tiny array: job $tiny (3 shards of 2 cases, --cpus-per-task=2), merge job $tmerge"
wait_until 120 "the merge job $tmerge" merge_ended "$tmerge"
for k in 1 2 3; do expect_ok "${tiny}_$k" "tiny task $k"; done
expect_ok "$tmerge" "tiny merge"
[ -e "$tmp/tiny/part_3.h5" ] || fail "the empty shard's task 3 wrote no part_3.h5"
say "tiny array: tasks with a failed case and with no case exited 0; merged after afterok"

# --- the same studies in one run each ----------------------------------------------------
single() { # STUDY EXPECTED_EXIT_CODE
  local rc=0
  "$STUDYRUN" run "$tmp/$1/study.yaml" -o "$tmp/single/$1.h5" -j 2 -q || rc=$?
  [ "$rc" -eq "$2" ] || fail "the single run of the $1 study exited $rc, not $2"
}
single main 0
single tiny 3 # finished, a case failed

# --- merged = single, value for value -----------------------------------------------------
cat >"$tmp/compare.py" <<'EOF'
"""Compares two study files: the same objects, every variable's values bit for bit
(but wall_time) and the attributes (but the run's own: created, history, git_commit;
and the dimension scales' references)."""
import sys

import h5py
import numpy as np

SKIP_VARS = {"wall_time"}
SKIP_ATTRS = {"created", "history", "git_commit", "DIMENSION_LIST", "REFERENCE_LIST"}


def objects(f):
    found = {"/": f}
    f.visititems(lambda name, obj: found.__setitem__(name, obj))
    return found


def same(x, y):
    x, y = np.asarray(x), np.asarray(y)
    if x.shape != y.shape or x.dtype != y.dtype:
        return False
    if x.dtype.kind in "biufc":
        return x.tobytes() == y.tobytes()  # bit for bit, NaN included
    return x.tolist() == y.tolist()


a, b = (h5py.File(p, "r") for p in sys.argv[1:3])
oa, ob = objects(a), objects(b)
diffs = [f"{n}: only in {sys.argv[1] if n in oa else sys.argv[2]}" for n in sorted(set(oa) ^ set(ob))]
compared = 0
for name in sorted(set(oa) & set(ob)):
    x, y = oa[name], ob[name]
    ka, kb = set(x.attrs) - SKIP_ATTRS, set(y.attrs) - SKIP_ATTRS
    diffs += [f"{name}: attribute {k} in one file only" for k in sorted(ka ^ kb)]
    diffs += [f"{name}: attribute {k} differs: {x.attrs[k]!r} != {y.attrs[k]!r}"
              for k in sorted(ka & kb) if not same(x.attrs[k], y.attrs[k])]
    if isinstance(x, h5py.Dataset) and name.split("/")[-1] not in SKIP_VARS:
        if not isinstance(y, h5py.Dataset) or not same(x[()], y[()]):
            diffs.append(f"{name}: values differ")
        compared += 1
for d in diffs[:40]:
    print("  " + d)
if diffs or compared == 0:
    sys.exit(f"{len(diffs)} differences ({compared} variables compared)")
print(f"  {compared} variables equal")
EOF
for s in main tiny; do
  say "merged $s study against its single run:"
  "$PYTHON" "$tmp/compare.py" "$tmp/$s/merged.h5" "$tmp/single/$s.h5" ||
    fail "the merged $s study differs from its single run"
done

say "passed in $((SECONDS - started)) s"
