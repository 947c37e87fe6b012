#!/usr/bin/env bash
# Writes the results that a refactor must leave unchanged into DIR, so that two
# trees can be compared with `diff -r DIR_A DIR_B` (bit for bit):
#   - every method on each paper config (N = 10 and N = 100 on the bump),
#     JSON and --out files;
#   - the full car's reference setup; vehicle_live.yaml on a synthesized bag;
#   - reproduce.sh and robustness.sh on a few seeds (their JSON summaries).
# Wall-clock fields are removed from the JSON (they differ between any two runs).
#   result_snapshot.sh DIR [--quick]   (--quick: the estimate_offline runs only)
set -euo pipefail
source "$(dirname "$0")/common.sh"
out=${1:?usage: result_snapshot.sh DIR [--quick]}
quick=${2:-}
pc_ekf_tools_bin || exit 1
mkdir -p "$out"
out=$(cd "$out" && pwd)
cfg=$PC_EKF_ROOT/config
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

run() {  # name, then estimate_offline arguments
  local name=$1
  shift
  "$PC_EKF_BIN/estimate_offline" "$@" --out "$out/$name" >"$out/$name.json" 2>"$tmp/$name.err" ||
    echo "exit $?" >>"$out/$name.json"
}

for c in speed_bump sine_1hz sine_1hz_linear; do
  run "${c}_one_step_paper" --config "$cfg/$c.yaml" --method one_step --update paper
  for m in one_step whole_set es_mda enkf grid; do
    run "${c}_$m" --config "$cfg/$c.yaml" --method "$m"
  done
done
sed 's/^\( *samples:\).*/\1 100/' "$cfg/speed_bump.yaml" >"$tmp/bump100.yaml"
grep -q "^ *samples: 100" "$tmp/bump100.yaml"
for m in one_step es_mda grid; do run "bump100_$m" --config "$tmp/bump100.yaml" --method "$m"; done
for m in one_step es_mda; do run "full_car_bump_$m" --config "$cfg/full_car_bump.yaml" --method "$m"; done
"$PC_EKF_BIN/synthesize_bag" --config "$tmp/bump100.yaml" --output "$tmp/bump100.bag" --seed 3 \
  >/dev/null 2>&1
for m in one_step es_mda; do
  run "vehicle_live_bag_$m" --config "$cfg/vehicle_live.yaml" --bag "$tmp/bump100.bag" --method "$m"
done

if [ "$quick" != --quick ]; then
  bash "$PC_EKF_ROOT/launch_free_scripts/reproduce.sh" --seeds 2 --cases bump10,sine10,linear10 \
    --no-error-vs-n --out "$tmp/reproduce" >/dev/null 2>&1
  cp "$tmp/reproduce/summary.json" "$out/reproduce_summary.json"
  cp -r "$tmp/reproduce/runs" "$out/reproduce_runs"
  bash "$PC_EKF_ROOT/launch_free_scripts/robustness.sh" --seeds 2 --out "$tmp/robustness" \
    >/dev/null 2>&1
  cp -r "$tmp/robustness/runs" "$out/robustness_runs"
fi

# Drop wall-clock fields so that two runs of one tree compare equal.
find "$out" \( -name '*.json' -o -name '*.jsonl' \) -print0 | xargs -0 sed -i -E \
  -e '/^ *"wall_(time_)?s": [^,]*,?$/d' -e 's/"wall_(time_)?s": *[0-9.eE+-]+, *//g'
echo "snapshot in $out"
