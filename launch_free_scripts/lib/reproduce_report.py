"""Summary and figures of a reproduction run (launch_free_scripts/reproduce.sh).

Reads DIR/runs/*.jsonl (one estimate_offline-equivalent result per line) and
DIR/per_sample/<dataset>/<method>/ (seed 1), writes DIR/summary.json,
DIR/summary.md and DIR/figures/*.png. Every number comes from the runs; the
closing paragraph is generated from them.
"""
import glob
import json
import math
import os
import statistics
import sys

NOMINAL = (200.0, 0.762)
RANGE = (0.5, 0.25)
TRUTH_XI = (0.2326, -0.3875)
TRUTH = tuple(n * (1 + r * x) for n, r, x in zip(NOMINAL, RANGE, TRUTH_XI))
METHODS = ["one_step_paper", "one_step_square_root", "whole_set_paper", "whole_set_square_root",
           "es_mda", "enkf_small", "enkf_large", "grid"]
# Paper cases (docs/method.md §6): data set, the paper's method, its reported xi (or text).
CASES = [
    ("A", "bump10", "one_step_paper", "0.2240, -0.4415"),
    ("B", "bump100", "one_step_paper", "0.3988, -0.0834 (diverged)"),
    ("C", "bump10", "whole_set_paper", "0.2321, -0.3969"),
    ("D", "bump100", "whole_set_paper", "0.2305, -0.3773"),
    ("E", "sine10", "one_step_paper", "mass untrustworthy (PDF beyond 300 kg)"),
    ("F", "sine10", "whole_set_paper", "distance better, mass not"),
    ("G", "sine100", "one_step_paper", "diverges"),
    ("H", "sine100", "whole_set_paper", "M = 221.12 kg (xi1 = 0.2112), wide PDF"),
    ("I", "linear10", "whole_set_paper", "PDFs similar to F"),
    ("I", "linear100", "whole_set_paper", "PDFs similar to H"),
]
PAPER_XI = {"A": (0.2240, -0.4415), "B": (0.3988, -0.0834), "C": (0.2321, -0.3969),
            "D": (0.2305, -0.3773)}


def load_runs(out):
    runs = {}
    for path in sorted(glob.glob(os.path.join(out, "runs", "*.jsonl"))):
        with open(path) as f:
            for line in f:
                if line.strip():
                    r = json.loads(line)
                    runs.setdefault(r["dataset"], {}).setdefault(r["label"], []).append(r)
    return runs


def spread(values):
    return statistics.stdev(values) if len(values) > 1 else 0.0


def stats_of(runs, grid_by_seed):
    """Aggregates of one (data set, method) over seeds."""
    s = {"seeds": len(runs)}
    for i, key in enumerate(("M", "d")):
        means = [r["result"]["parameters"][i]["mean"] for r in runs]
        stds = [r["result"]["parameters"][i]["stddev"] for r in runs]
        xis = [r["result"]["parameters"][i]["xi_mean"] for r in runs]
        s[key + "_mean"] = statistics.fmean(means)
        s[key + "_spread"] = spread(means)
        s["xi%d_mean" % (i + 1)] = statistics.fmean(xis)
        s[key + "_reported_std"] = statistics.fmean(stds)
        s[key + "_coverage"] = statistics.fmean(
            [1.0 if abs(m - TRUTH[i]) <= 2 * sd else 0.0 for m, sd in zip(means, stds)])
        dist, ratio = [], []
        for r, m, sd in zip(runs, means, stds):
            g = grid_by_seed.get(r["seed"])
            if g is None:
                continue
            gm, gs = g["parameters"][i]["mean"], g["parameters"][i]["stddev"]
            dist.append(abs(m - gm) / gs)
            ratio.append(sd / gs)
        s[key + "_posterior_distance"] = statistics.fmean(dist) if dist else None
        s[key + "_std_ratio"] = statistics.fmean(ratio) if ratio else None
    s["flagged"] = statistics.fmean([0.0 if r["result"]["healthy"] else 1.0 for r in runs])
    s["coherence_flagged"] = statistics.fmean(
        [1.0 if r["result"]["coherence"]["flagged"] else 0.0 for r in runs])
    s["wall_s"] = statistics.fmean([r["result"]["wall_time_s"] for r in runs])
    return s


def summarise(runs):
    summary = {}
    for dataset, by_method in runs.items():
        grid = {r["seed"]: r["result"] for r in by_method.get("grid", [])}
        summary[dataset] = {m: stats_of(rs, grid) for m, rs in by_method.items()}
    return summary


def fmt(v, digits=3):
    if v is None:
        return "-"
    if isinstance(v, float) and (math.isnan(v) or math.isinf(v)):
        return "-"
    return f"{v:.{digits}g}"


