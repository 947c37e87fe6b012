#!/usr/bin/env bash
# Part of bench.sh: estimator_node end to end. Synthesises a bag of
# 10^4 samples (1 kHz for 10 s, the paper's speed bump and noise), starts its
# own roscore on a free port, estimator_node and a counter
# (bench_node_throughput), replays the bag with replay_node at full speed
# (rate 0, no handshake: the node must keep up through its queues), and
# reports the estimates received per second from first to last, how many
# were lost, and the node's peak RSS (VmHWM). Stops what it started, by PID.
#   bench_node.sh BIN_DIR OUT_DIR     -> OUT_DIR/node.json
#   bench_node.sh BIN_DIR OUT_DIR n11 -> OUT_DIR/node.json: the n = 11 roll
#     plane (test/benchmarks/roll_plane_tolerances.yaml, 10^5 PDF draws every
#     100th sample) at 1 kHz for 10 s, replayed in real time (rate 1) without
#     the handshake, re-linearisation deferred (filter.relinearize.defer 1);
#     adds node_max_lag_ms (bench_node_throughput).
#   bench_node.sh BIN_DIR OUT_DIR road_free -> OUT_DIR/node.json: road-free
#     estimation as shipped (config/vehicle_imu.yaml: 10 s at 200 Hz on ISO
#     class B, joint_states and imu/data, no road), played by
#     `rosbag play -r 5` (1 kHz, no handshake); node_max_lag_ms as above.
#   bench_node.sh BIN_DIR OUT_DIR full_car_imu -> OUT_DIR/node.json: the same
#     with config/full_car_imu.yaml as shipped (four corners, imu/data, odom).
#   bench_node.sh BIN_DIR OUT_DIR live -> OUT_DIR/node.json: the node with
#     config/vehicle_live.yaml as shipped (road from road/profile, its PDFs,
#     re-linearisation and threads) on a bag of the paper bump synthesised at
#     1 kHz for 10 s (vehicle_live.yaml with road speed_bump, 10^4 samples),
#     played by `rosbag play` at the recorded rate (no handshake);
#     node_max_lag_ms as above.
# Writes null figures (with the reason) when the executables are missing.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
pc_ekf_require_sources bench_node.sh
source "$here/roscore.sh"

bin=$1
out=$2
mode=${3:-paper}
samples=${PC_EKF_BENCH_NODE_SAMPLES:-10000}
duration=$(awk -v n="$samples" 'BEGIN { printf "%g", n / 1000 }')  # 1 kHz
# The road-free configs' own drives: 10 s at 200 Hz.
road_free=0
case "$mode" in road_free|full_car_imu) road_free=1; samples=2000 ;; esac
# (live: the 1 kHz bag below; the node's config is vehicle_live.yaml as shipped)
mkdir -p "$out"
json="$out/node.json"

write_null() {
  printf '{"node_samples_per_s": null, "node_peak_rss_mb": null, "reason": "%s"}\n' "$1" >"$json"
  pc_ekf_log "node benchmark skipped: $1"
  exit 0
}

for exe in estimator_node replay_node synthesize_bag bench_node_throughput; do
  [ -x "$bin/$exe" ] || write_null "$exe not built"
done

trap pc_ekf_stop_owned EXIT
trap 'exit 130' INT TERM
pc_ekf_source_workspace

if [ "$mode" = n11 ]; then
  # n = 11 at 1 kHz: the benchmark config's PDF settings (10^5 draws,
  # pdf_every 100), fed at the recorded rate.
  base=$PC_EKF_ROOT/test/benchmarks/roll_plane_tolerances.yaml
  draws=100000
  rate=1
else
  # The 1 kHz configuration: parameter_pdf every 100th sample (10 Hz) from
  # 20000 germ draws, replayed as fast as the node takes it.
  base=$PC_EKF_ROOT/config/speed_bump.yaml
  draws=20000
  rate=0
fi
config="$out/${mode}_1khz.yaml"
bag_config=$config  # what synthesize_bag simulates (live: the bump, not the topic)
if [ "$road_free" -eq 1 ]; then
  # As shipped: only the node's joint names are what synthesize_bag writes.
  cp "$PC_EKF_ROOT/config/$([ "$mode" = road_free ] && echo vehicle_imu || echo full_car_imu).yaml" "$config"
elif [ "$mode" = live ]; then
  cp "$PC_EKF_ROOT/config/vehicle_live.yaml" "$config"
  bag_config="$out/live_bag.yaml"
  sed -E "/^road:/,/^[a-z]/ s/^(  source:) *topic\b.*/\1 speed_bump/" "$config" >"$bag_config"
  printf 'sampling:\n  samples: %s\n  duration: %s\n' "$samples" "$duration" >>"$bag_config"
  grep -qE "^  source: speed_bump" "$bag_config" || write_null "cannot set road.source in the bag's config"
