#!/usr/bin/env bash
# Replays any recorded bag through estimator_node and prints the final
# one-step and batch estimates: builds if needed, starts its own roscore on a
# free port, estimator_node, replay_node (lossless: every sample gets its
# estimate at any speed), calls ~estimate_batch, stops exactly what it
# started (by PID).
#   replay.sh BAG [--config FILE] [--rate R] [--ns NS] [--node-args "ARGS"]
#   --config     estimator configuration (default config/speed_bump.yaml)
#   --rate       replay speed, 1 = recorded timing, 0 = as fast as possible (default 0)
#   --ns         namespace the nodes run in (ROS_NAMESPACE; default none): the
#                estimator subscribes NS/suspension/joint_states, replay_node
#                publishes the bag's relative topic names under NS
#   --node-args  extra estimator_node arguments, e.g. "_node/joints/left:=fl"
# The bag needs suspension/joint_states and, for road.source: topic,
# road/profile (under NS when given); see docs/tools.md and docs/method.md §8.2.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib/common.sh"
source "$here/lib/roscore.sh"

bag="" config="$PC_EKF_ROOT/config/speed_bump.yaml" rate=0 ns="" node_args=""
while [ $# -gt 0 ]; do
  case "$1" in
    --config) config=${2:?--config needs a file}; shift ;;
    --rate) rate=${2:?--rate needs a number}; shift ;;
    --ns) ns=${2:?--ns needs a namespace}; shift ;;
    --node-args) node_args=${2?--node-args needs a value}; shift ;;
    -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
    -*) echo "replay.sh: unknown option '$1'" >&2; exit 2 ;;
    *) [ -z "$bag" ] || { echo "replay.sh: one bag only ('$1')" >&2; exit 2; }; bag=$1 ;;
  esac
  shift
done
[ -n "$bag" ] || { echo "usage: replay.sh BAG [--config FILE] [--rate R] [--ns NS]" >&2; exit 2; }
[ -f "$bag" ] || { echo "replay.sh: no such bag: $bag" >&2; exit 2; }
[ -f "$config" ] || { echo "replay.sh: no such config: $config" >&2; exit 2; }
bag=$(cd "$(dirname "$bag")" && pwd)/$(basename "$bag")
config=$(cd "$(dirname "$config")" && pwd)/$(basename "$config")

trap pc_ekf_stop_owned EXIT
trap 'exit 130' INT TERM

pc_ekf_ensure_packages
if [ ! -x "$PC_EKF_EXE_DIR/estimator_node" ] || [ ! -x "$PC_EKF_EXE_DIR/replay_node" ]; then
  pc_ekf_build || exit 1
fi
pc_ekf_source_workspace
bin=$PC_EKF_EXE_DIR
out="$PC_EKF_STATE/replay_sh"
rm -rf "$out" && mkdir -p "$out"

# Samples in the bag: the collector waits for as many estimates.
# Samples in the bag (topic suspension/joint_states, any leading slash):
# the collector waits for as many estimates.
samples=$(/usr/bin/python3 - "$bag" <<'PY'
import sys, rosbag
with rosbag.Bag(sys.argv[1]) as b:
    print(sum(1 for t, _, _ in b.read_messages() if t.lstrip("/") == "suspension/joint_states"))
PY
) || { pc_ekf_log "cannot read $bag"; exit 1; }
[ "$samples" -gt 0 ] || { pc_ekf_log "$bag has no messages on suspension/joint_states"; exit 1; }

pc_ekf_roscore_start "$out/roscore.log" || exit 1
pc_ekf_log "roscore at $ROS_MASTER_URI; $samples samples in $(basename "$bag")"
export ROS_NAMESPACE=${ns}
# shellcheck disable=SC2086  # node_args: several words on purpose
pc_ekf_start_owned estimator_node "$out/estimator_node.log" "$bin/estimator_node" \
  "_config_file:=$config" __name:=estimator_node $node_args
estimator=$PC_EKF_LAST_PID
pc_ekf_start_owned collector "$out/collector.log" /usr/bin/python3 \
  "$here/lib/collect_estimates.py" --expect "$samples" --batch --ready "$out/ready" --timeout 3600
collector=$PC_EKF_LAST_PID
for _ in $(seq 1200); do
  [ -e "$out/ready" ] && break
  kill -0 "$collector" 2>/dev/null && kill -0 "$estimator" 2>/dev/null || break
  sleep 0.1
done
[ -e "$out/ready" ] || { pc_ekf_log "estimator_node did not come up"; tail -5 "$out/estimator_node.log" >&2; exit 1; }
pc_ekf_start_owned replay_node "$out/replay_node.log" "$bin/replay_node" "_bag:=$bag" \
  "_rate:=$rate" _lossless:=true __name:=replay_node
wait "$PC_EKF_LAST_PID" || { pc_ekf_log "replay_node failed"; tail -5 "$out/replay_node.log" >&2; exit 1; }
wait "$collector" || { pc_ekf_log "collecting estimates failed"; tail -5 "$out/collector.log" >&2; exit 1; }
tail -n 1 "$out/collector.log" >"$out/node.json"
/usr/bin/python3 - "$out/node.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
last, batch, truth = r["last"], r["batch"], r["truth"]
print(f"parameter_estimate: {r['received']} messages ({r['distinct_stamps']} distinct stamps)")
rows = {p["name"]: p for p in (truth or {}).get("parameters", [])}
print(f"{'parameter':<22}{'truth':>12}{'one-step':>28}{'batch':>28}")
for i, p in enumerate(last["parameters"]):
    b = batch["parameters"][i] if batch else None
    t = rows.get(p["name"])
    cell = lambda q: f"{q['mean']:.6g} +- {q['stddev']:.3g}" if q else "n/a"
    truth_text = f"{t['mean']:.6g}" if t else "n/a"
    print(f"{p['name']:<22}{truth_text:>12}{cell(p):>28}{cell(b):>28}")
print("health: one-step " + ("healthy" if last["healthy"] else "UNHEALTHY " + "; ".join(last["warnings"]))
      + ("; batch " + ("healthy" if batch["healthy"] else "UNHEALTHY") if batch else "; batch: " + str(r["batch_reply"])))
PY
pc_ekf_log "logs: ${out#"$PC_EKF_ROOT"/}/"
