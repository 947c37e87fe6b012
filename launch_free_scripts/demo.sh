#!/usr/bin/env bash
# The demo (the README's first command): installs what is missing, builds, starts
# its own roscore on a free port, synthesises the paper's speed-bump data
# into bags (N = 10 and N = 100 samples over 3 s, 1 % noise), replays each
# through replay_node into estimator_node (lossless handshake, full speed),
# asks the node for its batch (ES-MDA) estimate, and prints M and d_CG next
# to the truth and to estimate_offline on the same bag. Stops exactly what it
# started (by PID, also on Ctrl-C or failure).
#   --samples "10 100"  the sample counts to run (default both)
#   --model full_car    instead: the 7-DOF full car (config/full_car_bump.yaml,
#                       N = 100, road/heights and four suspension joints)
#   --model road_free   instead: no road at all (config/vehicle_imu.yaml): 10 s on
#                       an ISO 8608 class B road at 36 km/h the estimator is never
#                       told, suspension joints and a raw IMU at 200 Hz, N = 2000
#   --node-args "ARGS"  extra estimator_node arguments, e.g. "_node/publish_pdf:=false"
#   --hold              then loop the last bag in real time into a fresh
#                       estimator_node until Enter / Ctrl-C (rostopic echo/hz,
#                       rosnode info, rosservice call against the live graph)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib/common.sh"
source "$here/lib/roscore.sh"

sample_counts="10 100"
model=roll_plane
node_args=""
hold=0
while [ $# -gt 0 ]; do
  case "$1" in
    --samples) sample_counts=${2:?--samples needs a list, e.g. \"10 100\"}; shift ;;
    --node-args) node_args=${2?--node-args needs a value}; shift ;;
    --model) model=${2:?--model needs roll_plane, full_car or road_free}; shift ;;
    --hold) hold=1 ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    *) echo "demo.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
  shift
done

span="3 s, 1 % noise"
case "$model" in
  roll_plane) base_config="$PC_EKF_ROOT/config/speed_bump.yaml"; stem=speed_bump ;;
  full_car) base_config="$PC_EKF_ROOT/config/full_car_bump.yaml"; stem=full_car; sample_counts=100 ;;
  road_free) base_config="$PC_EKF_ROOT/config/vehicle_imu.yaml"; stem=road_free; sample_counts=2000
             span="10 s, the config's sensor noise" ;;
  *) echo "demo.sh: unknown model '$model' (roll_plane, full_car or road_free)" >&2; exit 2 ;;
esac

trap pc_ekf_stop_owned EXIT
trap 'exit 130' INT TERM  # through the EXIT trap

# The estimate collector (lib/collect_estimates.py) is rospy and calls a std_srvs service.
pc_ekf_ensure_packages
pc_ekf_build || exit 1
pc_ekf_source_workspace
bin=$PC_EKF_EXE_DIR
plotter=$PC_EKF_ROOT/scripts/plot_estimates
[ "$PC_EKF_INSTALLED" = 1 ] && plotter=$bin/plot_estimates
out="$PC_EKF_STATE/demo"
rm -rf "$out" && mkdir -p "$out"

pc_ekf_roscore_start "$out/roscore.log" || exit 1
pc_ekf_log "roscore at $ROS_MASTER_URI (pid $PC_EKF_ROSCORE_PID)"

# demo_fail MESSAGE LOG...: reports a failed step with the end of its logs.
demo_fail() {
  pc_ekf_log "$1"
  shift
  tail -n 5 "$@" >&2
  return 1
}

