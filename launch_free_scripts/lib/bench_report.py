#!/usr/bin/python3
"""bench.sh's report: reads the Google Benchmark JSON outputs (DIR/raw/*.json),
the node measurements (DIR/node*/node.json, each the median of bench.sh's
runs: lib/bench_median.py), the end-to-end runs and the long drive
(DIR/long/long.json), writes DIR/bench.json (the headline keys first, then
every detail) and prints one table.

Usage: bench_report.py DIR [ELAPSED_SECONDS]
"""
import datetime
import json
import math
import os
import pathlib
import platform
import statistics
import subprocess
import sys

out = pathlib.Path(sys.argv[1])
elapsed = float(sys.argv[2]) if len(sys.argv) > 2 else None


def load(name):
    path = out / "raw" / f"{name}.json"
    if not path.exists():
        return {}
    try:
        data = json.loads(path.read_text())
    except json.JSONDecodeError:
        return {}
    return {b["name"]: b for b in data.get("benchmarks", []) if b.get("run_type") != "aggregate"}


one_step = load("bench_one_step")
integrator = load("bench_integrator")
scaling = load("bench_scaling")
propagation = load("bench_propagation")
enkf = load("bench_enkf")
posterior = load("bench_posterior")
checkpoint = load("bench_checkpoint")
odeint = load("bench_odeint")
pdf = load("bench_pdf")


def repetitions(name, prefix):
    """Every repetition of the benchmarks named prefix... (load() keeps the last)."""
    try:
        data = json.loads((out / "raw" / f"{name}.json").read_text())
    except (OSError, json.JSONDecodeError):
        return []
    return [b for b in data.get("benchmarks", [])
            if b.get("run_type") != "aggregate" and b["name"].startswith(prefix)]


pdf_runs = repetitions("bench_pdf", "PdfN11/")
# forecast_thread_speedup: bench.sh repeats BM_ForecastThreads/0 (--runs times).
speedups = [b["speedup"] for b in repetitions("bench_forecast_threads", "BM_ForecastThreads/0")
            if b.get("speedup") is not None]


def load_json(path, missing):
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return missing


node = load_json(out / "node" / "node.json",
                 {"node_samples_per_s": None, "node_peak_rss_mb": None, "reason": "no node.json"})
node_n11 = load_json(out / "node_n11" / "node.json", {"reason": "no node_n11/node.json"})
node_road_free = load_json(out / "node_road_free" / "node.json",
                           {"reason": "no node_road_free/node.json"})
node_full_car_imu = load_json(out / "node_full_car_imu" / "node.json",
                              {"reason": "no node_full_car_imu/node.json"})
end_to_end = load_json(out / "end_to_end" / "end_to_end.json", {"reason": "no end_to_end.json"})
node_live = load_json(out / "node_live" / "node.json", {"reason": "no node_live/node.json"})
long_drive = load_json(out / "long" / "long.json", {"reason": "no long/long.json"})


def get(table, name, counter):
    v = table.get(name, {}).get(counter)
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return None
    return v


paper = "BM_OneStepPaper/40/0/iterations:1"
paper_rk4 = "BM_OneStepPaper/40/1/iterations:1"
paper_dp5 = "BM_OneStepPaper/40/2/iterations:1"
khz = "BM_OneStep1kHz/10/0/iterations:1"
khz_dp5 = "BM_OneStep1kHz/10/2/iterations:1"
pcmc = "BM_PcVersusMonteCarlo/iterations:1"
enkf_name = "BM_EnkfEqualAccuracy/iterations:1"
post = "BM_ReferencePosteriorCaseB/2/iterations:1/real_time"
post_car = "BM_ReferencePosteriorFullCar/2/iterations:1/real_time"
car = "BM_OneStepFullCar/20/iterations:1"
ckpt_bg = "BM_CallbackWhileCheckpointWritten/iterations:1/real_time"
ckpt_fg = "BM_CheckpointInCallback/iterations:1/real_time"
ckpt_none = "BM_CallbackWithoutCheckpoint/iterations:1/real_time"

