#!/usr/bin/env bash
# Performance benchmarks: builds the package in Release, runs the
# Google Benchmark binaries (test/benchmarks/bench_*.cpp) and the end-to-end
# node measurement, prints one table and writes DIR/bench.json (raw outputs
# in DIR/raw/, node logs in DIR/node*/, the long drive in DIR/long/).
#   --out DIR     results directory (default results/, git-ignored)
#   --quick       fewer repetitions (a smoke test; the figures are noisier)
#   --runs N      repeated runs behind the deciding figures (default 3)
# Timings are CPU time of the measuring thread, best of several passes, so
# other processes on the machine inflate them as little as possible. The
# deciding figures (end to end, the node's lag, forecast_thread_speedup) are
# the median of N whole runs instead: one run of them swings with the machine.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib/common.sh"
pc_ekf_require_sources bench.sh

out="$PC_EKF_ROOT/results"
quick=0
runs=3
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out=${2:?--out needs a directory}; shift ;;
    --quick) quick=1 ;;
    --runs) runs=${2:?--runs needs a number}; shift ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) echo "bench.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
  shift
done
[[ "$runs" =~ ^[1-9][0-9]*$ ]] || { echo "bench.sh: --runs needs a positive number" >&2; exit 2; }
export PC_EKF_BENCH_RUNS=$runs
mkdir -p "$out" && out=$(cd "$out" && pwd)
rm -rf "$out/raw" "$out/node" "$out/node_n11" "$out/node_road_free" "$out/node_full_car_imu" "$out/node_live" "$out/long"
mkdir -p "$out/raw" "$out/node"
started=$(date +%s)

pc_ekf_ensure_packages || exit 1
mkdir -p "$PC_EKF_ROOT/.build"
benches=(bench_one_step bench_integrator bench_scaling bench_propagation bench_enkf bench_posterior
         bench_checkpoint bench_odeint bench_pdf)
node_targets=(estimator_node replay_node synthesize_bag bench_node_throughput estimate_offline)
pc_ekf_log "building in Release (log: .build/bench_build.log)"
if ! PC_EKF_BUILD_TYPE=Release pc_ekf_catkin_make "${benches[@]}" \
     >"$PC_EKF_ROOT/.build/bench_build.log" 2>&1; then
  tail -30 "$PC_EKF_ROOT/.build/bench_build.log" >&2
  pc_ekf_log "build failed"
  exit 1
fi
# The node's executables are being written: build them separately, and
# measure the node only when they build.
PC_EKF_BUILD_TYPE=Release pc_ekf_catkin_make "${node_targets[@]}" \
  >"$PC_EKF_ROOT/.build/bench_build_node.log" 2>&1 ||
  pc_ekf_log "node executables did not build (.build/bench_build_node.log): node figures null"
grep -q "CMAKE_BUILD_TYPE:STRING=Release" "$PC_EKF_WS/build/CMakeCache.txt" ||
  { pc_ekf_log "workspace is not a Release build"; exit 1; }

bin="$PC_EKF_WS/devel/lib/pc_ekf"
[ -x "$bin/bench_one_step" ] || bin="$PC_EKF_WS/build/pc_ekf"
for b in "${benches[@]}"; do
  [ -x "$bin/$b" ] || { pc_ekf_log "$b not built (is libbenchmark-dev installed?)"; exit 1; }
done

run_bench() {  # run_bench NAME [benchmark flags...]; RAW=name sets the output's name
  local name=$1 raw=${RAW:-$1}
  shift
  pc_ekf_log "running $raw"
  "$bin/$name" --benchmark_out="$out/raw/$raw.json" --benchmark_out_format=json \
    --benchmark_format=console "$@" >"$out/raw/$raw.txt" 2>&1 ||
    pc_ekf_log "$name failed (see ${out#"$PC_EKF_ROOT"/}/raw/$raw.txt)"
}
if [ "$quick" = 1 ]; then
  run_bench bench_one_step --benchmark_filter='OneStep|Forecast'
  run_bench bench_integrator --benchmark_filter='StepAccuracy/(1000|3000)/'
  run_bench bench_scaling --benchmark_filter='UpdateScaling/(2|4)/(2|4|8)|WholeSet/(100|10000)$|ManyParameters/(4|8)/2/1|ForecastThreads'
  run_bench bench_propagation --benchmark_filter='PcVersus|DesignDefault'
  run_bench bench_checkpoint --benchmark_filter='WhileCheckpointWritten|WithoutCheckpoint|Snapshot'
  run_bench bench_odeint
  run_bench bench_pdf --benchmark_filter='PdfN11/'
else
  run_bench bench_one_step
  run_bench bench_integrator
  run_bench bench_scaling
  run_bench bench_propagation
  run_bench bench_enkf
  run_bench bench_posterior
  run_bench bench_checkpoint
  run_bench bench_odeint
  run_bench bench_pdf
fi
# forecast_thread_speedup: the median of N repetitions (one swung 0.92-1.61).
RAW=bench_forecast_threads run_bench bench_scaling --benchmark_filter='BM_ForecastThreads/0' \
  --benchmark_repetitions="$runs"

# node_runs DIR MODE LABEL: lib/bench_node.sh N times (DIR/run_i), DIR/node.json their median.
node_runs() {
  local dir=$1 mode=$2 label=$3 i
  local each=()
  for i in $(seq "$runs"); do
    pc_ekf_log "running $label (run $i of $runs)"
    bash "$here/lib/bench_node.sh" "$bin" "$dir/run_$i" "$mode" || pc_ekf_log "$label failed (run $i)"
    each+=("$dir/run_$i/node.json")
  done
  /usr/bin/python3 "$here/lib/bench_median.py" "$dir/node.json" "${each[@]}"
}
node_runs "$out/node" paper "the node end to end"
node_runs "$out/node_n11" n11 "the n = 11 node at 1 kHz in real time"
node_runs "$out/node_road_free" road_free "the road-free node (vehicle_imu.yaml) at 1 kHz"
node_runs "$out/node_full_car_imu" full_car_imu "the road-free full car node (full_car_imu.yaml) at 1 kHz"
# issue 31: the shipped live config at 1 kHz, as a user runs it.
node_runs "$out/node_live" live "the live node (vehicle_live.yaml as shipped) at 1 kHz"
# issue 44: long drives. One run (4 minutes at -r 5; PC_EKF_BENCH_LONG_RATE).
pc_ekf_log "running the node over long_drive.yaml's 20 minutes"
bash "$here/lib/bench_long.sh" "$bin" "$out/long" || pc_ekf_log "long-drive benchmark failed"
pc_ekf_log "running estimate_offline end to end"
rm -rf "$out/end_to_end"
bash "$here/lib/bench_end_to_end.sh" "$PC_EKF_WS/devel/lib/pc_ekf" "$out/end_to_end" ||
  pc_ekf_log "end-to-end benchmark failed"

/usr/bin/python3 "$here/lib/bench_report.py" "$out" "$(($(date +%s) - started))"
