#!/usr/bin/python3
"""bench.sh: one node.json from the node.json of repeated lib/bench_node.sh runs.

Usage: bench_median.py OUT.json RUN.json...

Lag, throughput and wall time are the median of the runs that measured them
(one run's largest lag on a shared machine says more about the other jobs
than about the node); lost samples and peak RSS are the worst run's, since a
single loss or peak is a fact, not noise. Every run is kept under per_run.
"""
import json
import pathlib
import statistics
import sys

MEDIAN = ("node_max_lag_ms", "node_input_max_lag_ms", "node_own_max_lag_ms",
          "node_samples_per_s", "node_replay_wall_s")
WORST = {"node_samples_lost": max, "node_peak_rss_mb": max, "node_samples_received": min}

runs = []
for name in sys.argv[2:]:
    try:
        runs.append(json.loads(pathlib.Path(name).read_text()))
    except (OSError, ValueError):
        runs.append({"reason": f"no {name}"})
measured = [r for r in runs if "node_samples_received" in r]  # null runs (write_null) lack it
result = {"node_samples_expected": next((r.get("node_samples_expected") for r in runs
                                         if "node_samples_expected" in r), None)}
for key in MEDIAN:
    values = [r[key] for r in measured if r.get(key) is not None]
    result[key] = statistics.median(values) if values else None
for key, pick in WORST.items():
    values = [r[key] for r in measured if r.get(key) is not None]
    result[key] = pick(values) if values else None
if len(measured) < len(runs):
    result["reason"] = "; ".join(r.get("reason", "run failed") for r in runs
                                 if r not in measured)
result.update({"runs": len(runs), "runs_measured": len(measured),
               "statistic": f"median of {len(measured)} (lost, peak RSS: the worst run)",
               "per_run": runs})
pathlib.Path(sys.argv[1]).write_text(json.dumps(result) + "\n")