members = get(enkf, enkf_name, "equal_accuracy_members")

result = {
    "real_time_factor": get(one_step, paper, "real_time_factor"),
    "update_latency_median_us": get(one_step, paper, "median_us"),
    "update_latency_p99_us": get(one_step, paper, "p99_us"),
    "update_latency_p99_us_1khz": get(one_step, khz, "p99_us"),
    "update_latency_median_us_1khz": get(one_step, khz, "median_us"),
    "mc_propagation_sample_ratio": get(propagation, pcmc, "sample_ratio"),
    "mc_propagation_wall_ratio": get(propagation, pcmc, "wall_ratio"),
    "enkf_equal_accuracy_members": None if members is None or members < 0 else members,
    "enkf_wall_ratio": None if members is None or members < 0 else get(enkf, enkf_name, "wall_ratio"),
    "enkf_integration_ratio": None if members is None or members < 0 else get(enkf, enkf_name, "integration_ratio"),
    "wholeset_1e4_update_s": get(scaling, "BM_WholeSet/10000/iterations:1", "beyond_forecast_s"),
    "reference_posterior_s": get(posterior, post, "wall_s"),
    "full_car_real_time_factor": get(one_step, car, "real_time_factor"),
    "full_car_update_latency_median_us": get(one_step, car, "median_us"),
    "full_car_reference_posterior_s": get(posterior, post_car, "wall_s"),
    "node_samples_per_s": node.get("node_samples_per_s"),
    "node_peak_rss_mb": node.get("node_peak_rss_mb"),
    "checkpoint_callback_max_ms_1khz": get(checkpoint, ckpt_bg, "callback_max_ms"),
    "checkpoint_sample_delay_max_ms_1khz": get(checkpoint, ckpt_bg, "delay_max_ms"),
    "checkpoint_in_callback_delay_max_ms_1khz": get(checkpoint, ckpt_fg, "delay_max_ms"),
    "no_checkpoint_delay_max_ms_1khz": get(checkpoint, ckpt_none, "delay_max_ms"),
    "odeint_vs_handwritten": {k: b.get("us_per_interval") for k, b in odeint.items()} or None,
    "mc_propagation_sample_ratio_default": get(propagation, "BM_DesignDefault/iterations:1", "sample_ratio"),
    # Q = 2S Halton, p = 2: the sparse grid of the same p has the larger moment
    # error (many_parameters_accuracy), so the keys are the Halton design's.
    "rtf_n4": get(scaling, "BM_ManyParameters/4/2/1/iterations:1", "real_time_factor"),
    "rtf_n8": get(scaling, "BM_ManyParameters/8/2/1/iterations:1", "real_time_factor"),
    # The median of bench.sh's repetitions (the single run in bench_scaling's
    # output without them).
    "forecast_thread_speedup": (statistics.median(speedups) if speedups else
                                get(scaling, "BM_ForecastThreads/0/iterations:1", "speedup")),
    # What users run, timed whole (docs/realtime.md): estimate_offline end to
    # end (median of the runs), the n = 11 node at 1 kHz in real time, the PDFs.
    "rtf_n11_end_to_end": end_to_end.get("rtf_n11_end_to_end"),
    "road_free_rtf_end_to_end": end_to_end.get("road_free_rtf_end_to_end"),
    "road_free_node_lost": node_road_free.get("node_samples_lost"),
    "road_free_node_max_lag_ms": node_road_free.get("node_max_lag_ms"),
    "full_car_imu_node_lost": node_full_car_imu.get("node_samples_lost"),
    "full_car_imu_node_max_lag_ms": node_full_car_imu.get("node_max_lag_ms"),
    "node_n11_1khz_lost": node_n11.get("node_samples_lost"),
    "node_n11_1khz_max_lag_ms": node_n11.get("node_max_lag_ms"),
    # Wall time per call (all 11 parameters' histograms), best repetition.
    "pdf_n11_ms": min((b["real_time"] for b in pdf_runs if b.get("time_unit") == "ms"),
                      default=None),
    "full_car_tolerances_rtf": end_to_end.get("full_car_tolerances_rtf"),
    # issue 31: the shipped live configs as users run them (estimate_offline
    # end to end on the paper bump, median of the runs; the node on a 1 kHz bag
    # fed by rosbag play without a handshake).
    "live_rtf_end_to_end": end_to_end.get("live_rtf_end_to_end"),
    "full_car_live_rtf_end_to_end": end_to_end.get("full_car_live_rtf_end_to_end"),
    # issue 45: driving as people drive (docs/models.md): the road-free full car
    # with heights, bars and odometry, and the roll plane on its turns course,
    # each on a 10 s, 200 Hz drive.
    "full_car_imu_rtf_end_to_end": end_to_end.get("full_car_imu_rtf_end_to_end"),
    "driving_rtf_end_to_end": end_to_end.get("driving_rtf_end_to_end"),
    "live_node_1khz_lost": node_live.get("node_samples_lost"),
    "live_node_1khz_max_lag_ms": node_live.get("node_max_lag_ms"),
    # issue 44: long_drive.yaml's 20 minutes through the node (lib/bench_long.sh).
    **{k: long_drive.get(k) for k in (
        "long_node_rss_growth_mb", "long_node_max_lag_ms", "long_node_lost",
        "long_node_load_changes", "long_node_matches_offline", "long_offline_rtf",
        "long_offline_max_rss_mb")},
}

