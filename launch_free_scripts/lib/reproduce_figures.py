"""Figures of a reproduction run (paper Fig. 6-10, 12-17 analogues).

Called by reproduce_report.py; matplotlib from Debian (python3-matplotlib).
"""
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

LABELS = {"one_step_paper": "one-step, paper update", "one_step_square_root": "one-step, square root",
          "whole_set_paper": "whole-set, paper", "whole_set_square_root": "whole-set, square root",
          "es_mda": "ES-MDA (square root)", "enkf_small": "EnKF (small)", "enkf_large": "EnKF (large)",
          "grid": "exact posterior (grid)"}
PARAMS = [("added_mass", "M [kg]"), ("added_mass_position", "d_CG [m]")]


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def prior_density(x, nominal, rng):
    xi = (x / nominal - 1.0) / rng
    return np.where(np.abs(xi) <= 1, 0.75 * (1 - xi ** 2), 0.0) / (nominal * rng)


def draw_pdfs(out, dataset, truth, nominal, rng):
    base = os.path.join(out, "per_sample", dataset)
    if not os.path.isdir(base):
        return
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5))
    for row, (name, unit) in enumerate(PARAMS):
        lo, hi = nominal[row] * (1 - rng[row]), nominal[row] * (1 + rng[row])
        x = np.linspace(lo, hi, 400)
        full, zoom = axes[row]
        full.plot(x, prior_density(x, nominal[row], rng[row]), "k--", label="prior")
        centres = []
        for method in LABELS:
            path = os.path.join(base, method, "pdfs.csv")
            if not os.path.exists(path):
                continue
            rows = [r for r in read_csv(path) if r["parameter"] == name]
            if not rows:
                continue
            edges = [float(r["bin_low"]) for r in rows] + [float(rows[-1]["bin_high"])]
            dens = [float(r["density"]) for r in rows]
            style = {"color": "k", "lw": 2.2} if method == "grid" else {"lw": 1.2}
            for ax in (full, zoom):
                ax.stairs(dens, edges, label=LABELS[method], **style)
            mid = 0.5 * (np.array(edges[:-1]) + np.array(edges[1:]))
            w = np.array(dens) * np.diff(edges)
            mean = float(np.sum(w * mid) / np.sum(w))
            sd = float(np.sqrt(np.sum(w * (mid - mean) ** 2) / np.sum(w)))
            centres.append((mean - 4 * sd, mean + 4 * sd))
        if centres:
            zlo = min(c[0] for c in centres)
            zhi = max(c[1] for c in centres)
            zoom.set_xlim(zlo, zhi)
        full.set_yscale("log")
        full.set_ylim(bottom=1e-3 / (hi - lo))
        for ax in (full, zoom):
            ax.axvline(truth[row], color="r", lw=1, label="truth")
            ax.set_xlabel(unit)
            ax.set_ylabel("probability density [1/unit]")
        full.set_title(f"{name}: prior range (log scale)")
        zoom.set_title(f"{name}: posterior region")
    axes[0][1].legend(fontsize=7, loc="upper right")
    fig.suptitle(f"Prior and posterior PDFs, data set {dataset} (seed 1)")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "figures", f"pdfs_{dataset}.png"), dpi=110)
    plt.close(fig)


