#!/usr/bin/env bash
# Soak test: 10^6 samples at 1 kHz through estimator_node's
# per-sample path (road buffer, pending samples, one-step + coherence
# filters, batch buffer, PDFs; test/soak/soak_estimator.cpp), at full speed.
# Fails when a sample is dropped or RSS grows by more than 20 MB after the
# warm-up. Bounds: node.max_road_samples and node.max_batch_samples as given.
# A road-free config (--config config/vehicle_imu.yaml --dt 0.005) runs the
# node's road-free path: its inputs are forgotten behind filters and batch.
#   soak.sh [--samples N (1000000)] [--warmup N (200000)] [--max-road N (100000)]
#           [--max-batch N (100000)] [--pdf-every K (1000)]
#           [--config FILE (config/speed_bump.yaml)] [--dt S (0.001)] [--batch 1: the batch at the end]
set -uo pipefail
case "${1:-}" in -h|--help) sed -n '2,11p' "$0"; exit 0 ;; esac
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib/common.sh"
pc_ekf_ensure_packages || exit 1
if [ "$PC_EKF_INSTALLED" = 0 ]; then
  pc_ekf_log "building soak_estimator (log: .build/soak_build.log)"
  pc_ekf_catkin_make soak_estimator >"$PC_EKF_ROOT/.build/soak_build.log" 2>&1 ||
    { tail -30 "$PC_EKF_ROOT/.build/soak_build.log" >&2; exit 1; }
fi
exec "$PC_EKF_EXE_DIR/soak_estimator" --config "$PC_EKF_ROOT/config/speed_bump.yaml" "$@"
