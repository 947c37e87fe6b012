"""Checks for lib/fleet_test.sh (estimate_fleet on Dask). Each subcommand
exits 1 with a one-line reason on stdout's last line when a check fails.

  fleet_test_check.py workers tcp://HOST:PORT N TIMEOUT_S
      waits until the scheduler has N workers; prints their addresses
  fleet_test_check.py table OUT_DIR SERIAL_DIR BAGS_FILE [--ok N] [--errors N]
                      [--error BAG_NAME:SUBSTRING ...] [--vehicle BAG_GLOB:VEHICLE_FILE ...]
      results.jsonl holds exactly one row per bag of BAGS_FILE, sorted by path;
      every bag that SERIAL_DIR's estimate_offline run estimated has its
      numbers (means, stds, healthy, warnings, samples) equal to it bit for bit,
      healthy ones have no error, unhealthy ones an "unhealthy:" error, the
      others an error row; results.csv says the same; the given counts and
      error reasons hold
  fleet_test_check.py run OUT_DIR --skipped K --ran M
      the last run_log.jsonl record skipped K bags and ran M
  fleet_test_check.py worker OUT_DIR BAG_PATH NOT_ADDRESS
      the bag's row was made by a worker other than NOT_ADDRESS
  fleet_test_check.py rename_topics IN.bag OUT.bag
      copies IN.bag with every topic renamed (/recorded_<topic>): a bag of
      the right messages on the wrong topics
"""
import argparse
import csv
import fnmatch
import json
import os
import re
import sys
import time


def fail(message):
    print(message)
    sys.exit(1)


def rows_of(out):
    with open(os.path.join(out, "results.jsonl"), encoding="utf-8") as f:
        text = f.read()
    if text and not text.endswith("\n"):
        fail(f"{out}/results.jsonl ends in a torn line")
    return [json.loads(line) for line in text.splitlines()]


def cmd_workers(args):
    from distributed import Client
    deadline = time.monotonic() + args.timeout
    with Client(args.address, timeout=args.timeout) as client:
        while True:
            workers = sorted(client.scheduler_info()["workers"])
            if len(workers) >= args.n:
                print("\n".join(workers))
                return
            if time.monotonic() > deadline:
                fail(f"{len(workers)} of {args.n} workers registered within {args.timeout} s")
            time.sleep(0.1)


def cmd_table(args):
    bags = sorted(os.path.abspath(l.strip()) for l in open(args.bags_file) if l.strip())
    rows = rows_of(args.out)
    paths = [r["path"] for r in rows]
    if paths != bags:
        missing = sorted(set(bags) - set(paths))
        doubled = sorted({p for p in paths if paths.count(p) > 1})
        fail(f"rows are not one per bag in path order: {len(rows)} rows for {len(bags)} bags, "
             f"missing {missing[:3]}, twice {doubled[:3]}, sorted {paths == sorted(paths)}")
    expected_errors = dict(e.split(":", 1) for e in args.error)
    ok = errors = 0
    for row in rows:
        name = os.path.basename(row["path"])
        stem = os.path.splitext(name)[0]
        with open(os.path.join(args.serial, stem + ".rc")) as f:
            rc = int(f.read())
        if rc == 0:
            with open(os.path.join(args.serial, stem + ".json")) as f:
                serial = json.load(f)
            for p in serial["parameters"]:
                got = row["parameters"].get(p["name"])
                if got is None or got["mean"] != p["mean"] or got["std"] != p["stddev"]:
                    fail(f"{name}: {p['name']} {got} differs from the serial estimate_offline "
                         f"run's mean {p['mean']!r}, std {p['stddev']!r}")
            if list(row["parameters"]) != [p["name"] for p in serial["parameters"]]:
                fail(f"{name}: parameters {list(row['parameters'])} differ from the serial run's")
            for key in ("healthy", "warnings", "samples"):
                if row[key] != serial[key]:
                    fail(f"{name}: {key} {row[key]!r} differs from the serial run's "
                         f"{serial[key]!r}")
            if serial["healthy"] and row["error"] is not None:
                fail(f"{name}: healthy in the serial run but an error row: {row['error']}")
            if not serial["healthy"] and not (row["error"] or "").startswith("unhealthy: "):
                fail(f"{name}: unhealthy in the serial run but error {row['error']!r}")
        elif row["error"] is None or row["parameters"]:
            fail(f"{name}: estimate_offline failed serially (exit {rc}) but the row is "
                 f"{row['error']!r} with parameters {row['parameters']}")
        if row["error"] is None:
            ok += 1
        else:
            errors += 1
            want = expected_errors.pop(name, None)
            if want is None:
                fail(f"{name}: unexpected error row: {row['error']}")
            if want not in row["error"]:
                fail(f"{name}: error {row['error']!r} does not say '{want}'")
        for spec in args.vehicle:
            pattern, vehicle = spec.split(":", 1)
            vehicle = os.path.abspath(vehicle) if vehicle else ""
            if fnmatch.fnmatch(name, pattern) and row["vehicle_file"] != vehicle:
                fail(f"{name}: vehicle_file {row['vehicle_file']!r}, expected {vehicle}")
        if (len(row["content_hash"]) != 64 or
                not re.fullmatch(r"0x[0-9a-f]{16}", row["config_hash"])):  # --config-hash
            fail(f"{name}: content/config hash missing")
    if expected_errors:
        fail(f"no error row for {sorted(expected_errors)}")
    if args.ok is not None and ok != args.ok or args.errors is not None and errors != args.errors:
        fail(f"{ok} result rows and {errors} error rows, expected {args.ok} and {args.errors}")
    with open(os.path.join(args.out, "results.csv"), newline="") as f:
        table = list(csv.DictReader(f))
    if [r["path"] for r in table] != paths:
        fail("results.csv rows differ from results.jsonl's")
    for r, row in zip(table, rows):
        for name, p in row["parameters"].items():
            if float(r[f"{name}_mean"]) != p["mean"] or float(r[f"{name}_std"]) != p["std"]:
                fail(f"results.csv {r['path']}: {name} differs from results.jsonl")
        if r["error"] != (row["error"] or ""):
            fail(f"results.csv {r['path']}: error differs from results.jsonl")
    for figure in ("report.md", "health.png", "fleet_parameters.png"):
        if not os.path.getsize(os.path.join(args.out, figure)):
            fail(f"{figure} is empty")
    print(f"{len(rows)} rows, one per bag in path order: {ok} result rows, {errors} error rows; "
          "every estimate equals the serial estimate_offline --bag run bit for bit")


