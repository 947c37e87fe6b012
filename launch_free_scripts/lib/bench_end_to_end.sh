#!/usr/bin/env bash
# Part of bench.sh: what a user runs, timed whole. Each configuration is run
# with `estimate_offline --config CFG --method one_step --out DIR` (start-up,
# design, filter, PDFs, every output file) RUNS times (PC_EKF_BENCH_E2E_RUNS,
# else PC_EKF_BENCH_RUNS, else 3); the median wall time counts (one run is not
# a figure on a shared machine, and the best of N hides how it usually goes),
# and the real-time factor is the record's duration over it.
#   bench_end_to_end.sh BIN_DIR OUT_DIR   -> OUT_DIR/end_to_end.json
#   rtf_n11_end_to_end       test/benchmarks/roll_plane_tolerances.yaml (n = 11)
#   full_car_tolerances_rtf  test/benchmarks/full_car_tolerances.yaml (n = 12)
#   rtf_paper_end_to_end     config/speed_bump.yaml (n = 2, N = 10)
#   road_free_rtf_end_to_end config/vehicle_imu.yaml (road-free, n = 20) on its own
#                            synthetic 10 s, 200 Hz drive (ISO B), read as a CSV
#   live_rtf_end_to_end      config/vehicle_live.yaml as shipped (n = 15) but its
#                            road: the paper bump, N = 100 over 3 s, synthesised
#   full_car_live_rtf_end_to_end  config/full_car_live.yaml likewise (n = 13, the
#                            full car's speed bump)
#   full_car_imu_rtf_end_to_end  config/full_car_imu.yaml (road-free full car with
#                            heights, bars, odometry, n = 14) on its own synthetic
#                            10 s, 200 Hz drive (a braking, a lane change), read as a CSV
#   driving_rtf_end_to_end   config/vehicle_imu.yaml (road-free with heights, a bar,
#                            odometry, n = 20) on a 10 s, 200 Hz drive of a lane
#                            change and a turn on ISO B (its synthetic drive with that
#                            course as truth.road), read as a CSV
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
pc_ekf_require_sources bench_end_to_end.sh
bin=$1
out=$2
mkdir -p "$out"
runs=${PC_EKF_BENCH_E2E_RUNS:-${PC_EKF_BENCH_RUNS:-3}}

# walls CONFIG NAME [ARGS...] -> prints each run's wall time in s, comma-separated
# (null if a run failed); the Python below takes their median.
walls() {
  local config=$1 name=$2 all="" t0 t1
  shift 2
  for i in $(seq "$runs"); do
    t0=$(date +%s.%N)
    if ! "$bin/estimate_offline" --config "$config" --method one_step "$@" --out "$out/$name.$i" \
      >"$out/$name.$i.json" 2>"$out/$name.$i.err"; then
      echo null
      return
    fi
    t1=$(date +%s.%N)
    all+=${all:+,}$(awk -v t0="$t0" -v t1="$t1" 'BEGIN { printf "%.6f", t1 - t0 }')
  done
  echo "$all"
}

n11=$PC_EKF_ROOT/test/benchmarks/roll_plane_tolerances.yaml
car=$PC_EKF_ROOT/test/benchmarks/full_car_tolerances.yaml
paper=$PC_EKF_ROOT/config/speed_bump.yaml
n11_wall=$(walls "$n11" n11)
car_wall=$(walls "$car" full_car)
paper_wall=$(walls "$paper" paper)
imu=$PC_EKF_ROOT/config/vehicle_imu.yaml
road_free_wall=null
if "$bin/synthesize_bag" --config "$imu" --output "$out/road_free.bag" --csv "$out/road_free.csv" \
  2>"$out/road_free_synthesis.err"; then
  road_free_wall=$(walls "$imu" road_free --measurements "$out/road_free.csv")
fi
car_imu=$PC_EKF_ROOT/config/full_car_imu.yaml
car_imu_wall=null
if "$bin/synthesize_bag" --config "$car_imu" --output "$out/full_car_imu.bag" \
  --csv "$out/full_car_imu.csv" 2>"$out/full_car_imu_synthesis.err"; then
  car_imu_wall=$(walls "$car_imu" full_car_imu --measurements "$out/full_car_imu.csv")
