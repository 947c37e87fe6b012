#!/usr/bin/env bash
# estimator_node for live topics: builds if needed, uses the master at
# $ROS_MASTER_URI when one answers there, else starts its own roscore (on
# --port), runs estimator_node until Ctrl-C, then stops exactly what it
# started (by PID).
#   run_live.sh [--config FILE] [--ns NS] [--port P] [--node-args "ARGS"]
#   --config     estimator configuration (default config/speed_bump.yaml)
#   --ns         namespace (ROS_NAMESPACE): subscribes NS/suspension/joint_states
#                and NS/road/profile, publishes NS/parameter_estimate ...
#   --port       port of the roscore started when no master answers (default 11311)
#   --node-args  extra estimator_node arguments, e.g. "_node/joints/left:=fl_shock"
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib/common.sh"
source "$here/lib/roscore.sh"

config="$PC_EKF_ROOT/config/speed_bump.yaml" ns="" port=11311 node_args=""
while [ $# -gt 0 ]; do
  case "$1" in
    --config) config=${2:?--config needs a file}; shift ;;
    --ns) ns=${2:?--ns needs a namespace}; shift ;;
    --port) port=${2:?--port needs a number}; shift ;;
    --node-args) node_args=${2?--node-args needs a value}; shift ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) echo "run_live.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
  shift
done
[ -f "$config" ] || { echo "run_live.sh: no such config: $config" >&2; exit 2; }
config=$(cd "$(dirname "$config")" && pwd)/$(basename "$config")

trap pc_ekf_stop_owned EXIT
trap 'exit 130' INT TERM

pc_ekf_ensure_packages
if [ ! -x "$PC_EKF_EXE_DIR/estimator_node" ]; then
  pc_ekf_build || exit 1
fi
pc_ekf_source_workspace
out="$PC_EKF_STATE/live"
mkdir -p "$out"

export ROS_MASTER_URI=${ROS_MASTER_URI:-http://localhost:$port}
if pc_ekf_master_up; then
  pc_ekf_log "using the running master at $ROS_MASTER_URI"
else
  export ROS_MASTER_URI="http://localhost:$port"
  [ -z "${ROS_HOSTNAME:-}" ] && [ -z "${ROS_IP:-}" ] && export ROS_HOSTNAME=localhost
  pc_ekf_start_owned "roscore:$port" "$out/roscore.log" roscore -p "$port"
  started=$PC_EKF_LAST_PID
  for _ in $(seq 300); do
    pc_ekf_master_up && break
    kill -0 "$started" 2>/dev/null || { pc_ekf_log "roscore failed (port $port taken?); log: $out/roscore.log"; exit 1; }
    sleep 0.1
  done
  pc_ekf_master_up || { pc_ekf_log "roscore did not come up; log: $out/roscore.log"; exit 1; }
  sleep 1 && pc_ekf_adopt_children  # rosmaster and rosout, in sessions of their own
  pc_ekf_log "started roscore at $ROS_MASTER_URI"
fi
export ROS_NAMESPACE=$ns
# shellcheck disable=SC2086  # node_args: several words on purpose
pc_ekf_start_owned estimator_node "$out/estimator_node.log" \
  "$PC_EKF_EXE_DIR/estimator_node" "_config_file:=$config" __name:=estimator_node $node_args
node=$PC_EKF_LAST_PID
prefix=${ns:+/$ns}
echo "estimator_node ${prefix}/estimator_node is running (log: ${out#"$PC_EKF_ROOT"/}/estimator_node.log)."
echo "It listens on ${prefix}/suspension/joint_states (and ${prefix}/road/profile for road.source: topic)."
echo "In another shell:"
echo "  source $PC_EKF_SETUP; export ROS_MASTER_URI=$ROS_MASTER_URI"
echo "  rostopic echo -n 1 ${prefix}/parameter_estimate; rostopic hz ${prefix}/parameter_estimate"
echo "  rosservice call ${prefix}/estimator_node/estimate_batch; rosservice call ${prefix}/estimator_node/reset"
echo "Ctrl-C stops it."
tail -f "$out/estimator_node.log" --pid "$node" &
wait "$node" || { rc=$?; pc_ekf_log "estimator_node exited with $rc"; exit "$rc"; }
