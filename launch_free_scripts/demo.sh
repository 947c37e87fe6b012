#!/usr/bin/env bash
# The demo: installs what is missing, builds, shows the model at the nominal
# and true parameters, then estimates M and d_CG on the paper's speed-bump
# data (SPEC §4 cases A and C) and prints them next to the truth.
# (The ROS form - roscore, synthesize_bag, replay_node -> estimator_node -
# comes with estimator_node; this version needs no ROS master.)
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"

pc_ekf_ensure_packages
pc_ekf_log "building (log: .build/build.log)"
mkdir -p "$PC_EKF_ROOT/.build"
pc_ekf_catkin_make >"$PC_EKF_ROOT/.build/build.log" 2>&1 || {
  tail -30 "$PC_EKF_ROOT/.build/build.log" >&2; exit 1; }
bin="$PC_EKF_WS/devel/lib/pc_ekf"
config="$PC_EKF_ROOT/config/speed_bump.yaml"

echo "== Model: static equilibrium and speed-bump response (no noise) =="
"$bin/simulate_vehicle" --config "$config"

echo
echo "== Estimates from 10 noisy samples (1 % noise, seed 1); truth M = 223.26 kg, d_CG = 0.6882 m =="
printf "%-28s %22s %22s %8s\n" "method" "M [kg]" "d_CG [m]" "healthy"
for run in "one_step square_root" "one_step paper" "whole_set square_root" \
           "es_mda square_root" "enkf square_root" "grid square_root"; do
  set -- $run
  json=$("$bin/estimate_offline" --config "$config" --method "$1" --update "$2" 2>/dev/null)
  /usr/bin/python3 - "$1 ($2)" "$json" <<'PY'
import json, sys
r = json.loads(sys.argv[2])
m, d = r["parameters"]
print(f"{sys.argv[1]:<28} {m['mean']:10.3f} +- {m['stddev']:8.3f} "
      f"{d['mean']:10.5f} +- {d['stddev']:8.5f} {str(r['healthy']):>8}")
PY
done
echo "(grid = exact Bayesian posterior, the yardstick; see README)"