details = {
    "one_step": {k: {c: v for c, v in b.items() if c not in ("family_index", "per_family_instance_index", "run_name", "run_type", "repetitions", "repetition_index", "threads", "iterations", "time_unit")}
                 for k, b in one_step.items()},
    "integrator_accuracy_cost": [
        {"method": "dp5" if b.get("dp5") else "rk4", "max_step_ms": b.get("max_step_ms"),
         "error_rel_range": b.get("error_rel_range"), "error_rel_noise": b.get("error_rel_noise"),
         "us_per_30ms_interval": b.get("us_per_interval")}
        for k, b in integrator.items() if k.startswith("BM_StepAccuracy")],
    "update_scaling": [
        {c: b.get(c) for c in ("n", "p", "S", "Q", "median_us", "p99_us")}
        for k, b in scaling.items() if k.startswith("BM_UpdateScaling")],
    "wholeset": [
        {c: b.get(c) for c in ("samples", "observations", "forecast_s", "stack_project_s",
                               "kalman_s", "beyond_forecast_s")}
        for k, b in scaling.items() if k.startswith("BM_WholeSet")],
    "pc_vs_mc": {k: {c: v for c, v in b.items() if c not in ("family_index", "per_family_instance_index", "run_name", "run_type", "repetitions", "repetition_index", "threads", "iterations", "time_unit")}
                 for k, b in propagation.items()},
    "design_curve": [
        {c: b.get(c) for c in ("sequence", "regression", "p", "S", "Q", "pc_error", "sample_ratio",
                               "pc_cpu_s", "wall_ratio", "filter_mean_error", "filter_std_error",
                               "relinearized_mean_error", "relinearized_std_error")}
        for k, b in propagation.items() if k.startswith("BM_DesignCurve")],
    "design_default": propagation.get("BM_DesignDefault/iterations:1", {}),
    "many_parameters": [
        {c: b.get(c) for c in ("n", "p", "S", "Q", "smolyak", "q_norm", "threads", "median_us",
                               "p99_us", "real_time_factor")}
        for k, b in scaling.items() if k.startswith("BM_ManyParameters")],
    "many_parameters_accuracy": [
        {c: b.get(c) for c in ("n", "p", "Q_smolyak", "Q_halton", "smolyak_error", "halton_error",
                               "Q_hyperbolic", "hyperbolic_error", "reference_check")}
        for k, b in propagation.items() if k.startswith("BM_ManyParametersAccuracy")],
    "forecast_threads": {k: b for k, b in scaling.items() if k.startswith("BM_ForecastThreads")},
    "forecast_thread_speedup_runs": speedups,
    "enkf": enkf.get(enkf_name, {}),
    "reference_posterior_case_b": posterior.get(post, {}),
    "node": node,
    "node_n11": node_n11,
    "node_road_free": node_road_free,
    "node_full_car_imu": node_full_car_imu,
    "node_live": node_live,
    "long_drive": long_drive,
    "end_to_end": end_to_end,
    "pdf": [{c: b.get(c) for c in ("name", "real_time", "cpu_time", "time_unit", "iterations")}
            for b in repetitions("bench_pdf", "")],
    "checkpoint": {k: {c: b.get(c) for c in ("callback_max_ms", "callback_p99_ms",
                                             "callback_median_ms", "delay_max_ms", "delay_p99_ms",
                                             "delay_max_worst_pass_ms", "passes",
                                             "write_max_ms", "kept_samples", "checkpoints_written",
                                             "checkpoints_superseded", "real_time")}
                   for k, b in checkpoint.items()},
    "odeint": {k: {c: b.get(c) for c in ("us_per_interval", "evaluations", "max_difference")}
               for k, b in odeint.items()},
}


