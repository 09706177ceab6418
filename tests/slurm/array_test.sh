#!/usr/bin/env bash
# A recording sharded as a Slurm array job (issue 5): starts a single-node Slurm on loopback, runs a 3-task
# array of `raykin record --range` into one shared folder, merges the part manifests with
# `raykin record --merge`, and checks that every frame exists exactly once and equals a single full run.
#
#   tests/slurm/array_test.sh [RAYKIN_BINARY]      (default: target/debug/raykin, built if missing)
#
# Too slow for every CI run: .ci/run calls it when RAYKIN_SLURM_TEST=1. Installs slurm-wlm and munge with
# apt-get when they are missing and starts munged, slurmctld and slurmd, so it needs root (or sudo); every
# daemon it starts is stopped on exit. docs/RECORDING.md records its last result.
set -euo pipefail
cd "$(dirname "$0")/../.."

SCENE=../shared/assets/RiggedSimple/glTF/RiggedSimple.gltf
FRAMES=10
TASKS=3
RECORDING=(--frames "$FRAMES" --fps 10 --start 0.05 --width 32 --height 32 --spp 8
  --look-from 0,2.5,8 --look-at 0,2.5,0 --fov 40)

sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
say() { echo "slurm-test: $*" >&2; }

RAYKIN=${1:-target/debug/raykin}
if [ ! -x "$RAYKIN" ]; then
  say "building $RAYKIN"
  cargo build --workspace
fi
RAYKIN=$(realpath "$RAYKIN")

if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v munged >/dev/null; then
  say "installing slurm-wlm and munge"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq slurm-wlm munge >/dev/null
fi

WORK=$(mktemp -d /tmp/raykin-slurm.XXXXXX)
chmod 755 "$WORK"
export SLURM_CONF="$WORK/slurm.conf"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$WORK/xdg}"
mkdir -p -m700 "$XDG_RUNTIME_DIR"
started_munge=0
status=failed

cleanup() {
  for pidfile in "$WORK/slurmd.pid" "$WORK/slurmctld.pid"; do
    [ -s "$pidfile" ] && $sudo kill "$(cat "$pidfile")" 2>/dev/null || true
  done
  [ "$started_munge" = 1 ] && $sudo runuser -u munge -- /usr/sbin/munged --stop 2>/dev/null || true
  if [ "$status" = passed ]; then
    $sudo rm -rf "$WORK"
  else
    say "FAILED; logs and outputs kept in $WORK"
  fi
}
trap cleanup EXIT

# munge authenticates Slurm's messages; Debian's package creates the key.
$sudo mkdir -p /run/munge /var/log/munge /var/lib/munge
$sudo chown munge:munge /run/munge /var/log/munge /var/lib/munge
$sudo test -s /etc/munge/munge.key || $sudo mungekey --create
if ! munge -n >/dev/null 2>&1; then
  $sudo runuser -u munge -- /usr/sbin/munged
  started_munge=1
fi
munge -n | unmunge >/dev/null || { say "munge does not work"; exit 1; }

NODE=$(hostname -s)
CPUS=$(nproc)
mkdir -p "$WORK/state" "$WORK/spool" "$WORK/out"
cat >"$SLURM_CONF" <<EOF
ClusterName=raykin-test
SlurmctldHost=$NODE(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/slurmctld.log
SlurmdLogFile=$WORK/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
ReturnToService=2
MpiDefault=none
NodeName=$NODE NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=1000 State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF

say "starting slurmctld and slurmd ($NODE on 127.0.0.1, $CPUS CPUs)"
$sudo env SLURM_CONF="$SLURM_CONF" slurmctld -f "$SLURM_CONF"
$sudo env SLURM_CONF="$SLURM_CONF" slurmd -f "$SLURM_CONF"
for _ in $(seq 60); do
  state=$(sinfo -h -N -o %t 2>/dev/null | head -n1 || true)
  [ "$state" = "idle" ] && break
  sleep 1
done
[ "$state" = "idle" ] || { say "the node did not come up (state '$state'); see $WORK/*.log"; exit 1; }

# One task per slice: frames split as evenly as the count allows.
cat >"$WORK/task.sh" <<EOF
#!/usr/bin/env bash
set -euo pipefail
i=\$SLURM_ARRAY_TASK_ID
a=\$(( i * $FRAMES / $TASKS )); b=\$(( (i + 1) * $FRAMES / $TASKS ))
echo "task \$i on \$(hostname): frames \$a..\$b"
exec "$RAYKIN" record "$(realpath "$SCENE")" --out "$WORK/out" ${RECORDING[*]} --range "\$a..\$b"
EOF
chmod +x "$WORK/task.sh"

say "running a $TASKS-task array (sbatch --wait)"
start=$(date +%s)
sbatch --wait --array=0-$((TASKS - 1)) --cpus-per-task=1 --output="$WORK/task-%a.log" "$WORK/task.sh"
array_seconds=$(( $(date +%s) - start ))
cat "$WORK"/task-*.log >&2

parts=$(ls "$WORK/out"/manifest.part-*.json | wc -l)
[ "$parts" -eq "$TASKS" ] || { say "expected $TASKS part manifests, found $parts"; exit 1; }
"$RAYKIN" record --merge "$WORK/out"

say "single full run for comparison"
"$RAYKIN" record "$SCENE" --out "$WORK/full" "${RECORDING[@]}" 2>/dev/null

frames_out=$(ls "$WORK/out" | grep -c '^frame_')
[ "$frames_out" -eq "$FRAMES" ] || { say "expected $FRAMES frame files, found $frames_out"; exit 1; }
if ls -a "$WORK/out" | grep -q '\.partial$'; then say "temporary files left behind"; exit 1; fi
for k in $(seq 0 $((FRAMES - 1))); do
  f=$(printf 'frame_%05d.png' "$k")
  cmp -s "$WORK/out/$f" "$WORK/full/$f" || { say "$f differs from the single run"; exit 1; }
done
listed=$(grep -c '"index"' "$WORK/out/manifest.json")
[ "$listed" -eq "$FRAMES" ] || { say "merged manifest lists $listed frames"; exit 1; }

status=passed
say "PASSED: $TASKS array tasks wrote $FRAMES frames once each in ${array_seconds}s; merged manifest lists all;" \
  "every frame equals the single run ($(sinfo -V), $(uname -m), $(nproc) CPUs, $(date -u +%F))"
