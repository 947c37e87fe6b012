"""estimate_fleet's command line and one run into DIR (docs/fleet.md)."""
import argparse
import fcntl
import json
import os
import signal
import sys
import time

from pc_ekf_fleet.inputs import (FleetError, find_bags, find_estimate_offline, hash_bags,
                                 prepare_configs)
from pc_ekf_fleet.journal import Journal, read_rows, write_final
from pc_ekf_fleet.report import Progress, write_report
from pc_ekf_fleet.scheduling import plan, previous_rows, run_on_dask

USAGE_TITLE = "Estimates a fleet's bags on a Dask cluster: one estimate_offline --bag per bag."


def parse_args(argv, description=USAGE_TITLE):
    parser = argparse.ArgumentParser(
        prog="estimate_fleet", description=description,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--config", required=True, help="estimator config (YAML)")
    parser.add_argument("--bags", required=True, nargs="+", metavar="GLOB_OR_DIR",
                        help="bag files: globs (** recursive) or folders (*.bag below)")
    parser.add_argument("--vehicle-files", metavar="MAP.yaml",
                        help="'bag-name pattern: vehicle file' per line (fnmatch, first match)")
    parser.add_argument("--method", default="one_step",
                        choices=["one_step", "whole_set", "es_mda", "enkf", "grid"])
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                       help="a running dask-scheduler (default: a LocalCluster here)")
    where.add_argument("--workers", type=int, default=None,
                       help="LocalCluster worker processes (default: the number of cores)")
    parser.add_argument("--timeout", type=float, default=600.0,
                        help="seconds per bag before estimate_offline is killed (default 600)")
    parser.add_argument("--redo-errors", action="store_true",
                        help="run the bags whose row is an error row again")
    parser.add_argument("--estimate-offline", metavar="PATH",
                        help="the estimate_offline to run (default: the built/installed one)")
    parser.add_argument("--out", required=True, metavar="DIR")
    args = parser.parse_args(argv)
    if args.workers is not None and args.workers < 1:
        parser.error("--workers must be at least 1")
    if not args.timeout > 0:
        parser.error("--timeout must be positive")
    return args


def run(args, script):
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    lock = open(os.path.join(out, ".lock"), "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as err:
        raise FleetError(f"--out {out}: another estimate_fleet is writing there") from err
    if not os.path.isfile(args.config):
        raise FleetError(f"--config {args.config}: no such file")
    paths = find_bags(args.bags)
    exe = find_estimate_offline(args.estimate_offline, script)
    configs, entries = prepare_configs(args.config, args.vehicle_files, paths, out, exe)
    bags, rows, todo = plan(paths, entries, configs, hash_bags(paths), previous_rows(out),
                            args.method, args.redo_errors)
    skipped = len(bags) - len(todo)

    results_path = os.path.join(out, "results.jsonl")
    journal = Journal(results_path)
    for row in rows.values():  # unreadable bags: their rows go in now
        if not row["content_hash"]:
            journal.append(row)
    started = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    start = time.monotonic()
    print(f"estimate_fleet: {len(bags)} bags, {skipped} already done, {len(todo)} to run "
          f"({exe})", file=sys.stderr)
    workers = ran = errors = 0
    interrupted = False
    estimating = 0.0
    if todo:
        progress = Progress(len(todo))

        def on_row(row):
            journal.append(row)
            rows[row["path"]] = row
            progress.update(row["error"])

        def task_of(bag):
            return {"path": bag["path"], "config": bag["config"], "method": args.method,
                    "exe": exe, "timeout": args.timeout}

        done = run_on_dask(todo, task_of, args.scheduler, args.workers, on_row)
        workers, ran, errors, interrupted = done.workers, done.ran, done.errors, done.interrupted
        estimating = time.monotonic() - done.submitted
    journal.close()
    wall = time.monotonic() - start

    final = [rows[p] for p in paths if p in rows]
    write_final(out, final)
    run_record = {"started": started, "workers": workers, "bags": len(bags), "skipped": skipped,
                  "ran": ran, "errors": errors, "wall_s": wall, "estimate_s": estimating,
                  "bags_per_s": ran / estimating if estimating > 0 else 0.0,
                  "interrupted": interrupted,
                  "scheduler": (args.scheduler or "LocalCluster") if todo else "-"}
    with open(os.path.join(out, "run_log.jsonl"), "a", encoding="utf-8") as f:
        f.write(json.dumps(run_record) + "\n")
    write_report(final, read_rows(os.path.join(out, "run_log.jsonl")), args.config,
                 args.method, args.vehicle_files, out)
    bad = sum(1 for r in final if r["error"])
    print(f"estimate_fleet: {len(final)} rows ({len(final) - bad} ok, {bad} errors) in "
          f"{out}/results.jsonl; ran {ran} in {wall:.1f} s on {workers} workers",
          file=sys.stderr)
    return 130 if interrupted else 0


def _interrupt(signum, frame):
    raise KeyboardInterrupt(f"signal {signum}")


def main(argv=None, script=__file__, description=USAGE_TITLE):
    """estimate_fleet [options]; script: the entry point's path (the
    estimate_offline beside it is the default)."""
    args = parse_args(sys.argv[1:] if argv is None else argv, description)
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        return run(args, script)
    except FleetError as err:
        print(f"estimate_fleet: {err}", file=sys.stderr)
        return 2