fi
# vehicle_imu.yaml as shipped, its synthetic drive turning (truth.road a course).
driving_wall=null
/usr/bin/python3 - "$imu" "$out/driving.yaml" <<'PY' &&
import sys
text = open(sys.argv[1]).read()
start = text.index("\n  road:", text.index("\ntruth:"))
end = text.index("\n  sensor:", start)
course = """
  road:
    source: course
    speed_kmh: 72.0
    iso8608: {class: B, seed: 1}
    course:
      - {type: iso8608, duration: 2.0}
      - {type: lane_change, duration: 2.5, lateral_acceleration: 4.0, surface: iso8608}
      - {type: turn, duration: 4.5, lateral_acceleration: 3.5, ramp: 1.0, surface: iso8608}
      - {type: iso8608, duration: 1.0}"""
open(sys.argv[2], "w").write(text[:start] + course + text[end:])
PY
  "$bin/synthesize_bag" --config "$out/driving.yaml" --output "$out/driving.bag" \
    --csv "$out/driving.csv" 2>"$out/driving_synthesis.err" &&
  driving_wall=$(walls "$out/driving.yaml" driving --measurements "$out/driving.csv")
# The shipped live configs, every section as shipped but the road (a topic
# there): the speed bump, N = 100 over 3 s.
as_shipped_on_bump() {  # as_shipped_on_bump CONFIG OUT
  sed -E "/^road:/,/^[a-z]/ s/^(  source:) *topic\b.*/\1 speed_bump/" "$1" >"$2"
  printf 'sampling:\n  samples: 100\n  duration: 3.0\n' >>"$2"
  grep -qE "^  source: speed_bump" "$2"
}
live_wall=null
car_live_wall=null
as_shipped_on_bump "$PC_EKF_ROOT/config/vehicle_live.yaml" "$out/live.yaml" &&
  live_wall=$(walls "$out/live.yaml" live)
as_shipped_on_bump "$PC_EKF_ROOT/config/full_car_live.yaml" "$out/full_car_live.yaml" &&
  car_live_wall=$(walls "$out/full_car_live.yaml" full_car_live)
/usr/bin/python3 - "$out/end_to_end.json" "$n11_wall" "$car_wall" "$paper_wall" "$runs" \
  "$road_free_wall" "$live_wall" "$car_live_wall" "$car_imu_wall" "$driving_wall" <<'PY'
import json, statistics, sys
path, n11, car, paper, runs, road_free, live, car_live, car_imu, driving = sys.argv[1:]
def each(w):
    return None if w == "null" else [float(x) for x in w.split(",")]
def wall(w):
    return None if w == "null" else statistics.median(each(w))
def rtf(w, duration=3.0):  # the records are 3 s long but road_free's, full_car_imu's, driving's 10 s
    return None if w == "null" else duration / wall(w)
json.dump({
    "rtf_n11_end_to_end": rtf(n11),
    "full_car_tolerances_rtf": rtf(car),
    "rtf_paper_end_to_end": rtf(paper),
    "road_free_rtf_end_to_end": rtf(road_free, 10.0),
    "live_rtf_end_to_end": rtf(live),
    "full_car_live_rtf_end_to_end": rtf(car_live),
    "full_car_imu_rtf_end_to_end": rtf(car_imu, 10.0),
    "driving_rtf_end_to_end": rtf(driving, 10.0),
    "full_car_imu_end_to_end_wall_s": wall(car_imu),
    "driving_end_to_end_wall_s": wall(driving),
    "live_end_to_end_wall_s": wall(live),
    "full_car_live_end_to_end_wall_s": wall(car_live),
    "road_free_end_to_end_wall_s": wall(road_free),
    "n11_end_to_end_wall_s": wall(n11),
    "full_car_tolerances_wall_s": wall(car),
    "paper_end_to_end_wall_s": wall(paper),
    "walls_s": {"n11": each(n11), "full_car_tolerances": each(car), "paper": each(paper),
                "road_free": each(road_free), "live": each(live), "full_car_live": each(car_live),
                "full_car_imu": each(car_imu), "driving": each(driving)},
    "runs": int(runs),
    "statistic": "median",
    "command": "estimate_offline --config CFG --method one_step --out DIR, median wall time of the runs",
}, open(path, "w"), indent=1)
PY
pc_ekf_log "end to end: $(tr -d '\n' <"$out/end_to_end.json")"
