#!/usr/bin/env bash
# test.sh's fleet cases (scripts/estimate_fleet on Dask), loopback only:
# 20 bags from synthesize_bag (N = 10; three vehicles with their own truth
# and seeds, two of them through --vehicle-files; one bag truncated), each
# also estimated serially by estimate_offline --bag as the reference.
#  1. scheduler_two_workers_one_killed: a dask-scheduler and two dask-workers
#     on 127.0.0.1 (free ports); worker 1 is killed (SIGKILL, by PID) while an
#     estimate_offline of its own is running. Expected: 19 result rows + 1
#     error row (the corrupt bag), one per bag in path order, every number
#     equal to the serial run bit for bit, the bag in flight on the killed
#     worker redone by the other.
#  2. local_cluster_resume_after_killed_fleet: the default LocalCluster run
#     is killed (SIGKILL to estimate_fleet's PID) after a few rows; a torn
#     line is appended to its journal; the rerun (--workers 1) skips exactly
#     the rows kept, runs the rest, and the table equals the serial run's.
#  3. redo_errors: 4 bags (2 good, 1 unhealthy, 1 on the wrong topics) with
#     --timeout 0.01: 4 timeout rows; a rerun skips them all; --redo-errors
#     runs them again: 2 result rows, an "unhealthy:" row with its estimate,
#     a "bad input:" row naming the topics. Also --redo-errors on case 1's
#     folder reruns only the corrupt bag.
# Stops exactly the processes it started (by PID/process group).
#   fleet_test.sh RESULTS_DIR     -> RESULTS_DIR/fleet.xml
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
source "$here/roscore.sh"

results=${1:?usage: fleet_test.sh RESULTS_DIR}
work=$PC_EKF_ROOT/.build/fleet
rm -rf "$work" && mkdir -p "$work" "$results"
bin=$PC_EKF_WS/devel/lib/pc_ekf
check=("/usr/bin/python3" "$here/fleet_test_check.py")
config=$PC_EKF_ROOT/config/speed_bump.yaml
trap pc_ekf_stop_owned EXIT
trap 'exit 130' INT TERM
cases=$work/cases.tsv
: >"$cases"

# Bounded waits: wait_for SECONDS COMMAND... (polls every 20 ms).
wait_for() {
  local deadline=$((SECONDS + $1))
  shift
  until "$@"; do
    [ $SECONDS -ge $deadline ] && return 1
    sleep 0.02
  done
}
rows_in() { [ -f "$1/results.jsonl" ] && wc -l <"$1/results.jsonl" || echo 0; }
has_rows() { [ "$(rows_in "$1")" -ge "$2" ]; }
fleet() { timeout 120 "$bin/estimate_fleet" --config "$config" "$@"; }

