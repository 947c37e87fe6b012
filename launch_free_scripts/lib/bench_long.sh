#!/usr/bin/env bash
# Part of bench.sh: the node over a long drive (the product runs for hours).
# Synthesises config/long_drive.yaml's 20-minute drive (200 Hz, 240 000
# samples, ISO roads, four stops, the load changed at two) as a bag, starts its
# own roscore on a free port, estimator_node with long_drive.yaml as shipped
# and a counter (bench_node_throughput), plays the bag with
# `rosbag play -r RATE` (no handshake: the node keeps up through its queues),
# samples the node's VmRSS every 2 s, then times estimate_offline --bag on the
# same bag (median of RUNS, /usr/bin/time -v for its peak RSS) and compares
# the node's last estimate with it. Stops what it started, by PID.
#   bench_long.sh BIN_DIR OUT_DIR [RATE] -> OUT_DIR/long.json (lib/bench_long.py)
# RATE: default PC_EKF_BENCH_LONG_RATE or 5 (1 kHz of samples, the drive in
# 4 minutes; 1 is the config's own 200 Hz, 20 minutes). The bag (437 MB) is
# removed at the end unless PC_EKF_BENCH_LONG_KEEP=1.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
pc_ekf_require_sources bench_long.sh
source "$here/roscore.sh"

bin=$1
out=$2
rate=${3:-${PC_EKF_BENCH_LONG_RATE:-5}}
runs=${PC_EKF_BENCH_RUNS:-3}
config=$PC_EKF_ROOT/config/long_drive.yaml
mkdir -p "$out"
rm -f "$out"/long.json "$out"/rss.txt "$out"/last.json "$out"/offline.*
json="$out/long.json"

write_null() {
  printf '{"long_node_rss_growth_mb": null, "reason": "%s"}\n' "$1" >"$json"
  pc_ekf_log "long-drive benchmark skipped: $1"
  exit 0
}

for exe in estimator_node synthesize_bag bench_node_throughput estimate_offline; do
  [ -x "$bin/$exe" ] || write_null "$exe not built"
done

bag="$out/long_drive.bag"
cleanup() {
  pc_ekf_stop_owned
  [ "${PC_EKF_BENCH_LONG_KEEP:-0}" = 1 ] || rm -f "$bag"
}
trap cleanup EXIT
trap 'exit 130' INT TERM
pc_ekf_source_workspace

"$bin/synthesize_bag" --config "$config" --output "$bag" >"$out/synthesize_bag.log" 2>&1 ||
  write_null "synthesize_bag failed (see synthesize_bag.log)"
# synthesize_bag: "wrote BAG (N samples, ...": one joint_states message per sample.
samples=$(grep -oE '\(([0-9]+) samples' "$out/synthesize_bag.log" | grep -oE '[0-9]+')
[ -n "$samples" ] || write_null "no sample count in synthesize_bag.log"

pc_ekf_roscore_start "$out/roscore.log" || write_null "roscore did not start"
pc_ekf_start_owned estimator_node "$out/estimator_node.log" \
  "$bin/estimator_node" "_config_file:=$config" __name:=estimator_node
estimator=$PC_EKF_LAST_PID
rm -f "$out/ready"
# linger: the node's /diagnostics (1 Hz) reports once more after the last sample.
pc_ekf_start_owned counter "$out/counter.log" "$bin/bench_node_throughput" \
  "_expect:=$samples" _timeout:=60 "_ready:=$out/ready" "_lag_file:=$out/lags.txt" \
  "_last_file:=$out/last.json" "_rate:=$rate" _linger:=2.5 __name:=bench_node_throughput
counter=$PC_EKF_LAST_PID
for _ in $(seq 600); do
  [ -e "$out/ready" ] && break
  { kill -0 "$estimator" && kill -0 "$counter"; } 2>/dev/null || break
  sleep 0.1
done
[ -e "$out/ready" ] || write_null "estimator_node did not come up (see estimator_node.log)"

# "unix-time VmRSS-kB" every 2 s while the node lives. A background job of a
# script ignores SIGINT; env gives the sampler its default back, so it stops at once.
# shellcheck disable=SC2016  # expanded by the sampler's own shell
pc_ekf_start_owned rss_sampler "$out/rss.txt" env --default-signal=INT bash -c \
  'while rss=$(awk "/^VmRSS:/ { print \$2 }" "/proc/$1/status" 2>/dev/null) && [ -n "$rss" ]; do
     echo "$(date +%s.%N) $rss"; sleep 2; done' rss_sampler "$estimator"
uptime >"$out/uptime_node.txt"
pc_ekf_log "playing the $samples-sample drive at rate $rate (wall about $(awk -v n="$samples" -v r="$rate" 'BEGIN { printf "%.0f", n / 200 / r }') s)"
pc_ekf_start_owned rosbag_play "$out/rosbag_play.log" /usr/bin/rosbag play --quiet -r "$rate" -d 1 "$bag"
replay=$PC_EKF_LAST_PID
wait "$counter"
rss_end_kb=$(awk '/^VmRSS:/ { print $2 }' "/proc/$estimator/status" 2>/dev/null)
hwm_kb=$(awk '/^VmHWM:/ { print $2 }' "/proc/$estimator/status" 2>/dev/null)
echo "$(date +%s.%N) ${rss_end_kb:-}" >"$out/rss_end.txt"
wait "$replay" 2>/dev/null
pc_ekf_stop_owned  # node and roscore: estimate_offline below has the machine to itself

# estimate_offline --bag, whole command: RUNS times (median wall), peak RSS of each.
uptime >"$out/uptime_offline.txt"
for i in $(seq "$runs"); do
  t0=$(date +%s.%N)
  /usr/bin/time -v -o "$out/offline.$i.time" "$bin/estimate_offline" --config "$config" \
    --bag "$bag" >"$out/offline.$i.json" 2>"$out/offline.$i.err" ||
    pc_ekf_log "estimate_offline --bag failed (run $i; see offline.$i.err)"
  t1=$(date +%s.%N)
  echo "$t0 $t1" >"$out/offline.$i.wall"
done

/usr/bin/python3 "$here/bench_long.py" "$out" "$samples" "$rate" "$runs" "${hwm_kb:-}" >"$json"
pc_ekf_log "long drive: $(cat "$json")"
