#!/usr/bin/env bash
# THE test command: installs what is missing, builds, runs every gtest and
# rostest, and ends with "N passed, N failed" (N = test cases).
#   --colcon     also check that `colcon build` succeeds (separate workspace)
set -uo pipefail
source "$(dirname "$0")/lib/common.sh"

check_colcon=0
for arg in "$@"; do
  case "$arg" in
    --colcon) check_colcon=1 ;;
    -h|--help) sed -n '2,5p' "$0"; exit 0 ;;
    *) echo "test.sh: unknown option '$arg'" >&2; exit 2 ;;
  esac
done

pc_ekf_ensure_packages || { echo "0 passed, 1 failed"; exit 1; }
mkdir -p "$PC_EKF_ROOT/.build"

results="$PC_EKF_WS/build/test_results/pc_ekf"
rm -rf "$results"
if ! pc_ekf_catkin_make >"$PC_EKF_ROOT/.build/build.log" 2>&1; then
  tail -40 "$PC_EKF_ROOT/.build/build.log" >&2
  pc_ekf_log "build failed (full log: .build/build.log)"
  echo "0 passed, 1 failed"
  exit 1
fi
pc_ekf_log "build ok; running tests"

extra_failures=0
if ! (cd "$PC_EKF_WS" && catkin_make run_tests -j"$(nproc)") >"$PC_EKF_ROOT/.build/tests.log" 2>&1; then
  pc_ekf_log "run_tests returned non-zero (log: .build/tests.log)"
fi

if [ "$check_colcon" -eq 1 ]; then
  colcon_ws="$PC_EKF_ROOT/.build/colcon_ws"
  mkdir -p "$colcon_ws/src" && ln -sfn "$PC_EKF_ROOT" "$colcon_ws/src/pc_ekf"
  if (cd "$colcon_ws" && colcon build --cmake-args -DCMAKE_BUILD_TYPE=Release) \
       >"$PC_EKF_ROOT/.build/colcon.log" 2>&1; then
    pc_ekf_log "colcon build ok"
  else
    pc_ekf_log "colcon build FAILED (log: .build/colcon.log)"
    extra_failures=1
  fi
fi

/usr/bin/python3 "$PC_EKF_ROOT/launch_free_scripts/lib/count_results.py" "$results" "$extra_failures"
