#!/usr/bin/env bash
# Reproduces the paper's experiments (docs/method.md §6, cases A-I) over many seeds with
# every method, against the exact posterior, and writes DIR/summary.md,
# DIR/summary.json and DIR/figures/*.png.
#   reproduce.sh [--seeds N] [--out DIR] [--cases LIST] [--no-error-vs-n]
# Defaults: 30 seeds, results/, all cases. LIST: comma-separated of
# bump10,bump100,sine10,sine100,linear10,linear100 (the data sets behind the cases).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"

seeds=30
out="$PC_EKF_RESULTS"
datasets="bump10,bump100,sine10,sine100,linear10,linear100"
error_vs_n=1
while [ $# -gt 0 ]; do
  case "$1" in
    --seeds) seeds=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --cases) datasets=$2; shift 2 ;;
    --no-error-vs-n) error_vs_n=0; shift ;;
    -h|--help) sed -n '2,8p' "$0"; exit 0 ;;
    *) echo "reproduce.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
[[ "$seeds" =~ ^[1-9][0-9]*$ ]] || { echo "reproduce.sh: --seeds needs a positive integer" >&2; exit 2; }

pc_ekf_tools_bin || exit 1
mkdir -p "$out/runs" "$out/per_sample" "$out/figures"
rm -f "$out"/runs/*.jsonl
start=$(date +%s)

# One job per data set: "name config samples seeds methods".
jobs=()
for d in ${datasets//,/ }; do
  case "$d" in
    bump*) cfg=speed_bump.yaml; n=${d#bump} ;;
    sine*) cfg=sine_1hz.yaml; n=${d#sine} ;;
    linear*) cfg=sine_1hz_linear.yaml; n=${d#linear} ;;
    *) echo "reproduce.sh: unknown data set '$d'" >&2; exit 2 ;;
  esac
  jobs+=("$d $cfg $n $seeds all")
done
# Absolute error against N (paper Fig. 8): speed bump, every method but the grid.
if [ "$error_vs_n" -eq 1 ]; then
  few=$(( seeds < 10 ? seeds : 10 ))
  for n in 5 20 30 50 200; do
    jobs+=("bump$n speed_bump.yaml $n $few one_step_paper,one_step_square_root,whole_set_paper,es_mda,enkf_small,enkf_large")
  done
fi

run_job() {
  set -- $1
  local methods=()
  [ "$5" != all ] && methods=(--methods "$5")
  "$PC_EKF_BIN/reproduce_runs" --config "$PC_EKF_ROOT/config/$2" --samples "$3" \
    --seeds "1-$4" --dataset "$1" --per-sample-dir "$out/per_sample" "${methods[@]}" \
    >"$out/runs/$1.jsonl" 2>"$out/runs/$1.log"
}

total=0
for j in "${jobs[@]}"; do
  set -- $j
  m=8; [ "$5" != all ] && m=$(echo "$5" | tr ',' '\n' | wc -l)
  total=$(( total + $4 * m ))
done

progress() {
  local done=0 f
  for f in "$out"/runs/*.jsonl; do [ -f "$f" ] && done=$(( done + $(wc -l <"$f") )); done
  local filled=$(( done * 40 / total ))
  printf '\r[%-40s] %d/%d runs, %ds' "$(head -c "$filled" /dev/zero | tr '\0' '#')" \
    "$done" "$total" "$(( $(date +%s) - start ))" >&2
}
( while sleep 2; do progress; done ) &
progress_pid=$!
trap 'kill "$progress_pid" 2>/dev/null || true' EXIT

failed=0
running=0
for j in "${jobs[@]}"; do
  if [ "$running" -ge "$(nproc)" ]; then
    wait -n || failed=1
    running=$(( running - 1 ))
  fi
  run_job "$j" &
  running=$(( running + 1 ))
done
while [ "$running" -gt 0 ]; do
  wait -n || failed=1
  running=$(( running - 1 ))
done
kill "$progress_pid" 2>/dev/null || true
progress
echo >&2
[ "$failed" -eq 0 ] || { echo "reproduce.sh: a run failed (see $out/runs/*.log)" >&2; exit 1; }
elapsed=$(( $(date +%s) - start ))
/usr/bin/python3 "$PC_EKF_ROOT/launch_free_scripts/lib/reproduce_report.py" "$out" "$seeds" "$elapsed"
pc_ekf_log "done in ${elapsed}s: $out/summary.md, $out/figures/"
