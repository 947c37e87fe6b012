#!/usr/bin/python3
"""Prints demo.sh's result table for one bag.

usage: demo_table.py N NODE.json OFFLINE_ONE_STEP_DIR OFFLINE_ES_MDA.json [REPLAY_LOG]
NODE.json is collect_estimates.py's output (the node's last parameter_estimate,
its parameter_estimate/batch and the bag's ground_truth); the OFFLINE ones are
estimate_offline --bag on the same bag: the one-step run's --out directory
(its samples.csv, like the JSON, has round-trip doubles) and the es_mda
run's JSON. Exit 1 when the run was not lossless.
"""
import csv
import json
import math
import re
import sys

LABELS = {"added_mass": "M [kg]", "added_mass_position": "d_CG [m]",
          "added_mass_x": "x_M [m]", "added_mass_y": "y_M [m]"}


def by_name(result):
    return {p["name"]: p for p in (result or {}).get("parameters", [])}


def cell(p, digits):
    if p is None:
        return "n/a".center(24)
    return f"{p['mean']:.{digits}f} +- {p['stddev']:.{digits}f}".rjust(24)


def error_in_std(p, truth):
    if p is None or truth is None or not p["stddev"] > 0:
        return "".rjust(8)
    return f"{(p['mean'] - truth) / p['stddev']:+8.2f}"


def last_sample(out_dir):
    """The final estimate in estimate_offline's samples.csv, shaped like its JSON."""
    with open(f"{out_dir}/samples.csv") as f:
        row = list(csv.DictReader(f))[-1]
    names = [c[: -len("_mean")] for c in row if c.endswith("_mean")]
    return {"parameters": [{"name": n, "mean": float(row[n + "_mean"]),
                            "stddev": float(row[n + "_stddev"])} for n in names]}


def max_relative_difference(node, offline):
    worst = 0.0
    for name, p in by_name(node).items():
        q = by_name(offline).get(name)
        if q is None:
            return math.inf
        for key in ("mean", "stddev"):
            scale = max(abs(q[key]), 1e-300)
            worst = max(worst, abs(p[key] - q[key]) / scale)
    return worst


def difference(d):
    return "0 (identical)" if d == 0 else f"{d:.1e}"


def health(result):
    if result is None:
        return "n/a"
    if result.get("healthy"):
        return "healthy"
    return "UNHEALTHY (" + "; ".join(result.get("warnings", [])) + ")"


def main():
    n = int(sys.argv[1])
    node = json.load(open(sys.argv[2]))
    offline_one_step = last_sample(sys.argv[3])
    offline_batch = json.load(open(sys.argv[4]))
    replay_counts = ""
    if len(sys.argv) > 5:
        m = re.search(r"replayed [^:]*: (.*?) \(", open(sys.argv[5]).read())
        replay_counts = m.group(1) if m else ""

    truth = {name: p["mean"] for name, p in by_name(node.get("truth")).items()}
    last, batch = by_name(node.get("last")), by_name(node.get("batch"))
    print(f"  replay_node -> estimator_node: {replay_counts}")
    print(f"  parameter_estimate messages: {node['received']} for {n} samples "
          f"({node['distinct_stamps']} distinct stamps)")
    names = list(last or truth)
    # The vehicle's tolerances (nuisance parameters) have long names and large values.
    width = max([10] + [len(LABELS.get(name, name)) + 1 for name in names])
    print(f"  {'parameter':<{width}}{'truth':>14}{'one-step (node)':>26}{'err/std':>9}"
          f"{'ES-MDA batch (node)':>26}{'err/std':>9}")
    for name in names:
        digits = 3 if name == "added_mass" else 6
        t = truth.get(name)
        if t is not None and abs(t) >= 1000.0:
            digits = 1
        print(f"  {LABELS.get(name, name):<{width}}"
              f"{(f'{t:.{digits}f}' if t is not None else 'n/a'):>14}"
              f"  {cell(last.get(name), digits)}{error_in_std(last.get(name), t)}"
              f"  {cell(batch.get(name), digits)}{error_in_std(batch.get(name), t)}")
    print(f"  health: one-step {health(node.get('last'))}; batch {health(node.get('batch'))}")
    if node.get("batch_reply") and not node["batch_reply"].get("success"):
        print(f"  ~estimate_batch: {node['batch_reply'].get('message')}")
    diffs = [max_relative_difference(node.get("last"), offline_one_step)]
    line = f"  vs estimate_offline --bag (same bag): one-step max rel. diff {difference(diffs[0])}"
    if node.get("batch"):
        diffs.append(max_relative_difference(node["batch"], offline_batch))
        line += f", es_mda {difference(diffs[1])}"
    line += " (both print round-trip doubles)"
    print(line)
    lossless = node["received"] == n and node["distinct_stamps"] == n
    if not lossless:
        print(f"  NOT LOSSLESS: expected {n} estimates with distinct stamps")
    return 0 if lossless else 1


if __name__ == "__main__":
    sys.exit(main())
