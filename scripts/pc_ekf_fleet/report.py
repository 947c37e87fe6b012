"""report.md, the figures and the progress bar of a fleet run."""
import math
import os
import sys
import time

from pc_ekf_fleet.journal import atomic_write

PARAMETER_LABELS = {"added_mass": "M (kg)", "added_mass_position": "d_CG (m)"}


def vehicle_label(row):
    return row["vehicle_file"] or "(config's vehicle)"


def write_figures(rows, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figures = {}
    estimated = [r for r in rows if r["parameters"]]
    names = list(dict.fromkeys(n for r in estimated for n in r["parameters"]))
    if names:
        fig, axes = plt.subplots(1, len(names), figsize=(4.5 * len(names), 3.6), squeeze=False)
        for ax, name in zip(axes[0], names):
            healthy = [r["parameters"][name]["mean"] for r in estimated
                       if name in r["parameters"] and r["healthy"]]
            unhealthy = [r["parameters"][name]["mean"] for r in estimated
                         if name in r["parameters"] and not r["healthy"]]
            ax.hist([healthy, unhealthy], bins=20, stacked=True, color=["tab:blue", "tab:red"],
                    label=[f"healthy ({len(healthy)})", f"unhealthy ({len(unhealthy)})"])
            ax.set_xlabel(PARAMETER_LABELS.get(name, name))
            ax.set_ylabel("bags")
            ax.legend(fontsize=8)
        fig.suptitle("Estimated means over the fleet")
        fig.tight_layout()
        fig.savefig(os.path.join(out, "fleet_parameters.png"), dpi=90)
        plt.close(fig)
        figures["parameters"] = "fleet_parameters.png"

    vehicles = sorted({vehicle_label(r) for r in rows})
    fig, ax = plt.subplots(figsize=(max(4.0, 1.2 * len(vehicles) + 2), 3.4))
    counts = {kind: [sum(1 for r in rows if vehicle_label(r) == v and kind_of(r) == kind)
                     for v in vehicles] for kind in ("healthy", "unhealthy", "failed")}
    bottom = [0] * len(vehicles)
    for kind, color in (("healthy", "tab:green"), ("unhealthy", "tab:orange"),
                        ("failed", "tab:red")):
        ax.bar(range(len(vehicles)), counts[kind], bottom=bottom, color=color, label=kind)
        bottom = [b + c for b, c in zip(bottom, counts[kind])]
    ax.set_xticks(range(len(vehicles)))
    ax.set_xticklabels([os.path.basename(v) for v in vehicles], rotation=20, fontsize=8)
    ax.set_ylabel("bags")
    total = len(rows)
    ax.set_title(f"Health: {sum(counts['healthy'])} of {total} bags healthy "
                 f"({100.0 * sum(counts['healthy']) / max(total, 1):.0f} %)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "health.png"), dpi=90)
    plt.close(fig)
    figures["health"] = "health.png"

    import matplotlib.dates as mdates
    import datetime
    figures["vehicles"] = {}
    for index, vehicle in enumerate(vehicles):
        mine = [r for r in estimated if vehicle_label(r) == vehicle and r["start_stamp"]]
        if not mine or not names:
            continue
        fig, axes = plt.subplots(len(names), 1, figsize=(6.5, 2.4 * len(names)), sharex=True,
                                 squeeze=False)
        for ax, name in zip(axes[:, 0], names):
            for healthy, style in ((True, "o"), (False, "x")):
                sel = [r for r in mine if name in r["parameters"] and bool(r["healthy"]) == healthy]
                if not sel:
                    continue
                t = [datetime.datetime.fromtimestamp(r["start_stamp"], datetime.timezone.utc)
                     for r in sel]
                ax.errorbar(t, [r["parameters"][name]["mean"] for r in sel],
                            yerr=[r["parameters"][name]["std"] for r in sel], fmt=style,
                            capsize=2, color="tab:blue" if healthy else "tab:red",
                            label="healthy" if healthy else "unhealthy")
            ax.set_ylabel(PARAMETER_LABELS.get(name, name))
            ax.legend(fontsize=7)
        axes[-1, 0].xaxis.set_major_formatter(mdates.DateFormatter("%Y-%m-%d\n%H:%M:%S"))
        axes[-1, 0].set_xlabel("bag start stamp (UTC)")
        fig.suptitle(f"{os.path.basename(vehicle)}: estimate (mean +- std) per bag")
        fig.tight_layout()
        stem = os.path.splitext(os.path.basename(vehicle))[0] if mine[0]["vehicle_file"] else "config"
        name = "".join(c if c.isalnum() or c in "._-" else "_"
                       for c in f"vehicle_{index:02d}_{stem}.png")
        fig.savefig(os.path.join(out, name), dpi=90)
        plt.close(fig)
        figures["vehicles"][vehicle] = name
    return figures


def kind_of(row):
    if not row["parameters"]:
        return "failed"
    return "healthy" if row["healthy"] else "unhealthy"


def stats(values):
    """mean, sample std, min, median, max."""
    values = sorted(values)
    n = len(values)
    mean = sum(values) / n
    std = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1)) if n > 1 else 0.0
    median = values[n // 2] if n % 2 else 0.5 * (values[n // 2 - 1] + values[n // 2])
    return mean, std, values[0], median, values[-1]


def write_report(rows, runs, config, method, vehicle_files, out):
    """DIR/report.md and its figures."""
    figures = write_figures(rows, out)
    atomic_write(os.path.join(out, "report.md"),
                 report_text(rows, runs, config, method, vehicle_files, figures))


def report_text(rows, runs, config, method, vehicle_files, figures):
    """report.md: counts, the fleet distribution of every parameter, a table
    per vehicle, the error rows and the runs (run_log.jsonl's records)."""
    ok = [r for r in rows if not r["error"]]
    errors = [r for r in rows if r["error"]]
    estimated = [r for r in rows if r["parameters"]]
    lines = [f"# Fleet estimate: {len(rows)} bags", "",
             f"- config: `{os.path.abspath(config)}`, method `{method}`",
             f"- vehicle files: `{vehicle_files or '(none: the config vehicle)'}`",
             f"- rows: {len(ok)} estimated and healthy, {len(errors)} error rows "
             f"({sum(1 for r in errors if r['parameters'])} unhealthy with an estimate, "
             f"{sum(1 for r in errors if not r['parameters'])} without one)",
             f"- health fraction: {len(ok)}/{len(rows)} = "
             f"{len(ok) / max(len(rows), 1):.3f} (![health](health.png))", ""]
    names = list(dict.fromkeys(n for r in estimated for n in r["parameters"]))
    if names:
        lines += ["## Fleet distribution (healthy rows)", "",
                  "| parameter | bags | mean of means | std over bags | min | median | max "
                  "| median reported std |", "|---|---|---|---|---|---|---|---|"]
        for name in names:
            sel = [r["parameters"][name] for r in ok if name in r["parameters"]]
            if not sel:
                continue
            mean, std, low, median, high = stats([p["mean"] for p in sel])
            reported = stats([p["std"] for p in sel])[3]
            lines.append(f"| {PARAMETER_LABELS.get(name, name)} | {len(sel)} | {mean:.6g} | "
                         f"{std:.4g} | {low:.6g} | {median:.6g} | {high:.6g} | {reported:.4g} |")
        lines += ["", "![parameters](fleet_parameters.png)", ""]
    lines += ["## Per vehicle", "", "| vehicle file | bags | healthy | unhealthy | failed | "
              + " | ".join(f"median {PARAMETER_LABELS.get(n, n)}" for n in names) + " |",
              "|---|---|---|---|---|" + "---|" * len(names)]
    vehicles = sorted({vehicle_label(r) for r in rows})
    for vehicle in vehicles:
        mine = [r for r in rows if vehicle_label(r) == vehicle]
        medians = []
        for n in names:
            sel = [r["parameters"][n]["mean"] for r in mine if not r["error"] and n in r["parameters"]]
            medians.append(f"{stats(sel)[3]:.6g}" if sel else "-")
        kinds = [kind_of(r) for r in mine]
        lines.append(f"| `{vehicle}` | {len(mine)} | {kinds.count('healthy')} | "
                     f"{kinds.count('unhealthy')} | {kinds.count('failed')} | "
                     + " | ".join(medians) + " |")
    lines.append("")
    for vehicle in vehicles:
        if vehicle in figures.get("vehicles", {}):
            lines += [f"![{os.path.basename(vehicle)}]({figures['vehicles'][vehicle]})", ""]
    if errors:
        lines += ["## Error rows", "", "| bag | reason |", "|---|---|"]
        lines += [f"| `{r['path']}` | {r['error'].replace('|', '/')} |" for r in errors]
        lines.append("")
    lines += ["## Runs into this folder (run_log.jsonl)", "",
              "Wall time from the start; estimating: from the first submission to the last "
              "row (without the cluster's start); bags/s over the estimating time.", "",
              "| started (UTC) | scheduler | workers | bags | skipped | ran | errors | wall s "
              "| estimating s | bags/s |", "|---|---|---|---|---|---|---|---|---|---|"]
    for run in runs:
        lines.append(f"| {run['started']} | {run['scheduler']} | {run['workers']} | "
                     f"{run['bags']} | {run['skipped']} | {run['ran']} | {run['errors']} | "
                     f"{run['wall_s']:.1f} | {run['estimate_s']:.1f} | "
                     f"{run['bags_per_s']:.2f} |" + (" (interrupted)" if run["interrupted"] else ""))
    return "\n".join(lines) + "\n"


class Progress:
    """A bar on stderr: redrawn in place on a terminal, a line per 10 % else."""

    def __init__(self, total):
        self.total, self.done, self.errors = total, 0, 0
        self.start = time.monotonic()
        self.tty = sys.stderr.isatty()
        self.last_tenth = -1

    def update(self, error):
        self.done += 1
        self.errors += 1 if error else 0
        tenth = self.done * 10 // max(self.total, 1)
        if not self.tty and tenth == self.last_tenth and self.done != self.total:
            return
        self.last_tenth = tenth
        elapsed = time.monotonic() - self.start
        rate = self.done / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else 0.0
        filled = 30 * self.done // max(self.total, 1)
        text = (f"[{'#' * filled}{'.' * (30 - filled)}] {self.done}/{self.total} bags, "
                f"{self.errors} errors, {rate:.2f} bags/s, ETA {eta:.0f} s")
        sys.stderr.write(("\r" + text + ("\n" if self.done == self.total else "")) if self.tty
                         else text + "\n")
        sys.stderr.flush()
