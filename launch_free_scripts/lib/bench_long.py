#!/usr/bin/python3
"""lib/bench_long.sh's figures: reads DIR (counter.log, last.json, rss.txt,
rss_end.txt, offline.N.{json,time,wall}) and prints one JSON object.

Usage: bench_long.py DIR SAMPLES RATE RUNS [VMHWM_KB]

The RSS samples are placed on the drive by the counter's first estimate
(drive time first_time_s at first_arrival_unix; the bag plays RATE times
faster than its stamps), so "after the first minute" is of the drive.
"""
import json
import math
import pathlib
import re
import statistics
import sys

out = pathlib.Path(sys.argv[1])
samples, rate, runs = int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
hwm_kb = float(sys.argv[5]) if len(sys.argv) > 5 and sys.argv[5] else None
DRIVE_S = samples / 200.0  # long_drive.yaml: 200 Hz


def read_json(path):
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def counter():
    try:
        last = pathlib.Path(out / "counter.log").read_text().strip().splitlines()[-1]
        return json.loads(last)
    except (OSError, IndexError, ValueError):
        return {}


def rss_series(c):
    """(drive seconds, MB) of each sample taken while the drive played, and the end."""
    rows = []
    for name in ("rss.txt", "rss_end.txt"):
        try:
            for line in (out / name).read_text().splitlines():
                parts = line.split()
                if len(parts) == 2:
                    rows.append((float(parts[0]), float(parts[1]) / 1024.0))
        except (OSError, ValueError):
            pass
    if "first_arrival_unix" not in c or not c.get("received"):
        return []
    t0, u0 = c["first_time_s"], c["first_arrival_unix"]
    return [(t0 + (u - u0) * rate, mb) for u, mb in rows]


def by_name(parameters):
    return {p["name"]: p for p in parameters}


def max_relative_difference(node, offline):
    """demo_table.py's: largest |node - offline| / |offline| over every mean and stddev."""
    if not node or not offline:
        return None
    theirs = by_name(offline)
    worst = 0.0
    for name, p in by_name(node).items():
        q = theirs.get(name)
        if q is None:
            return math.inf
        for key in ("mean", "stddev"):
            worst = max(worst, abs(p[key] - q[key]) / max(abs(q[key]), 1e-300))
    return worst if len(theirs) == len(node) else math.inf


def peak_rss_mb(path):
    try:
        m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", path.read_text())
    except OSError:
        return None
    return int(m.group(1)) / 1024.0 if m else None


c = counter()
series = rss_series(c)
after = [mb for t, mb in series if t >= 60.0]
rss_1min = after[0] if after else None
rss_end = series[-1][1] if series else None
last = read_json(out / "last.json")

walls, rss, offline = [], [], None
for i in range(1, runs + 1):
    result = read_json(out / f"offline.{i}.json")
    try:
        t0, t1 = map(float, (out / f"offline.{i}.wall").read_text().split())
    except (OSError, ValueError):
        continue
    if result is None:
        continue
    offline = offline or result
    walls.append(t1 - t0)
    rss.append(peak_rss_mb(out / f"offline.{i}.time"))
wall = statistics.median(walls) if walls else None
received = c.get("received", 0)
minutes = {}
for t, mb in series:  # the largest RSS in each minute of the drive
    minutes[int(t // 60)] = max(mb, minutes.get(int(t // 60), 0.0))

print(json.dumps({
    "long_node_rss_growth_mb": rss_end - rss_1min if rss_1min is not None and rss_end else None,
    "long_node_max_lag_ms": c.get("max_lag_ms") if received else None,
    "long_node_lost": samples - received,
    "long_node_load_changes": c.get("load_changed") if received else None,
    "long_node_matches_offline": max_relative_difference(
        (last or {}).get("parameters"), (offline or {}).get("parameters")),
    "long_offline_rtf": DRIVE_S / wall if wall else None,
    "long_offline_max_rss_mb": max((r for r in rss if r is not None), default=None),
    # details
    "rate": rate,
    "samples": samples,
    "drive_s": DRIVE_S,
    "node_rss_after_first_minute_mb": rss_1min,
    "node_rss_end_mb": rss_end,
    "node_rss_max_growth_mb": max(after) - rss_1min if after else None,
    "node_peak_rss_mb": hwm_kb / 1024.0 if hwm_kb else None,
    "node_rss_by_minute_mb": [round(minutes[k], 1) for k in sorted(minutes)],
    "node_load_changed_at_s": c.get("load_changed_at_s"),
    "node_last_sample_index": (last or {}).get("sample_index"),
    "node_last_load_changes": (last or {}).get("load_changes"),
    "node_max_lag_at_s": c.get("max_lag_at_s"),
    "node_own_max_lag_ms": c.get("own_max_lag_ms"),
    "node_input_max_lag_ms": c.get("input_max_lag_ms"),
    "node_diag_max_lag_ms": c.get("diag_max_lag_ms"),
    "node_diag_load_changes": c.get("diag_load_changes"),
    "node_samples_per_s": c.get("samples_per_s"),
    "node_first_to_last_s": c.get("first_to_last_s"),
    "offline_samples": (offline or {}).get("samples"),
    "offline_load_changes": [
        {"began_s": x.get("began_s"), "found_s": x.get("found_s")}
        for x in (offline or {}).get("load_changes", [])],
    "offline_wall_s": walls,
    "offline_runs": len(walls),
    "offline_max_rss_mb_each": rss,
    "command": f"rosbag play -r {rate:g} long_drive.bag into estimator_node "
               "_config_file:=config/long_drive.yaml; estimate_offline --config "
               "config/long_drive.yaml --bag long_drive.bag (median wall of the runs)",
}))
