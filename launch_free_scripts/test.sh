#!/usr/bin/env bash
# THE test command: installs what is missing, builds, runs every gtest and
# rostest, checks the install space (an outside package builds against it),
# catkin_lint (no errors), estimate_fleet (lib/fleet_test.sh; its modules with
# pytest, test/fleet) and that the install list covers every package used
# (lib/check_install_list.py), and ends with "N passed, N failed" (N = test cases).
#   --colcon     also check that `colcon build` succeeds (separate workspace)
#   --sanitize   instead: build .build/catkin_ws_sanitize with ASan + UBSan
#                (RelWithDebInfo) and run every gtest and rostest there; any
#                sanitizer report fails the test case sanitizer.reports
#   --no-fuzz    skip the fuzz step (by default, after the tests: each
#                test/fuzz target replays its corpus and fuzzes
#                PC_EKF_FUZZ_SECONDS, default 30 s; one test case per target)
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib/common.sh"
pc_ekf_require_sources test.sh
source "$here/lib/fuzz.sh"
source "$here/lib/sanitize.sh"
source "$here/lib/package_checks.sh"

check_colcon=0
sanitize=0
fuzz=1
for arg in "$@"; do
  case "$arg" in
    --colcon) check_colcon=1 ;;
    --sanitize) sanitize=1; fuzz=0 ;;
    --no-fuzz) fuzz=0 ;;
    -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
    *) echo "test.sh: unknown option '$arg'" >&2; exit 2 ;;
  esac
done

pc_ekf_ensure_packages || { echo "0 passed, 1 failed"; exit 1; }
mkdir -p "$PC_EKF_ROOT/.build"

suffix=""
build_args=()
if [ "$sanitize" -eq 1 ]; then
  PC_EKF_WS=$PC_EKF_ROOT/.build/catkin_ws_sanitize
  export PC_EKF_BUILD_TYPE=RelWithDebInfo
  mapfile -t build_args < <(pc_ekf_sanitize_cmake_args)
  suffix=_sanitize
fi

results="$PC_EKF_WS/build/test_results/pc_ekf"
rm -rf "$results"
if ! pc_ekf_catkin_make "${build_args[@]}" >"$PC_EKF_ROOT/.build/build$suffix.log" 2>&1; then
  tail -40 "$PC_EKF_ROOT/.build/build$suffix.log" >&2
  pc_ekf_log "build failed (full log: .build/build$suffix.log)"
  echo "0 passed, 1 failed"
  exit 1
fi
pc_ekf_log "build ok; running tests"

sanitizer_logs=$PC_EKF_ROOT/.build/sanitizer_reports
[ "$sanitize" -eq 1 ] && pc_ekf_sanitize_env "$sanitizer_logs"
extra_failures=0
tests_start=$SECONDS
if ! (cd "$PC_EKF_WS" && catkin_make run_tests -j"$(nproc)") >"$PC_EKF_ROOT/.build/tests$suffix.log" 2>&1; then
  pc_ekf_log "run_tests returned non-zero (log: .build/tests$suffix.log)"
fi
pc_ekf_log "tests took $((SECONDS - tests_start)) s"
if [ "$sanitize" -eq 1 ]; then
  unset ASAN_OPTIONS UBSAN_OPTIONS LSAN_OPTIONS
  pc_ekf_sanitize_results "$results" "$sanitizer_logs" "$PC_EKF_ROOT/.build/tests$suffix.log"
fi

# The install space: headers, libraries and tools usable by another package.
[ "$sanitize" -eq 0 ] && pc_ekf_install_check "$results"
[ "$sanitize" -eq 0 ] && pc_ekf_lint_check "$results"
# The node survives a restart of the ROS master (a script: rostest owns its master).
[ "$sanitize" -eq 0 ] && { bash "$here/lib/master_restart_test.sh" "$results" ||
                             pc_ekf_log "master restart test FAILED (log: .build/master_restart/)"; }

# estimate_fleet on Dask: a scheduler and two workers on the loopback, one killed mid-run;
# the LocalCluster path, resume after a killed run, --redo-errors (lib/fleet_test.sh).
[ "$sanitize" -eq 0 ] && { bash "$here/lib/fleet_test.sh" "$results" ||
                             pc_ekf_log "fleet test FAILED (log: .build/fleet/)"; }

# estimate_fleet's modules without Dask (scripts/pc_ekf_fleet; test/fleet, pytest).
if [ "$sanitize" -eq 0 ] &&
   ! (cd "$PC_EKF_ROOT" && /usr/bin/python3 -m pytest -q -p no:cacheprovider \
        --junitxml="$results/fleet_unit.xml" test/fleet) >"$PC_EKF_ROOT/.build/pytest.log" 2>&1; then
  pc_ekf_log "fleet pytest FAILED (log: .build/pytest.log)"
  [ -f "$results/fleet_unit.xml" ] ||
    pc_ekf_junit "$results/fleet_unit.xml" fleet_unit pytest --failure "pytest wrote no results" \
      --failure-text "$PC_EKF_ROOT/.build/pytest.log" --tail 4000
fi

# The install list covers every package used (a fresh machine has only it).
mkdir -p "$results"
(pc_ekf_source_workspace && /usr/bin/python3 "$here/lib/check_install_list.py" \
   "$results/install_list.xml" "${PC_EKF_APT_PACKAGES[@]}") || pc_ekf_log "install list check FAILED"

if [ "$fuzz" -eq 1 ]; then
  fuzz_start=$SECONDS
  pc_ekf_fuzz_ci "$results" "${PC_EKF_FUZZ_SECONDS:-30}"
  pc_ekf_log "fuzz step took $((SECONDS - fuzz_start)) s (results: fuzz.xml; logs: .build/fuzz/logs)"
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
