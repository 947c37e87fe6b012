#!/usr/bin/env bash
# Performance benchmarks: builds the package in Release, runs the
# Google Benchmark binaries (test/benchmarks/bench_*.cpp) and the end-to-end
# node measurement, prints one table and writes DIR/bench.json (raw outputs
# in DIR/raw/, node logs in DIR/node/).
#   --out DIR     results directory (default results/, git-ignored)
#   --quick       fewer repetitions (a smoke test; the figures are noisier)
# Timings are CPU time of the measuring thread, best of several passes, so
# other processes on the machine inflate them as little as possible.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib/common.sh"
pc_ekf_require_sources bench.sh

out="$PC_EKF_ROOT/results"
quick=0
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out=${2:?--out needs a directory}; shift ;;
    --quick) quick=1 ;;
    -h|--help) sed -n '2,9p' "$0"; exit 0 ;;
    *) echo "bench.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
  shift
done
mkdir -p "$out" && out=$(cd "$out" && pwd)
rm -rf "$out/raw" "$out/node" && mkdir -p "$out/raw" "$out/node"
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

run_bench() {  # run_bench NAME [benchmark flags...]
  local name=$1
  shift
  pc_ekf_log "running $name"
  "$bin/$name" --benchmark_out="$out/raw/$name.json" --benchmark_out_format=json \
    --benchmark_format=console "$@" >"$out/raw/$name.txt" 2>&1 ||
    pc_ekf_log "$name failed (see ${out#"$PC_EKF_ROOT"/}/raw/$name.txt)"
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
pc_ekf_log "running the node end to end"
bash "$here/lib/bench_node.sh" "$bin" "$out/node" || pc_ekf_log "node benchmark failed"
pc_ekf_log "running the n = 11 node at 1 kHz in real time"
bash "$here/lib/bench_node.sh" "$bin" "$out/node_n11" n11 || pc_ekf_log "n = 11 node benchmark failed"
pc_ekf_log "running the road-free node (vehicle_imu.yaml) at 1 kHz"
bash "$here/lib/bench_node.sh" "$bin" "$out/node_road_free" road_free ||
  pc_ekf_log "road-free node benchmark failed"
# issue 31: the shipped live config at 1 kHz, as a user runs it.
pc_ekf_log "running the live node (vehicle_live.yaml as shipped) at 1 kHz"
bash "$here/lib/bench_node.sh" "$bin" "$out/node_live" live || pc_ekf_log "live node benchmark failed"
pc_ekf_log "running estimate_offline end to end"
rm -rf "$out/end_to_end"
bash "$here/lib/bench_end_to_end.sh" "$PC_EKF_WS/devel/lib/pc_ekf" "$out/end_to_end" ||
  pc_ekf_log "end-to-end benchmark failed"

/usr/bin/python3 "$here/lib/bench_report.py" "$out" "$(($(date +%s) - started))"
