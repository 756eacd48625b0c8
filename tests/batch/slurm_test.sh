#!/usr/bin/env bash
# `unique3d batch` on a real Slurm: a single-node cluster (munged, slurmctld, slurmd on localhost, with a
# slurm.conf generated in a temporary folder) runs scripts/cluster/unique3d_batch.sbatch as a 3-task
# array over view sets rendered from the bundled example and the repository's test object.
#   1. The array over 6 view sets: every object done exactly once, no partial folder, nothing failed.
#   2. Three view sets added; the array again, and one task cancelled (scancel of its index) while an
#      object of its is half-written; the rest of the array ends; then the whole array resubmitted.
#      Every object done exactly once over all runs, the killed object's partial folder gone, and the
#      objects of step 1 not recomputed (their done.json unchanged byte for byte).
# The daemons are stopped at the end whatever happens. Exit 0: passed, 1: failed, 77 (ctest's skip):
# the daemons cannot start here, with the reason.
#   tests/batch/slurm_test.sh UNIQUE3D_BINARY SOURCE_DIR
set -uo pipefail
cli=$1
src=$2
tmp=$(mktemp -d /tmp/unique3d_slurm.XXXXXX)
pids=()
cleanup() {
  local status=$?
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null; done
  if [ $status -eq 0 ] || [ $status -eq 77 ]; then rm -rf "$tmp"; else echo "slurm_test: kept $tmp (logs)"; fi
  exit $status
}
trap cleanup EXIT
trap 'exit 1' INT TERM
fail() { echo "slurm_test: FAILED: $*"; exit 1; }
skip() {
  printf 'slurm_test.sh: Skipped\n%s\n\n' "$*"
  exit 77
}

for tool in munged slurmctld slurmd sbatch squeue scancel sinfo python3; do
  command -v "$tool" >/dev/null 2>&1 || PATH="$PATH:/usr/sbin" command -v "$tool" >/dev/null 2>&1 ||
    skip "$tool is not installed (scripts/install_deps.sh installs slurm-wlm and munge)"
done
export PATH="$PATH:/usr/sbin"

# --- the cluster -------------------------------------------------------------------------------------
mkdir -p "$tmp/munge" "$tmp/state" "$tmp/spool" "$tmp/logs"
chmod 700 "$tmp/munge"
head -c 1024 /dev/urandom > "$tmp/munge/munge.key"
chmod 400 "$tmp/munge/munge.key"
munged -F -f --key-file="$tmp/munge/munge.key" --socket="$tmp/munge/munge.sock" --pid-file="$tmp/munge/munged.pid" \
  --log-file="$tmp/munge/munged.log" --seed-file="$tmp/munge/munged.seed" > "$tmp/logs/munged.out" 2>&1 &
pids+=($!)