def cmd_run(args):
    with open(os.path.join(args.out, "run_log.jsonl")) as f:
        last = json.loads(f.read().splitlines()[-1])
    if last["skipped"] != args.skipped or last["ran"] != args.ran:
        fail(f"the last run skipped {last['skipped']} and ran {last['ran']}, expected "
             f"{args.skipped} and {args.ran}")
    print(f"last run: skipped {last['skipped']}, ran {last['ran']}")


def cmd_worker(args):
    row = [r for r in rows_of(args.out) if r["path"] == os.path.abspath(args.bag)]
    if len(row) != 1:
        fail(f"{args.bag}: {len(row)} rows")
    if row[0]["worker"] == args.not_address:
        fail(f"{args.bag}: made by the killed worker {args.not_address}")
    print(f"{os.path.basename(args.bag)} (in flight on the killed worker {args.not_address}) "
          f"was redone by {row[0]['worker']}")


def cmd_rename_topics(args):
    import rosbag
    with rosbag.Bag(args.input) as source, rosbag.Bag(args.output, "w") as target:
        for topic, raw, stamp in source.read_messages(raw=True):
            target.write("/recorded_" + topic.strip("/").replace("/", "_"), raw, stamp, raw=True)


def main():
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("workers")
    p.add_argument("address")
    p.add_argument("n", type=int)
    p.add_argument("timeout", type=float)
    p = sub.add_parser("table")
    p.add_argument("out")
    p.add_argument("serial")
    p.add_argument("bags_file")
    p.add_argument("--ok", type=int)
    p.add_argument("--errors", type=int)
    p.add_argument("--error", action="append", default=[])
    p.add_argument("--vehicle", action="append", default=[])
    p = sub.add_parser("run")
    p.add_argument("out")
    p.add_argument("--skipped", type=int, required=True)
    p.add_argument("--ran", type=int, required=True)
    p = sub.add_parser("worker")
    p.add_argument("out")
    p.add_argument("bag")
    p.add_argument("not_address")
    p = sub.add_parser("rename_topics")
    p.add_argument("input")
    p.add_argument("output")
    args = parser.parse_args()
    {"workers": cmd_workers, "table": cmd_table, "run": cmd_run, "worker": cmd_worker,
     "rename_topics": cmd_rename_topics}[args.command](args)


if __name__ == "__main__":
    main()
