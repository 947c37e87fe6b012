#!/usr/bin/env bash
# Robustness table: every method on data its model did not generate (vehicle
# values 5-10 % off, sensor bias, noise floor, jitter and drops, a load
# change), and again with the mismatched values declared uncertain. Writes
# DIR/robustness.md and .json (coverage of the truth, fraction flagged,
# silent failures per scenario and method) and prints the table.
#   robustness.sh [--seeds N] [--out DIR] [--rows LIST]
# Defaults: 20 seeds, results/robustness, all rows (lib/robustness_rows.py).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"

seeds=20
out="$PC_EKF_RESULTS/robustness"
rows=""
while [ $# -gt 0 ]; do
  case "$1" in
    --seeds) seeds=${2:?--seeds needs a number}; shift 2 ;;
    --out) out=${2:?--out needs a folder}; shift 2 ;;
    --rows) rows=${2:?--rows needs a list}; shift 2 ;;
    -h|--help) sed -n '2,8p' "$0"; exit 0 ;;
    *) echo "robustness.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
[[ "$seeds" =~ ^[1-9][0-9]*$ ]] || { echo "robustness.sh: --seeds needs a positive integer" >&2; exit 2; }

pc_ekf_tools_bin || exit 1
mkdir -p "$out/runs" "$out/logs"
start=$SECONDS

mapfile -t jobs < <(/usr/bin/python3 "$PC_EKF_ROOT/launch_free_scripts/lib/robustness_rows.py" \
  "$out" ${rows//,/ })
[ ${#jobs[@]} -gt 0 ] || { echo "robustness.sh: no such rows: $rows" >&2; exit 2; }

run_row() {
  local name=$1 config=$2 samples=$3 methods=$4
  "$PC_EKF_BIN/reproduce_runs" --config "$config" --samples "$samples" --seeds "1-$seeds" \
    --dataset "$name" --methods "$methods" --enkf-members 200,200 --threads 1 \
    >"$out/runs/$name.jsonl" 2>"$out/logs/$name.log"
}

# Two rows at a time (2 cores); each row's runs are single-threaded.
names=() pids=()
for job in "${jobs[@]}"; do
  set -- $job
  names+=("$1")
  run_row "$@" &
  pids+=("$!")
  if [ ${#pids[@]} -ge 2 ]; then
    wait "${pids[0]}" || { pc_ekf_log "a row failed (logs: $out/logs)"; exit 1; }
    pids=("${pids[@]:1}")
  fi
done
for pid in "${pids[@]}"; do wait "$pid" || { pc_ekf_log "a row failed (logs: $out/logs)"; exit 1; }; done
pc_ekf_log "runs took $((SECONDS - start)) s"
/usr/bin/python3 "$PC_EKF_ROOT/launch_free_scripts/lib/robustness_report.py" "$out" "${names[@]}"