# demo_run N: one bag of N samples through the graph and offline; prints its
# table. (Called in an `||` list, where `set -e` is off: every step is checked.)
demo_run() {
  local n=$1 config=$base_config
  local bag="$out/${stem}_n$n.bag" run="$out/n$n"
  mkdir -p "$run"
  if [ "$model" = roll_plane ] && [ "$n" != 10 ]; then  # the paper's file with sampling.samples = N
    config="$out/speed_bump_n$n.yaml"
    sed -E "/^sampling:/,/^[a-z]/ s/^(  samples:) *10\b/\1 $n/" \
      "$PC_EKF_ROOT/config/speed_bump.yaml" >"$config"
    grep -qE "^  samples: $n\b" "$config" || { pc_ekf_log "cannot set samples: $n"; return 1; }
  fi
  "$bin/synthesize_bag" --config "$config" --output "$bag" 2>"$run/synthesize_bag.log" ||
    { demo_fail "synthesize_bag failed" "$run/synthesize_bag.log"; return 1; }

  # The estimator, then the collector; replay_node waits until both have
  # connected to it (~wait_for_subscribers) and, with ~lossless, publishes
  # each sample once the estimate of the previous one arrived.
  # shellcheck disable=SC2086  # node_args: several words on purpose
  pc_ekf_start_owned estimator_node "$run/estimator_node.log" \
    "$bin/estimator_node" "_config_file:=$config" __name:=estimator_node $node_args
  local estimator=$PC_EKF_LAST_PID
  pc_ekf_start_owned collector "$run/collector.log" /usr/bin/python3 \
    "$here/lib/collect_estimates.py" --expect "$n" --batch --ready "$run/ready" --timeout 120
  local collector=$PC_EKF_LAST_PID
  # The figure of this run: every estimate, the batch result, PDFs, truth.
  pc_ekf_start_owned plot_estimates "$run/plot_estimates.log" /usr/bin/python3 \
    "$plotter" --save "$run/estimates.png" --samples "$n" --batch --ready "$run/plot_ready" \
    --timeout 120
  local plot=$PC_EKF_LAST_PID
  for _ in $(seq 1200); do
    [ -e "$run/ready" ] && [ -e "$run/plot_ready" ] && break
    kill -0 "$collector" 2>/dev/null && kill -0 "$estimator" 2>/dev/null &&
      kill -0 "$plot" 2>/dev/null || break
    sleep 0.1
  done
  [ -e "$run/ready" ] && [ -e "$run/plot_ready" ] ||
    { demo_fail "estimator_node did not come up" "$run"/estimator_node.log "$run"/collector.log \
        "$run"/plot_estimates.log; return 1; }

  pc_ekf_start_owned replay_node "$run/replay_node.log" "$bin/replay_node" "_bag:=$bag" \
    _rate:=0 _lossless:=true __name:=replay_node
  wait "$PC_EKF_LAST_PID" || { demo_fail "replay_node failed" "$run/replay_node.log"; return 1; }
  wait "$collector" || { demo_fail "collecting the estimates failed" "$run/collector.log"; return 1; }
  wait "$plot" || { demo_fail "plot_estimates failed" "$run/plot_estimates.log"; return 1; }
  # The collector's JSON is the last line of its log (rospy may log before it).
  tail -n 1 "$run/collector.log" >"$run/node.json"

  "$bin/estimate_offline" --config "$config" --bag "$bag" --out "$run/offline_one_step" \
    >/dev/null 2>"$run/offline.log" &&
    "$bin/estimate_offline" --config "$config" --bag "$bag" --method es_mda \
      >"$run/offline_es_mda.json" 2>>"$run/offline.log" ||
    { demo_fail "estimate_offline failed" "$run/offline.log"; return 1; }

  echo
  echo "== N = $n samples over $span (bag: ${bag#"$PC_EKF_ROOT"/}) =="
  /usr/bin/python3 "$here/lib/demo_table.py" "$n" "$run/node.json" \
    "$run/offline_one_step" "$run/offline_es_mda.json" "$run/replay_node.log" || return 1
  echo "figure: $run/estimates.png ($(grep -o "from [0-9]* estimates" "$run/plot_estimates.log"))"
  pc_ekf_stop_group "$estimator" estimator_node
}

if [ "$model" = full_car ]; then
  echo "Estimating the added mass M and its position (x_M forward of the rear axle, y_M left of"
  echo "the right wheels) on the 7-DOF full car over an oblique speed bump"
elif [ "$model" = road_free ]; then
  echo "Estimating the added mass M and its position d_CG with no road known: 10 s on a rough"
  echo "road (ISO 8608 class B, 36 km/h), from the suspension readings and a body IMU"
else
  echo "Estimating the added mass M and its position d_CG on the paper's speed bump"
fi
echo "(square-root PC-EKF one step per sample; batch = ES-MDA on all samples)."
for n in $sample_counts; do
  demo_run "$n" || exit 1
done
echo
echo "err/std = (estimate - truth) / std. Logs: ${out#"$PC_EKF_ROOT"/}/"

[ "$hold" = 1 ] || exit 0
# Live: the last bag looped in real time; the estimator starts over at each
# pass (stamps jump back), so there is always something to look at.
last_n=${sample_counts##* }
config=$base_config
[ -e "$out/${stem}_n$last_n.yaml" ] && config="$out/${stem}_n$last_n.yaml"
# shellcheck disable=SC2086
pc_ekf_start_owned estimator_node "$out/live_estimator_node.log" "$bin/estimator_node" \
  "_config_file:=$config" _node/reset_on_time_jump:=true __name:=estimator_node $node_args
pc_ekf_start_owned replay_node "$out/live_replay_node.log" "$bin/replay_node" \
  "_bag:=$out/${stem}_n$last_n.bag" _rate:=1 _loop:=true __name:=replay_node
echo
echo "Live: replay_node loops ${stem}_n$last_n.bag in real time into estimator_node."
echo "In another shell:"
echo "  source $PC_EKF_SETUP"
echo "  export ROS_MASTER_URI=$ROS_MASTER_URI ROS_HOSTNAME=${ROS_HOSTNAME:-}"
echo "  rostopic echo -n 1 /parameter_estimate; rostopic hz /parameter_estimate"
echo "  rosnode info /estimator_node; rosservice call /estimator_node/estimate_batch"
echo "Press Enter (or Ctrl-C) to stop everything."
read -r _ || true