def cpu_model():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def git_commit():
    try:
        return subprocess.run(["git", "-C", str(pathlib.Path(__file__).resolve().parents[2]),
                               "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              check=False).stdout.strip() or None
    except OSError:
        return None


machine = {
    "cpu": cpu_model(),
    "cores": os.cpu_count(),
    "load_average_at_report": os.getloadavg()[0],
    "date": datetime.datetime.now().isoformat(timespec="seconds"),
    "commit": git_commit(),
    "bench_seconds": elapsed,
    "timing": "CPU time of the measuring thread, best over passes (one-step: per sample, best of "
              "40 passes of the record spread over ~4 s; median/p99 over the samples)",
}
(out / "bench.json").write_text(json.dumps({**result, "machine": machine, "details": details},
                                           indent=2) + "\n")


def fmt(v, unit="", digits=3):
    if v is None:
        return "n/a"
    if isinstance(v, float):
        if v != 0 and (abs(v) >= 1e5 or abs(v) < 1e-3):
            s = f"{v:.{digits}g}"
        else:
            s = f"{v:.{digits}g}" if abs(v) < 100 else f"{v:.0f}"
    else:
        s = str(v)
    return s + unit


def status(ok):
    return "n/a" if ok is None else ("met" if ok else "NOT met")


rows = []


def row(figure, value, target, ok):
    rows.append((figure, value, target, status(ok)))


def cmp(v, op, t):
    if v is None:
        return None
    return v >= t if op == ">=" else v <= t


# How many runs the medians come from (bench.sh --runs).
e2e_n = f"median of {end_to_end.get('runs', '?')}"
def node_n(node_json):
    return f"median of {node_json.get('runs_measured', node_json.get('runs', '?'))} runs"
def lag_parts(j, prefix="node_"):  # the lag's parts: the node's own and the input's (player)
    return (f"own {fmt(j.get(prefix + 'own_max_lag_ms'), ' ms')}, "
            f"input {fmt(j.get(prefix + 'input_max_lag_ms'), ' ms')}")
rtf = result["real_time_factor"]
row("real-time factor, one-step, paper config, 1 thread", fmt(rtf, "x"), ">= 1000x", cmp(rtf, ">=", 1000))
row("  update latency median / p99 (dt = 30 ms)",
    f"{fmt(result['update_latency_median_us'], ' us')} / {fmt(result['update_latency_p99_us'], ' us')}",
    "<= 30 us", cmp(result["update_latency_median_us"], "<=", 30))
for name, label in ((paper_rk4, "rk4 1 ms"), (paper_dp5, "dp5 3 ms")):
    v = get(one_step, name, "real_time_factor")
    if v is not None:
        row(f"  same with integration {label}",
            f"{fmt(v, 'x')} ({fmt(get(one_step, name, 'median_us'), ' us')} median)", ">= 1000x",
            cmp(v, ">=", 1000))
row("1 kHz stream, update latency p99 (median)",
    f"{fmt(result['update_latency_p99_us_1khz'], ' us')} ({fmt(result['update_latency_median_us_1khz'], ' us')})",
    "<= 200 us", cmp(result["update_latency_p99_us_1khz"], "<=", 200))
e_pc = get(propagation, pcmc, "pc_error")
row(f"PC (Q = 30) vs MC propagation, MC samples to match (PC error {fmt(e_pc)})",
    fmt(get(propagation, pcmc, "mc_samples_to_match")), "", None)
row("  integration ratio MC / PC", fmt(result["mc_propagation_sample_ratio"], "x"), ">= 100x",
    cmp(result["mc_propagation_sample_ratio"], ">=", 100))
row("  wall (CPU) ratio MC / PC", fmt(result["mc_propagation_wall_ratio"], "x"), ">= 30x",
    cmp(result["mc_propagation_wall_ratio"], ">=", 30))
gauss = "BM_PcOrderVersusMonteCarlo/4/5/iterations:1"
if gauss in propagation:
    row(f"  same, 5x5 Gauss points, p = 4 (PC error {fmt(get(propagation, gauss, 'pc_error'))})",
        f"{fmt(get(propagation, gauss, 'sample_ratio'), 'x')} / {fmt(get(propagation, gauss, 'wall_ratio'), 'x')}",
        ">= 100x / 30x", cmp(get(propagation, gauss, "sample_ratio"), ">=", 100))
e = enkf.get(enkf_name, {})
if e:
    row(f"EnKF vs PC-EKF error / posterior std (10 seeds): A {fmt(e.get('pc_error_A'))}, "
        f"B {fmt(e.get('pc_error_B'))} (PC-EKF)", "", "", None)
    row("  EnKF members for equal accuracy, both cases",
        fmt(result["enkf_equal_accuracy_members"]) if result["enkf_equal_accuracy_members"] else
        f"none <= {fmt(e.get('largest_members'))}", "", None)
    for case in ("A", "B"):
        m = e.get(f"equal_accuracy_members_{case}")
        row(f"  case {case}: EnKF members for equal accuracy",
            fmt(m) if m is not None and m > 0 else f"none <= {fmt(e.get('largest_members'))} "
            f"(EnKF error {fmt(e.get(f'enkf_best_error_{case}'))})",
            "", None)
        if m is not None and m > 0:
            row(f"  case {case}: EnKF / PC-EKF CPU time, integrations at that size",
                f"{fmt(e.get(f'wall_ratio_{case}'), 'x')}, {fmt(e.get(f'integration_ratio_{case}'), 'x')}",
                ">= 2x", cmp(e.get(f"wall_ratio_{case}"), ">=", 2))
for b in details["update_scaling"]:
    if (b["n"], b["p"]) in ((2, 2), (2, 8), (4, 2), (4, 4), (4, 8)):
        row(f"update cost n = {b['n']:.0f}, p = {b['p']:.0f} (S = {b['S']:.0f}, Q = {b['Q']:.0f}), median",
            fmt(b["median_us"], " us"), "", None)
for b in details["wholeset"]:
    row(f"whole-set N = {b['samples']:.0f}: forecast / everything after it",
        f"{fmt(b['forecast_s'], ' s')} / {fmt(b['beyond_forecast_s'], ' s')}",
        "< 0.1 s (N = 1e4)" if b["samples"] == 10000 else "linear",
        cmp(b["beyond_forecast_s"], "<=", 0.1) if b["samples"] == 10000 else None)
sequences = {0: "halton", 1: "hammersley", 2: "gauss", 3: "smolyak"}
for b in details["design_curve"]:
    label = sequences.get(int(b["sequence"] or 0), "?") + (" (regression)" if b["regression"] and b["sequence"] == 3 else "")
    row(f"design {label}, p = {b['p']:.0f}, Q = {b['Q']:.0f}: moment error, MC sample ratio, "
        f"filter mean/std error vs exact posterior (re-linearised)",
        f"{fmt(b['pc_error'])}, {fmt(b['sample_ratio'], 'x')}, {fmt(b['filter_mean_error'])}/{fmt(b['filter_std_error'])}"
        f" ({fmt(b['relinearized_mean_error'])}/{fmt(b['relinearized_std_error'])})",
        "", None)
row("MC sample ratio of the default design (paper case, no pc:/collocation: given)",
    fmt(result["mc_propagation_sample_ratio_default"], "x"), ">= 100x",
    cmp(result["mc_propagation_sample_ratio_default"], ">=", 100))
for b in details["many_parameters_accuracy"]:
    row(f"n = {b['n']:.0f}, p = {b['p']:.0f}: moment error sparse grid (Q = {b['Q_smolyak']:.0f}) / "
        f"Halton Q = 2S = {b['Q_halton']:.0f}",
        f"{fmt(b['smolyak_error'])} / {fmt(b['halton_error'])}", "sparse <= Halton",
        None if b["smolyak_error"] is None or b["halton_error"] is None
        else b["smolyak_error"] <= b["halton_error"])
for b in details["many_parameters"]:
    if b["threads"] is not None:
        row(f"n = {b['n']:.0f}, p = {b['p']:.0f}, S = {b['S']:.0f}, "
            f"{'sparse grid' if b['smolyak'] else 'Halton'} Q = {b['Q']:.0f}, "
            f"{b['threads']:.0f} thread(s): median update, real-time factor",
            f"{fmt(b['median_us'], ' us')}, {fmt(b['real_time_factor'], 'x')}", "", None)
row("rtf_n4 (p = 2, Q = 2S = 30 Halton, 2 threads configured)", fmt(result["rtf_n4"], "x"), ">= 500x",
    cmp(result["rtf_n4"], ">=", 500))
row("rtf_n8 (p = 2, Q = 2S = 90 Halton, 2 threads; process() only: no start-up, no PDFs, "
    "no output)", fmt(result["rtf_n8"], "x"), ">= 100x", cmp(result["rtf_n8"], ">=", 100))
row(f"road_free_rtf_end_to_end (estimate_offline, vehicle_imu.yaml on a 10 s, 200 Hz CSV, {e2e_n})",
    fmt(result["road_free_rtf_end_to_end"], "x"), ">= 40x",
    cmp(result["road_free_rtf_end_to_end"], ">=", 40))
row("road_free_node_lost (estimator_node, vehicle_imu.yaml, its 10 s bag by rosbag play -r 5; "
    "worst run)", fmt(result["road_free_node_lost"]), "0", cmp(result["road_free_node_lost"], "<=", 0))
row(f"road_free_node_max_lag_ms ({node_n(node_road_free)}; {lag_parts(node_road_free)})", fmt(result["road_free_node_max_lag_ms"], " ms"), "<= 50 ms",
    cmp(result["road_free_node_max_lag_ms"], "<=", 50))
row("full_car_imu_node_lost (estimator_node, full_car_imu.yaml, its 10 s bag by rosbag play -r 5; "
    "worst run)", fmt(result["full_car_imu_node_lost"]), "0",
    cmp(result["full_car_imu_node_lost"], "<=", 0))
row(f"full_car_imu_node_max_lag_ms ({node_n(node_full_car_imu)}; {lag_parts(node_full_car_imu)})",
    fmt(result["full_car_imu_node_max_lag_ms"], " ms"), "<= 50 ms",
    cmp(result["full_car_imu_node_max_lag_ms"], "<=", 50))
row(f"rtf_n11_end_to_end (whole estimate_offline --method one_step, n = 11, {e2e_n})",
    fmt(result["rtf_n11_end_to_end"], "x"), ">= 30x", cmp(result["rtf_n11_end_to_end"], ">=", 30))
row(f"full_car_tolerances_rtf (whole estimate_offline, full car n = 12, dt = 30 ms, {e2e_n})",
    fmt(result["full_car_tolerances_rtf"], "x"), ">= 10x",
    cmp(result["full_car_tolerances_rtf"], ">=", 10))
row("pdf_n11_ms (PDFs of the 11 parameters, 10^5 draws, per call)", fmt(result["pdf_n11_ms"], " ms"),
    "<= 20 ms", cmp(result["pdf_n11_ms"], "<=", 20))
row("node_n11_1khz_lost (n = 11 at 1 kHz, real time, no handshake; worst run)",
    fmt(result["node_n11_1khz_lost"]), "0", cmp(result["node_n11_1khz_lost"], "<=", 0))
row(f"node_n11_1khz_max_lag_ms ({node_n(node_n11)}; {lag_parts(node_n11)})", fmt(result["node_n11_1khz_max_lag_ms"], " ms"), "<= 50 ms",
    cmp(result["node_n11_1khz_max_lag_ms"], "<=", 50))
row(f"live_rtf_end_to_end (estimate_offline, vehicle_live.yaml as shipped on the bump, N = 100, {e2e_n})",
    fmt(result["live_rtf_end_to_end"], "x"), ">= 40x", cmp(result["live_rtf_end_to_end"], ">=", 40))
row(f"full_car_live_rtf_end_to_end (same, full_car_live.yaml, {e2e_n})",
    fmt(result["full_car_live_rtf_end_to_end"], "x"), ">= 40x",
    cmp(result["full_car_live_rtf_end_to_end"], ">=", 40))
row(f"full_car_imu_rtf_end_to_end (estimate_offline, full_car_imu.yaml on a 10 s, 200 Hz CSV, {e2e_n})",
    fmt(result["full_car_imu_rtf_end_to_end"], "x"), ">= 40x",
    cmp(result["full_car_imu_rtf_end_to_end"], ">=", 40))
row(f"driving_rtf_end_to_end (estimate_offline, vehicle_imu.yaml on a lane change and a turn, "
    f"10 s at 200 Hz, {e2e_n})",
    fmt(result["driving_rtf_end_to_end"], "x"), ">= 40x",
    cmp(result["driving_rtf_end_to_end"], ">=", 40))
row("live_node_1khz_lost (estimator_node, vehicle_live.yaml as shipped, 1 kHz bag by rosbag play; "
    "worst run)",
    fmt(result["live_node_1khz_lost"]), "0", cmp(result["live_node_1khz_lost"], "<=", 0))
row(f"live_node_1khz_max_lag_ms ({node_n(node_live)}; {lag_parts(node_live)})", fmt(result["live_node_1khz_max_lag_ms"], " ms"), "<= 50 ms",
    cmp(result["live_node_1khz_max_lag_ms"], "<=", 50))
runs_text = (f"median of {len(speedups)}: {', '.join(fmt(v) for v in speedups)}" if speedups
             else "one run")
row(f"forecast speedup on 2 threads (n = 4, p = 4, Q = 140 Halton; {runs_text})", fmt(result["forecast_thread_speedup"], "x"),
    ">= 1.7x", cmp(result["forecast_thread_speedup"], ">=", 1.7))
ld = long_drive
rate = f"rosbag play -r {fmt(ld.get('rate'))}" if ld.get("rate") else "rosbag play"
row(f"long_node_rss_growth_mb (node, long_drive.yaml's 20 min, {rate}: RSS end - at 1 min "
    f"({fmt(ld.get('node_rss_after_first_minute_mb'), ' MB')}))", fmt(result["long_node_rss_growth_mb"], " MB"), "<= 20 MB",
    cmp(result["long_node_rss_growth_mb"], "<=", 20))
row(f"long_node_max_lag_ms (one run, {rate}; at t = {fmt(ld.get('node_max_lag_at_s'))} s; "
    f"{lag_parts(ld)})", fmt(result["long_node_max_lag_ms"], " ms"),
    "<= 50 ms", cmp(result["long_node_max_lag_ms"], "<=", 50))
row(f"long_node_lost (of {fmt(ld.get('samples'))})", fmt(result["long_node_lost"]), "0",
    cmp(result["long_node_lost"], "<=", 0))
row(f"long_node_load_changes (found at t = {ld.get('node_load_changed_at_s')} s)",
    fmt(result["long_node_load_changes"]), "2 (~250 s, ~740 s)",
    None if result["long_node_load_changes"] is None else result["long_node_load_changes"] == 2)
row("long_node_matches_offline (last estimate vs estimate_offline --bag: max rel. diff of mean, std)",
    fmt(result["long_node_matches_offline"]), "<= 1e-9",
    cmp(result["long_node_matches_offline"], "<=", 1e-9))
row(f"long_offline_rtf (estimate_offline --bag on that bag, median of {fmt(ld.get('offline_runs'))})",
    fmt(result["long_offline_rtf"], "x"), ">= 30x", cmp(result["long_offline_rtf"], ">=", 30))
row("long_offline_max_rss_mb (/usr/bin/time -v, largest of the runs)",
    fmt(result["long_offline_max_rss_mb"], " MB"), "<= 300 MB",
    cmp(result["long_offline_max_rss_mb"], "<=", 300))
p = posterior.get(post, {})
row(f"reference posterior case B, 2 threads ({fmt(p.get('simulations'))} simulations)",
    fmt(result["reference_posterior_s"], " s"), "< 30 s", cmp(result["reference_posterior_s"], "<=", 30))
row("full car (n = 3, S = 20, Q = 40, dt = 30 ms): one-step real-time factor, 1 thread",
    fmt(result["full_car_real_time_factor"], "x"), "", None)
row("full car: exact posterior in 3-D, 2 threads", fmt(result["full_car_reference_posterior_s"], " s"),
    "", None)
row(f"estimator_node, 10^4-sample replay at full speed (lost {fmt(node.get('node_samples_lost'))}; "
    f"{node_n(node)})",
    fmt(result["node_samples_per_s"], " samples/s"), ">= 1000/s (1 kHz)",
    cmp(result["node_samples_per_s"], ">=", 1000))
row("estimator_node peak RSS", fmt(result["node_peak_rss_mb"], " MB"), "<= 50 MB",
    cmp(result["node_peak_rss_mb"], "<=", 50))

row("checkpoint of 10^5 samples at 1 kHz: callback max / sample delay max (background write)",
    f"{fmt(result['checkpoint_callback_max_ms_1khz'], ' ms')} / "
    f"{fmt(result['checkpoint_sample_delay_max_ms_1khz'], ' ms')}", "<= 5 ms",
    cmp(result["checkpoint_sample_delay_max_ms_1khz"], "<=", 5))
row("  same, written in the callback (before): sample delay max",
    fmt(result["checkpoint_in_callback_delay_max_ms_1khz"], " ms"), "", None)
row("  same loop without checkpoints (the machine's scheduling): sample delay max",
    fmt(result["no_checkpoint_delay_max_ms_1khz"], " ms"), "", None)
for k, b in details["odeint"].items():
    row(f"integrator {k.replace('BM_', '').split('/iterations')[0]}: per 30 ms interval (paper batch)",
        fmt(b["us_per_interval"], " us"), "", None)

print()
print(f"pc_ekf benchmarks - {machine['cpu']}, {machine['cores']} cores, {machine['date']}, "
      f"commit {machine['commit']}, load {machine['load_average_at_report']:.1f}"
      + (f", {elapsed:.0f} s" if elapsed else ""))
widths = [max(len(r[i]) for r in rows + [("figure", "value", "target", "status")]) for i in range(4)]
header = ("figure", "value", "target", "status")
line = "  ".join(h.ljust(w) for h, w in zip(header, widths))
print(line)
print("-" * len(line))
for r in rows:
    print("  ".join(c.ljust(w) for c, w in zip(r, widths)))
for label, part in (("node", node), ("long drive", long_drive)):
    if part.get("reason"):
        print(f"({label}: {part['reason']})")
print(f"\nwrote {out / 'bench.json'}")