else
sed -E -e "/^sampling:/,/^[a-z]/ s/^(  samples:) *[0-9]+/\1 $samples/" \
  -e "/^sampling:/,/^[a-z]/ s/^(  duration:) *[0-9.]+/\1 $duration/" \
  -e "/^pdf:/,/^[a-z]/ s/^(  draws:) *[0-9]+/\1 $draws/" \
  -e "/^node:/,/^[a-z]/ s/^(  pdf_every:) *[0-9]+/\1 100/" \
  "$base" >"$config"
fi
if [ "$mode" = n11 ]; then
  # The node defers its re-linearisation re-runs (docs/realtime.md): a re-run
  # of the kept samples in one sample's callback would stall a 1 kHz stream.
  sed -i -E 's/^(  relinearize: \{.*max_samples: [0-9]+)\}/\1, defer: 1.0}/' "$config"
  grep -q "defer: 1.0" "$config" || write_null "cannot set filter.relinearize.defer in the config"
fi
grep -qE "^  samples: $samples\b" "$bag_config" || write_null "cannot set sampling.samples in the config"
if [ "$road_free" -eq 0 ] && [ "$mode" != live ]; then
  grep -qE "^  pdf_every: 100\b" "$config" && grep -qE "^  draws: $draws\b" "$config" ||
    write_null "cannot set node.pdf_every / pdf.draws in the config"
fi
bag="$out/${mode}_1khz.bag"
"$bin/synthesize_bag" --config "$bag_config" --output "$bag" >"$out/synthesize_bag.log" 2>&1 ||
  write_null "synthesize_bag failed (see node/synthesize_bag.log)"

pc_ekf_roscore_start "$out/roscore.log" || write_null "roscore did not start"
pc_ekf_start_owned estimator_node "$out/estimator_node.log" \
  "$bin/estimator_node" "_config_file:=$config" __name:=estimator_node
estimator=$PC_EKF_LAST_PID
rm -f "$out/ready"
pc_ekf_start_owned counter "$out/counter.log" "$bin/bench_node_throughput" \
  "_expect:=$samples" _timeout:=30 "_ready:=$out/ready" "_lag_file:=$out/lags.txt" "_rate:=$([ "$road_free" -eq 1 ] && echo 5.0 || echo 1.0)" \
  __name:=bench_node_throughput
counter=$PC_EKF_LAST_PID
for _ in $(seq 600); do
  [ -e "$out/ready" ] && break
  kill -0 "$estimator" 2>/dev/null && kill -0 "$counter" 2>/dev/null || break
  sleep 0.1
done
[ -e "$out/ready" ] || write_null "estimator_node did not come up (see node/estimator_node.log)"

start=$(date +%s.%N)
if [ "$road_free" -eq 1 ]; then
  pc_ekf_start_owned rosbag_play "$out/replay_node.log" /usr/bin/rosbag play --quiet -r 5 -d 1 "$bag"
elif [ "$mode" = live ]; then
  pc_ekf_start_owned rosbag_play "$out/replay_node.log" /usr/bin/rosbag play --quiet -d 1 "$bag"
else
  pc_ekf_start_owned replay_node "$out/replay_node.log" "$bin/replay_node" "_bag:=$bag" \
    "_rate:=$rate" _lossless:=false __name:=replay_node
fi
replay=$PC_EKF_LAST_PID
wait "$counter"
end=$(date +%s.%N)
# Peak resident set of the estimator over the run (kB), read before stopping it.
rss_kb=$(awk '/^VmHWM:/ { print $2 }' "/proc/$estimator/status" 2>/dev/null)
wait "$replay" 2>/dev/null
counts=$(tail -n 1 "$out/counter.log")
/usr/bin/python3 - "$counts" "${rss_kb:-}" "$samples" "$start" "$end" >"$json" <<'PY'
import json, sys
counts = json.loads(sys.argv[1]) if sys.argv[1].startswith("{") else {}
rss = float(sys.argv[2]) / 1024.0 if sys.argv[2] else None
expected = int(sys.argv[3])
received = counts.get("received", 0)
print(json.dumps({
    "node_samples_per_s": counts.get("samples_per_s") if received > 1 else None,
    "node_peak_rss_mb": rss,
    "node_samples_expected": expected,
    "node_samples_received": received,
    "node_samples_lost": expected - received,
    "node_replay_wall_s": float(sys.argv[5]) - float(sys.argv[4]),
    "node_max_lag_ms": counts.get("max_lag_ms") if received > 0 else None,
    # Its parts: the input's own delay (player, scheduling) and the node's own.
    "node_input_max_lag_ms": counts.get("input_max_lag_ms") if received > 0 else None,
    "node_own_max_lag_ms": counts.get("own_max_lag_ms") if received > 0 else None,
}))
PY
pc_ekf_log "node: $(cat "$json")"
