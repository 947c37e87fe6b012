"""Robustness table from robustness.sh's runs.

Usage: robustness_report.py OUT_DIR ROW [ROW ...]
Reads OUT_DIR/runs/<row>.jsonl (reproduce_runs lines) and
OUT_DIR/configs/<row>.yaml, writes OUT_DIR/robustness.md and .json, prints the
markdown. Per row and method, over the seeds:
  covered  every estimated parameter within 3 reported std of its truth
           (the truth at the end of the record when the row has a schedule)
  flagged  healthy = false
  silent   not covered and healthy: the failure this table exists to count,
           with the largest distance (reported std) among them in brackets
"""
import json
import os
import sys

import yaml

COLUMNS = [
    ("one_step_paper", "one-step paper"),
    ("one_step_square_root", "one-step sq. root"),
    ("whole_set_square_root", "whole-set"),
    ("es_mda", "ES-MDA"),
    ("grid", "grid"),
    ("enkf_small", "EnKF"),
]


def truth_values(config):
    values = {}
    xi = config["truth"]["xi"]
    for u, x in zip(config["uncertain"], xi):
        values[u["name"]] = u["nominal"] * (1.0 + u["relative_range"] * x)
    for change in config["truth"].get("schedule") or []:
        if "xi" in change:
            for u, x in zip(config["uncertain"], change["xi"]):
                values[u["name"]] = u["nominal"] * (1.0 + u["relative_range"] * x)
        for name, v in (change.get("values") or {}).items():
            values[name] = v
    return values


def cell(runs, truth):
    n = len(runs)
    covered = flagged = silent = 0
    worst = worst_silent = 0.0
    for r in runs:
        z = max(abs(p["mean"] - truth[p["name"]]) / p["stddev"] if p["stddev"] > 0 else float("inf")
                for p in r["parameters"])
        worst = max(worst, z)
        ok = z <= 3.0
        covered += ok
        flagged += not r["healthy"]
        if not ok and r["healthy"]:
            silent += 1
            worst_silent = max(worst_silent, z)
    return {"runs": n, "covered": covered / n, "flagged": flagged / n, "silent": silent,
            "worst_z": worst, "worst_silent_z": worst_silent}


def main():
    out_dir, rows = sys.argv[1], sys.argv[2:]
    table = {}
    for row in rows:
        config = yaml.safe_load(open(os.path.join(out_dir, "configs", row + ".yaml")))
        truth = truth_values(config)
        by_label = {}
        path = os.path.join(out_dir, "runs", row + ".jsonl")
        for line in open(path):
            line = line.strip()
            if line.startswith("{"):
                d = json.loads(line)
                by_label.setdefault(d["label"], []).append(d["result"])
        table[row] = {label: cell(runs, truth) for label, runs in by_label.items()}
    seeds = max((c["runs"] for r in table.values() for c in r.values()), default=0)
    lines = ["Cells: covered (all parameters within 3 reported std of the truth) / "
             "flagged (healthy false) / silent failures (not covered and healthy; in brackets the "
             "largest of their distances in reported std), "
             "over %d seeds; '-' not run." % seeds, "",
             "| scenario | " + " | ".join(title for _, title in COLUMNS) + " |",
             "|---|" + "---|" * len(COLUMNS)]
    for row in rows:
        cells = []
        for label, _ in COLUMNS:
            c = table[row].get(label)
            if c is None:
                cells.append("-")
                continue
            text = "%.0f%% / %.0f%% / %d" % (100 * c["covered"], 100 * c["flagged"], c["silent"])
            cells.append(text + (" (%.1f)" % c["worst_silent_z"] if c["silent"] else ""))
        lines.append("| %s | %s |" % (row, " | ".join(cells)))
    text = "\n".join(lines) + "\n"
    open(os.path.join(out_dir, "robustness.md"), "w").write(text)
    json.dump(table, open(os.path.join(out_dir, "robustness.json"), "w"), indent=1)
    print(text)


if __name__ == "__main__":
    main()