read -r ctld_port d_port < <(python3 -c '
import socket
socks = [socket.socket() for _ in range(2)]
for s in socks: s.bind(("127.0.0.1", 0))
print(*[s.getsockname()[1] for s in socks])')
node=$(hostname -s)
user=$(id -un)
cat > "$tmp/slurm.conf" <<CONF
ClusterName=u3dtest
SlurmctldHost=$node(127.0.0.1)
SlurmUser=$user
SlurmdUser=$user
SlurmctldPort=$ctld_port
SlurmdPort=$d_port
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge/munge.sock
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/logs/slurmctld.log
SlurmdLogFile=$tmp/logs/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
SwitchType=switch/none
MailProg=/bin/true
ReturnToService=2
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
NodeName=$node NodeAddr=127.0.0.1 CPUs=2 RealMemory=1000 State=UNKNOWN
PartitionName=test Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$tmp/slurm.conf"
sleep 0.5
[ -S "$tmp/munge/munge.sock" ] || skip "munged did not start: $(tail -n 3 "$tmp/logs/munged.out" | tr '\n' ' ')"
slurmctld -D -f "$SLURM_CONF" > "$tmp/logs/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$node" > "$tmp/logs/slurmd.out" 2>&1 &
pids+=($!)
ready=0
for _ in $(seq 1 60); do
  state=$(sinfo -h -N -o %T 2>/dev/null | head -n 1)
  if [ "$state" = idle ]; then ready=1; break; fi
  sleep 0.5
done
[ $ready -eq 1 ] || skip "the single-node Slurm did not come up (node state '${state:-none}'): $(tail -n 3 "$tmp/logs/slurmctld.out" "$tmp/logs/slurmd.out" 2>/dev/null | tr '\n' ' ')"
echo "slurm_test: slurmctld and slurmd up on $node, ports $ctld_port/$d_port"

# --- the view sets -----------------------------------------------------------------------------------
render() {  # MESH NAME FILL
  "$cli" -q render "$1" -o "$tmp/inputs/$2" --res 96 --fill "$3" > /dev/null || fail "render $2"
}
mkdir -p "$tmp/inputs"
spot="$src/examples/spot/spot.obj"
avocado="$src/tests/data/objects/avocado/avocado.obj"
render "$spot" spot_a 0.6; render "$spot" spot_b 0.75; render "$spot" spot_c 0.9
render "$avocado" avocado_a 0.6; render "$avocado" avocado_b 0.75; render "$avocado" avocado_c 0.9
first=(avocado_a avocado_b avocado_c spot_a spot_b spot_c)

out="$tmp/out"
options=(--coarse-steps 20 --refine-steps 10 --texture-size 256 --faces 2000 --visibility-resolution 256)
sbatch_array() {  # -> job id
  UNIQUE3D="$cli" sbatch --parsable --array=0-2 --cpus-per-task=1 --mem=200M --output="$tmp/logs/task-%A_%a.log" \
    "$src/scripts/cluster/unique3d_batch.sbatch" "$tmp/inputs" "$out" "${options[@]}" | cut -d';' -f1
}
wait_job() {  # JOB SECONDS
  for _ in $(seq 1 $((2 * $2))); do
    [ -z "$(squeue -h -j "$1" 2>/dev/null)" ] && return 0
    sleep 0.5
  done
  fail "job $1 still running after $2 s: $(squeue -h -j "$1" | tr '\n' ' ')"
}
# How many times the reports say NAME was done.
times_done() {
  python3 - "$out/.reports" "$1" <<'PY'
import json, pathlib, sys
reports = pathlib.Path(sys.argv[1]).glob("*.json")
print(sum(o["name"] == sys.argv[2] and o["outcome"] == "done" for r in reports for o in json.loads(r.read_text())["objects"]))
PY
}
check_complete() {  # NAMES...
  for name in "$@"; do
    [ -f "$out/$name/done.json" ] && [ -f "$out/$name/mesh.glb" ] || fail "$name has no done.json and mesh.glb"
    [ "$(times_done "$name")" = 1 ] || fail "$name done $(times_done "$name") times, not once"
  done
  [ -z "$(find "$out" -maxdepth 1 -name '.*+partial-*')" ] || fail "partial folders left: $(ls -a "$out")"
  [ -z "$(find "$out" -maxdepth 1 -name '*.failed.json')" ] || fail "failures: $(cat "$out"/*.failed.json)"
}

# --- 1. the whole array --------------------------------------------------------------------------------
job=$(sbatch_array) || fail "sbatch"
echo "slurm_test: array job $job over ${#first[@]} view sets"
wait_job "$job" 150
check_complete "${first[@]}"
[ "$(ls "$out/.reports" | wc -l)" = 3 ] || fail "expected 3 task reports: $(ls "$out/.reports")"
python3 - "$out/.reports" <<'PY'
import json, pathlib, sys
for r in sorted(pathlib.Path(sys.argv[1]).glob("*.json")):
    j = json.loads(r.read_text())
    print(f"slurm_test: shard {j['shard']}: {j['done']} done, {j['skipped']} skipped, peak memory {j['peak_memory_mib']:.0f} MiB")
PY
(cd "$out" && sha256sum */done.json) > "$tmp/done_before.txt"

# --- 2. three more, one task killed mid-way, the array resubmitted -------------------------------------
render "$spot" spot_d 0.5; render "$avocado" avocado_d 0.5; render "$avocado" avocado_e 0.8
added=(spot_d avocado_d avocado_e)
# The index with the most of the added objects.
victim=0; most=-1
for i in 0 1 2; do
  "$cli" -q batch "$tmp/inputs" -o "$out" --shard "$i/3" --jobs-file "$tmp/jobs_$i.txt" "${options[@]}" > /dev/null ||
    fail "--jobs-file"
  n=$(grep -c $'\ttodo\t' "$tmp/jobs_$i.txt")
  if [ "$n" -gt "$most" ]; then most=$n; victim=$i; fi
done
victim_objects=$(awk -F'\t' '$3 == "todo" {print $1}' "$tmp/jobs_$victim.txt")
job=$(sbatch_array) || fail "sbatch"
echo "slurm_test: array job $job; cancelling index $victim while one of its objects ($(echo $victim_objects)) is half-written"
killed=0
for _ in $(seq 1 600); do
  for name in $victim_objects; do
    if [ -n "$(find "$out" -maxdepth 1 -name ".$name+partial-*")" ]; then killed=1; break; fi
  done
  [ $killed -eq 1 ] && break
  sleep 0.1
done
[ $killed -eq 1 ] || fail "no object of index $victim started within 60 s"
scancel "${job}_${victim}" || fail "scancel ${job}_${victim}"
wait_job "$job" 150
[ -n "$(find "$out" -maxdepth 1 -name '.*+partial-*')" ] ||
  fail "the cancelled task left no partial folder: it was not stopped mid-object"
job=$(sbatch_array) || fail "sbatch"
echo "slurm_test: array job $job resubmitted"
wait_job "$job" 150
check_complete "${first[@]}" "${added[@]}"
(cd "$out" && sha256sum "${first[@]/%//done.json}") | cmp -s - "$tmp/done_before.txt" ||
  fail "done.json of objects done in step 1 changed: they were recomputed"
echo "slurm_test: passed (${#first[@]} + ${#added[@]} objects, each done once)"