def write_markdown(out, summary, seeds, elapsed):
    lines = ["# Reproduction of Blanchard, Sandu & Sandu (2008), docs/method.md §6", "",
             f"{seeds} seeds per data set (noise seeds 1..{seeds}); truth M = {TRUTH[0]:.2f} kg, "
             f"d_CG = {TRUTH[1]:.4f} m (xi = {TRUTH_XI[0]}, {TRUTH_XI[1]}). Wall time {elapsed} s.",
             "Columns: mean ± spread over seeds of the estimates; mean reported std; coverage of "
             "the truth by ±2σ; mean |distance| to the exact posterior mean in posterior std; "
             "reported std / posterior std; fraction of runs flagged unhealthy (health checks incl. "
             "multi-rate coherence); mean wall time per run.", ""]
    for dataset in sorted(summary, key=lambda d: (d.rstrip("0123456789"), int(d.lstrip("abcdefghijklmnopqrstuvwxyz") or 0))):
        cases = [c for c in CASES if c[1] == dataset]
        if not cases and dataset not in ("bump10", "bump100"):
            continue
        lines.append(f"## {dataset}: cases {', '.join(c[0] for c in cases) or '-'}")
        lines.append("")
        lines.append("| method | M [kg] | d_CG [m] | xi1, xi2 | std M, d | coverage M, d | "
                     "dist. to posterior M, d | std ratio M, d | flagged | wall [s] | paper (xi) |")
        lines.append("|---|---|---|---|---|---|---|---|---|---|---|")
        for m in METHODS:
            s = summary[dataset].get(m)
            if not s:
                continue
            paper = "; ".join(f"{c[0]}: {c[3]}" for c in cases if c[2] == m)
            lines.append(
                f"| {m} | {s['M_mean']:.3f} ± {s['M_spread']:.3f} | {s['d_mean']:.5f} ± "
                f"{s['d_spread']:.5f} | {s['xi1_mean']:.4f}, {s['xi2_mean']:.4f} | "
                f"{fmt(s['M_reported_std'])}, {fmt(s['d_reported_std'])} | "
                f"{s['M_coverage']:.2f}, {s['d_coverage']:.2f} | "
                f"{fmt(s['M_posterior_distance'])}, {fmt(s['d_posterior_distance'])} | "
                f"{fmt(s['M_std_ratio'])}, {fmt(s['d_std_ratio'])} | {s['flagged']:.2f} | "
                f"{s['wall_s']:.3f} | {paper} |")
        lines.append("")
    lines += ["## What reproduces, what does not, where we do better", ""] + findings(summary)
    with open(os.path.join(out, "summary.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


def findings(summary):
    """Sentences derived from the numbers only."""
    out = []
    for case, dataset, method, _ in CASES:
        s = summary.get(dataset, {}).get(method)
        if not s or case not in PAPER_XI:
            continue
        px = PAPER_XI[case]
        ours = (s["xi1_mean"], s["xi2_mean"])
        sp = (s["M_spread"] / (NOMINAL[0] * RANGE[0]), s["d_spread"] / (NOMINAL[1] * RANGE[1]))
        inside = all(abs(p - o) <= 2 * max(w, 1e-12) for p, o, w in zip(px, ours, sp))
        out.append(f"- Case {case} ({method}, {dataset}): the paper's xi = ({px[0]}, {px[1]}) is "
                   f"{'within' if inside else 'outside'} ±2 seed-spreads of ours "
                   f"({ours[0]:.4f} ± {sp[0]:.4f}, {ours[1]:.4f} ± {sp[1]:.4f}): "
                   f"{'reproduced' if inside else 'not reproduced as a typical outcome'}; "
                   f"coverage of the truth {s['M_coverage']:.2f}/{s['d_coverage']:.2f}, "
                   f"flagged unhealthy in {s['flagged']:.0%} of runs.")
    for dataset in sorted(summary):
        if not any(c[1] == dataset for c in CASES):
            continue  # the error-against-N runs have their own figure
        d = summary[dataset]
        if "one_step_paper" in d and "one_step_square_root" in d:
            p, q = d["one_step_paper"], d["one_step_square_root"]
            out.append(
                f"- {dataset}: ±2σ coverage of the truth, square-root vs paper update: "
                f"{q['M_coverage']:.2f}/{q['d_coverage']:.2f} vs {p['M_coverage']:.2f}/"
                f"{p['d_coverage']:.2f}; runs flagged by the coherence check "
                f"{q['coherence_flagged']:.2f} vs {p['coherence_flagged']:.2f}"
                f"{' - the square-root update does better' if q['M_coverage'] + q['d_coverage'] > p['M_coverage'] + p['d_coverage'] else ''}.")
        if "es_mda" in d and "whole_set_paper" in d and d["es_mda"]["M_posterior_distance"] is not None:
            e, w = d["es_mda"], d["whole_set_paper"]
            out.append(
                f"- {dataset}: distance to the exact posterior mean (posterior std, M/d): "
                f"ES-MDA {e['M_posterior_distance']:.2f}/{e['d_posterior_distance']:.2f} vs the "
                f"paper's whole-set {w['M_posterior_distance']:.2f}/{w['d_posterior_distance']:.2f}.")
    return out


def main():
    out, seeds, elapsed = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    runs = load_runs(out)
    summary = summarise(runs)
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1, sort_keys=True)
    write_markdown(out, summary, seeds, elapsed)
    if os.environ.get("PC_EKF_NO_FIGURES") != "1":
        import reproduce_figures
        reproduce_figures.draw_all(out, runs, TRUTH, NOMINAL, RANGE)


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    main()