# ---- data: 19 bags of three vehicles + 1 truncated; the serial reference.
setup() {
  local log=$work/setup.log vehicle seed i name cfg
  for exe in estimate_offline synthesize_bag estimate_fleet; do
    [ -x "$bin/$exe" ] || { echo "$exe not built"; return 1; }
  done
  mkdir -p "$work/bags" "$work/vehicles" "$work/serial" "$work/configs"
  # Vehicle files, and the same vehicles written into full configs
  # independently (sed on the config): the reference for the merge.
  printf 'vehicle:\n  damping_left: 730.0\n  damping_right: 730.0\n' >"$work/vehicles/van_a.yaml"
  printf 'vehicle:\n  spring_linear_left: 19800.0\n' >"$work/vehicles/van_b.yaml"
  printf '"van_a_*.bag": vehicles/van_a.yaml\n"van_b_*": vehicles/van_b.yaml\n' >"$work/map.yaml"
  sed -e 's/^  damping_left: 710.70 /  damping_left: 730.0 /' \
      -e 's/^  damping_right: 710.70 /  damping_right: 730.0 /' \
      -e 's/^  xi: \[0.2326, -0.3875\]/  xi: [-0.3, 0.2]/' "$config" >"$work/configs/van_a.yaml"
  sed -e 's/^  spring_linear_left: 19357.2 /  spring_linear_left: 19800.0 /' \
      -e 's/^  xi: \[0.2326, -0.3875\]/  xi: [0.6, -0.1]/' "$config" >"$work/configs/van_b.yaml"
  cp "$config" "$work/configs/other.yaml"
  [ "$(diff "$config" "$work/configs/van_a.yaml" | grep -c '^>')" = 3 ] &&
    [ "$(diff "$config" "$work/configs/van_b.yaml" | grep -c '^>')" = 2 ] ||
    { echo "could not write the reference vehicle configs (speed_bump.yaml changed?)"; return 1; }
  # van_a 7 bags, van_b 7, other 5; one day apart; seeds per vehicle.
  for vehicle in van_a:7:100 van_b:7:200 other:5:300; do
    IFS=: read -r name count seed <<<"$vehicle"
    for ((i = 1; i <= count; i++)); do
      "$bin/synthesize_bag" --config "$work/configs/$name.yaml" --seed $((seed + i)) \
        --start-time $((1700000000 + 86400 * i)) --output "$work/bags/${name}_$(printf %02d $i).bag" \
        >>"$log" 2>&1 || { echo "synthesize_bag failed (log: $log)"; return 1; }
    done
  done
  head -c 20000 "$work/bags/other_01.bag" >"$work/bags/other_00_corrupt.bag"
  ls "$work"/bags/*.bag >"$work/bags.txt"
  for bag in $(cat "$work/bags.txt"); do
    name=$(basename "$bag" .bag)
    cfg=$work/configs/${name%%_[0-9]*}.yaml
    "$bin/estimate_offline" --config "$cfg" --bag "$bag" >"$work/serial/$name.json" 2>>"$log"
    echo $? >"$work/serial/$name.rc"
  done
  # The four bags of case 3: two good, one the model does not explain
  # (truth spring 30 % off), one of the right messages on the wrong topics.
  mkdir -p "$work/bags_redo"
  cp "$work/bags/other_01.bag" "$work/bags/other_02.bag" "$work/bags_redo/"
  sed 's/^  vehicle: {}  /  vehicle: {spring_linear_left: 25000.0}/' "$config" >"$work/configs/unhealthy.yaml"
  "$bin/synthesize_bag" --config "$work/configs/unhealthy.yaml" --output "$work/bags_redo/unhealthy.bag" \
    >>"$log" 2>&1 || { echo "synthesize_bag (unhealthy) failed"; return 1; }
  "${check[@]}" rename_topics "$work/bags/other_03.bag" "$work/bags_redo/wrong_topics.bag" 2>>"$log" ||
    { echo "could not write the wrong-topic bag"; return 1; }
  for name in unhealthy wrong_topics; do
    "$bin/estimate_offline" --config "$config" --bag "$work/bags_redo/$name.bag" \
      >"$work/serial/$name.json" 2>>"$log"
    echo $? >"$work/serial/$name.rc"
  done
  ls "$work"/bags_redo/*.bag >"$work/bags_redo.txt"
  echo "20 bags ($(grep -lx 0 "$work"/serial/*.rc | wc -l) estimated serially incl. case 3's)"
}

# ---- case 1
case_scheduler() {
  local port w1port w2port w1 w2 fleet_pid child="" bag="" out=$work/out_scheduler
  port=$(pc_ekf_free_port)
  pc_ekf_start_owned dask-scheduler "$work/scheduler.log" \
    dask-scheduler --host 127.0.0.1 --port "$port" --no-dashboard --dashboard-address 127.0.0.1:0
  local scheduler_pid=$PC_EKF_LAST_PID
  scheduler=tcp://127.0.0.1:$port
  w1port=$(pc_ekf_free_port)
  w2port=$(pc_ekf_free_port)
  pc_ekf_start_owned dask-worker-1 "$work/worker1.log" dask-worker "$scheduler" --no-nanny \
    --nthreads 1 --host 127.0.0.1 --worker-port "$w1port" --no-dashboard \
    --dashboard-address 127.0.0.1:0 --local-directory "$work/w1"
  w1=$PC_EKF_LAST_PID
  pc_ekf_start_owned dask-worker-2 "$work/worker2.log" dask-worker "$scheduler" --no-nanny \
    --nthreads 1 --host 127.0.0.1 --worker-port "$w2port" --no-dashboard \
    --dashboard-address 127.0.0.1:0 --local-directory "$work/w2"
  w2=$PC_EKF_LAST_PID
  "${check[@]}" workers "$scheduler" 2 60 >"$work/workers.txt" ||
    { echo "workers: $(tail -1 "$work/workers.txt")"; return 1; }
  echo "scheduler $scheduler (pid $scheduler_pid), workers" \
    "tcp://127.0.0.1:$w1port (pid $w1), tcp://127.0.0.1:$w2port (pid $w2)"

  pc_ekf_start_owned estimate_fleet "$work/fleet_scheduler.log" "$bin/estimate_fleet" \
    --config "$config" --bags "$work/bags" --vehicle-files "$work/map.yaml" \
    --scheduler "$scheduler" --out "$out"
  fleet_pid=$PC_EKF_LAST_PID
  # Worker 1 is killed once it has made a row and runs an estimate_offline:
  # frozen (SIGSTOP) first, so it cannot report the bag in flight, then killed.
  wait_for 60 grep -q "tcp://127.0.0.1:$w1port" "$out/results.jsonl" 2>/dev/null ||
    { echo "worker 1 made no row within 60 s"; return 1; }
  for _ in $(seq 3000); do
    child=$(pgrep -P "$w1" | head -1)
    if [ -n "$child" ]; then
      kill -STOP "$w1"
      if kill -0 "$child" 2>/dev/null; then
        bag=$(tr '\0' '\n' <"/proc/$child/cmdline" | grep -A1 -x -- --bag | tail -1)
        [ -n "$bag" ] && break
      fi
      kill -CONT "$w1"
      bag=""
    fi
    kill -0 "$fleet_pid" 2>/dev/null || break
    sleep 0.01
  done
  [ -n "$bag" ] || { echo "found no estimate_offline running on worker 1 before the run ended"; return 1; }
  kill -KILL "$w1"
  echo "killed worker 1 (pid $w1, SIGKILL) after $(rows_in "$out") rows, in flight: $(basename "$bag")"
  wait_for 90 eval '! kill -0 "$fleet_pid" 2>/dev/null' || { echo "estimate_fleet did not end"; return 1; }
  wait "$fleet_pid"
  local status=$?
  [ "$status" = 0 ] || { echo "estimate_fleet exited $status: $(tail -2 "$work/fleet_scheduler.log")"; return 1; }
  pc_ekf_stop_group "$w1" dask-worker-1  # and its orphaned estimate_offline
  "${check[@]}" worker "$out" "$bag" "tcp://127.0.0.1:$w1port" || return 1
  "${check[@]}" table "$out" "$work/serial" "$work/bags.txt" --ok 19 --errors 1 \
    --error "other_00_corrupt.bag:corrupt" --vehicle "van_a_*:$work/vehicles/van_a.yaml" \
    --vehicle "van_b_*:$work/vehicles/van_b.yaml" --vehicle "other_*:" || return 1
  ls "$out"/vehicle_*.png | wc -l | grep -qx 3 || { echo "expected 3 per-vehicle figures"; return 1; }
}

# ---- case 2
case_resume() {
  local out=$work/out_local fleet_pid kept status
  pc_ekf_start_owned estimate_fleet_local "$work/fleet_local_killed.log" "$bin/estimate_fleet" \
    --config "$config" --bags "$work/bags" --vehicle-files "$work/map.yaml" --out "$out"
  fleet_pid=$PC_EKF_LAST_PID
  wait_for 90 has_rows "$out" 3 || { echo "the LocalCluster run made no 3 rows within 90 s"; return 1; }
  kill -KILL "$fleet_pid"
  wait "$fleet_pid" 2>/dev/null
  pc_ekf_stop_group "$fleet_pid" estimate_fleet_local  # its LocalCluster's processes
  kept=$(rows_in "$out")
  echo "killed estimate_fleet (pid $fleet_pid, SIGKILL, default LocalCluster) with $kept rows kept"
  [ "$kept" -lt 20 ] || { echo "the run had finished before the kill"; return 1; }
  printf '{"path": "/torn' >>"$out/results.jsonl"
  fleet --bags "$work/bags" --vehicle-files "$work/map.yaml" --workers 1 --out "$out" \
    >"$work/fleet_local_rerun.log" 2>&1
  status=$?
  [ "$status" = 0 ] || { echo "rerun exited $status: $(tail -2 "$work/fleet_local_rerun.log")"; return 1; }
  grep -q "torn last line" "$work/fleet_local_rerun.log" || { echo "the torn line was not reported"; return 1; }
  ! grep "unreadable row" "$work/fleet_local_rerun.log" | grep -qv 'skipped: {"path": "/torn$' ||
    { echo "a row appended after the torn line was unreadable"; return 1; }
  "${check[@]}" run "$out" --skipped "$kept" --ran $((20 - kept)) || return 1
  "${check[@]}" table "$out" "$work/serial" "$work/bags.txt" --ok 19 --errors 1 \
    --error "other_00_corrupt.bag:corrupt" || return 1
}

# ---- case 3
case_redo() {
  local out=$work/out_redo
  fleet --bags "$work/bags_redo" --scheduler "$scheduler" --timeout 0.01 --out "$out" \
    >"$work/fleet_redo_1.log" 2>&1 || { echo "timeout run failed: $(tail -1 "$work/fleet_redo_1.log")"; return 1; }
  [ "$(grep -c '"error": "timeout: ' "$out/results.jsonl")" = 4 ] ||
    { echo "expected 4 timeout rows: $(cut -c1-300 "$out/results.jsonl")"; return 1; }
  fleet --bags "$work/bags_redo" --scheduler "$scheduler" --out "$out" >"$work/fleet_redo_2.log" 2>&1 &&
    "${check[@]}" run "$out" --skipped 4 --ran 0 || return 1
  # This run uses the installed estimate_fleet when test.sh has made the
  # install space (not one older than the build; install keeps whole-second
  # mtimes): it must find the estimate_offline installed beside it.
  local exe=$bin/estimate_fleet installed=$PC_EKF_WS/install/lib/pc_ekf
  [ -x "$installed/estimate_fleet" ] &&
    [ "$(stat -c %Y "$bin/estimate_offline")" -le "$(stat -c %Y "$installed/estimate_offline")" ] &&
    exe=$installed/estimate_fleet
  timeout 120 "$exe" --config "$config" --bags "$work/bags_redo" --scheduler "$scheduler" \
    --redo-errors --out "$out" >"$work/fleet_redo_3.log" 2>&1 &&
    "${check[@]}" run "$out" --skipped 0 --ran 4 || return 1
  grep -q "to run ($(dirname "$exe")/estimate_offline)" "$work/fleet_redo_3.log" ||
    { echo "$exe did not run the estimate_offline beside it: $(head -1 "$work/fleet_redo_3.log")"; return 1; }
  echo "--redo-errors run by $exe"
  "${check[@]}" table "$out" "$work/serial" "$work/bags_redo.txt" --ok 2 --errors 2 \
    --error "unhealthy.bag:unhealthy: windowed NIS" \
    --error "wrong_topics.bag:bad input: estimate_offline: $work/bags_redo/wrong_topics.bag: no pc_ekf/RoadProfile messages on a topic ending in 'road/profile'" || return 1
  [ "$(wc -l <"$out/superseded.jsonl")" = 4 ] || { echo "the 4 timeout rows are not in superseded.jsonl"; return 1; }
  fleet --bags "$work/bags" --vehicle-files "$work/map.yaml" --scheduler "$scheduler" --redo-errors \
    --out "$work/out_scheduler" >"$work/fleet_redo_4.log" 2>&1 &&
    "${check[@]}" run "$work/out_scheduler" --skipped 19 --ran 1 || return 1
  "${check[@]}" table "$work/out_scheduler" "$work/serial" "$work/bags.txt" --ok 19 --errors 1 \
    --error "other_00_corrupt.bag:corrupt"
}

# run_case NAME FUNCTION: one JUnit case; its output is the case's log.
run_case() {
  local name=$1 started status
  started=$(date +%s.%N)
  if [ -n "${setup_failed:-}" ]; then
    echo "setup failed: $setup_failed" >"$work/$name.log"
    status=1
  else
    "$2" >"$work/$name.log" 2>&1
    status=$?
  fi
  printf '%s\t%s\t%s\n' "$name" "$status" \
    "$(awk -v a="$started" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')" >>"$cases"
  pc_ekf_log "fleet $name: $([ "$status" = 0 ] && echo ok || echo FAILED): $(tail -1 "$work/$name.log")"
}

started_all=$SECONDS
pc_ekf_source_workspace
setup >"$work/setup_summary.log" 2>&1 || setup_failed=$(tail -1 "$work/setup_summary.log")
scheduler=""
run_case scheduler_two_workers_one_killed case_scheduler
run_case local_cluster_resume_after_killed_fleet case_resume
[ -z "$scheduler" ] && setup_failed=${setup_failed:-no scheduler (case 1 failed)}
run_case redo_errors case_redo
pc_ekf_stop_owned
pc_ekf_log "fleet: $((SECONDS - started_all)) s (logs: .build/fleet/)"
PYTHONPATH=$PC_EKF_JUNIT_PATH /usr/bin/python3 - "$results/fleet.xml" "$cases" "$work" <<'PY'
import sys
import junit
out, cases, work = sys.argv[1:]
rows = [l.rstrip("\n").split("\t") for l in open(cases) if l.strip()]
written = []
for name, status, elapsed in rows:
    log = junit.read_tail(f"{work}/{name}.log", 4000)
    failure = (log.strip().splitlines() or ["failed"])[-1] if status != "0" else None
    written.append(junit.Case(name, failure=failure, failure_text=log, system_out=log,
                              time=elapsed))
junit.write(out, "fleet", written)
PY
! grep -qv $'\t0\t' "$cases"