def draw_estimates(out, truth):
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5), sharex="col")
    for col, dataset in enumerate(("bump10", "bump100")):
        for method, color in (("one_step_paper", "tab:orange"), ("one_step_square_root", "tab:blue")):
            path = os.path.join(out, "per_sample", dataset, method, "samples.csv")
            if not os.path.exists(path):
                continue
            rows = read_csv(path)
            k = np.array([float(r["index"]) for r in rows])
            for row, (name, unit) in enumerate(PARAMS):
                m = np.array([float(r[name + "_mean"]) for r in rows])
                s = np.array([float(r[name + "_stddev"]) for r in rows])
                ax = axes[row][col]
                ax.plot(k, m, color=color, label=LABELS[method] + " mean")
                ax.fill_between(k, m - s, m + s, color=color, alpha=0.25, label="± std")
        for row, (name, unit) in enumerate(PARAMS):
            ax = axes[row][col]
            ax.axhline(truth[row], color="r", lw=1, label="truth")
            grid = os.path.join(out, "per_sample", dataset, "grid", "samples.csv")
            if os.path.exists(grid):
                g = read_csv(grid)[-1]
                ax.errorbar([float(g["index"])], [float(g[name + "_mean"])],
                            yerr=[float(g[name + "_stddev"])], fmt="ks", label="exact posterior")
            ax.set_ylabel(unit)
            ax.set_title(f"{name}, N = {dataset[4:]}")
            if row == 1:
                ax.set_xlabel("sample index k")
            lo = truth[row] * (0.97 if row == 0 else 0.95)
            hi = truth[row] * (1.03 if row == 0 else 1.05)
            ax.set_ylim(lo, hi)
    axes[0][0].legend(fontsize=7)
    fig.suptitle("Estimate ± std against sample index, speed bump (seed 1; paper Fig. 6c,d, 7c,d)")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "figures", "estimate_vs_sample.png"), dpi=110)
    plt.close(fig)


def draw_error_vs_n(out, runs, truth):
    sizes = sorted(int(d[4:]) for d in runs if d.startswith("bump"))
    if len(sizes) < 2:
        return
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for method in LABELS:
        if method == "grid":
            continue
        for i, (name, unit) in enumerate(PARAMS):
            xs, med, q1, q3 = [], [], [], []
            for n in sizes:
                rs = runs.get(f"bump{n}", {}).get(method, [])
                if not rs:
                    continue
                err = [abs(r["result"]["parameters"][i]["mean"] - truth[i]) for r in rs]
                xs.append(n)
                med.append(np.median(err))
                q1.append(np.percentile(err, 25))
                q3.append(np.percentile(err, 75))
            if xs:
                line, = axes[i].plot(xs, med, "o-", label=LABELS[method])
                axes[i].fill_between(xs, q1, q3, color=line.get_color(), alpha=0.15)
    for i, (name, unit) in enumerate(PARAMS):
        axes[i].set_xscale("log")
        axes[i].set_yscale("log")
        axes[i].set_xlabel("number of samples N over 3 s")
        axes[i].set_ylabel(f"|estimate - truth| of {unit}")
        axes[i].set_title(f"{name}: median and quartiles over seeds")
    axes[1].legend(fontsize=7)
    fig.suptitle("Absolute error against N, speed bump (paper Fig. 8)")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "figures", "error_vs_n.png"), dpi=110)
    plt.close(fig)


def draw_coherence(out, runs):
    datasets = [d for d in sorted(runs) if "one_step_paper" in runs[d] and not d.startswith("bump") or d in ("bump10", "bump100")]
    datasets = [d for d in datasets if "one_step_square_root" in runs[d]]
    if not datasets:
        return
    fig, ax = plt.subplots(figsize=(11, 4.5))
    for j, d in enumerate(datasets):
        for off, method, color in ((-0.15, "one_step_paper", "tab:orange"),
                                   (0.15, "one_step_square_root", "tab:blue")):
            vals = [max(max(r["result"]["coherence"]["disagreement"] or [0.0]), 1e-2)
                    for r in runs[d][method]]
            ax.scatter(np.full(len(vals), j + off), vals, s=12, color=color,
                       label=LABELS[method] if j == 0 else None)
    ax.axhline(3.0, color="r", lw=1, label="flag threshold (3)")
    ax.set_yscale("log")
    ax.set_xticks(range(len(datasets)), datasets)
    ax.set_ylabel("max over parameters of |m_full - m_dec| / combined std")
    ax.set_title("Multi-rate coherence check (full stream vs every 10th sample), one point per seed")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "figures", "coherence.png"), dpi=110)
    plt.close(fig)


def draw_all(out, runs, truth, nominal, rng):
    os.makedirs(os.path.join(out, "figures"), exist_ok=True)
    for dataset in runs:
        if not dataset.startswith("bump") or dataset in ("bump10", "bump100"):
            draw_pdfs(out, dataset, truth, nominal, rng)
    draw_estimates(out, truth)
    draw_error_vs_n(out, runs, truth)
    draw_coherence(out, runs)
