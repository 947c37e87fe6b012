"""Which bags a run estimates, and the Dask run that estimates them.

Dask (python3-distributed) is imported in run_on_dask only: planning, the
journal and the report work without it.
"""
import os
import sys
import time

from pc_ekf_fleet import worker
from pc_ekf_fleet.inputs import FleetError, vehicle_for
from pc_ekf_fleet.journal import make_row, read_rows


def row_key(row):
    """What decides a row's numbers besides the estimator: the bag's content,
    the config's identity and the method."""
    return (row["content_hash"], row["config_hash"], row["method"])


def previous_rows(out):
    """{row_key: row} of DIR's rows (superseded.jsonl, then results.jsonl: the
    last row wins; superseded rows count too, e.g. after a run on fewer bags)."""
    previous = {}
    for name in ("superseded.jsonl", "results.jsonl"):
        for row in read_rows(os.path.join(out, name)):
            previous[row_key(row)] = row
    return previous


def plan(paths, entries, configs, hashes, previous, method, redo_errors):
    """(bags, rows, todo): every bag of the run ({path, content_hash,
    config_hash, vehicle_file, method, config}); the rows known without
    running (an unreadable bag's error row, a previous row of the same key,
    not an error row with redo_errors) by path; the bags to run, in path
    order. configs: {vehicle file: (config path, config hash)}; hashes:
    {path: sha256 or an OSError}."""
    bags, rows, todo = [], {}, []
    for path in paths:
        vehicle = vehicle_for(path, entries)
        config, digest = configs[vehicle]
        content = hashes[path]
        unreadable = isinstance(content, OSError)
        bag = {"path": path, "content_hash": "" if unreadable else content,
               "config_hash": digest, "vehicle_file": vehicle, "method": method,
               "config": config}
        bags.append(bag)
        if unreadable:
            rows[path] = make_row(bag, {"error": str(content)})
            continue
        old = previous.get(row_key(bag))
        if old is not None and not (redo_errors and old["error"]):
            rows[path] = dict(old, path=path)
        else:
            todo.append(bag)
    return bags, rows, todo


def open_client(scheduler, workers):
    import logging
    from distributed import Client, LocalCluster
    if scheduler:
        try:
            client = Client(scheduler, timeout=30)
        except (OSError, TimeoutError) as err:
            raise FleetError(f"--scheduler {scheduler}: cannot connect ({err})") from err
        return client, None
    cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                           processes=True, host="127.0.0.1", scheduler_port=0,
                           # their HTTP servers on the loopback too (no bokeh dashboard)
                           dashboard_address="127.0.0.1:0",
                           worker_dashboard_address="127.0.0.1:0", silence_logs=logging.ERROR)
    return Client(cluster), cluster


class DaskRun:
    """What run_on_dask did: workers, bags ran, error rows, when the first
    task was submitted (time.monotonic) and whether it was interrupted."""

    def __init__(self):
        self.workers = self.ran = self.errors = 0
        self.submitted = time.monotonic()
        self.interrupted = False


def run_on_dask(todo, task_of, scheduler, workers, on_row):
    """Estimates the bags todo on Dask, one task each (worker.estimate_bag of
    task_of(bag)); on_row(row) as each finishes. A task whose worker died
    too often becomes an error row. Returns a DaskRun."""
    try:
        import cloudpickle
        from distributed import as_completed
    except ImportError as err:
        raise FleetError(f"Dask is not installed ({err}): estimate_fleet needs "
                         "python3-distributed (docs/fleet.md)") from err
    # The workers need not import this package: the task goes by value.
    cloudpickle.register_pickle_by_value(worker)
    done = DaskRun()
    client, cluster = open_client(scheduler, workers)
    try:
        done.workers = len(client.scheduler_info()["workers"])
        done.submitted = time.monotonic()
        futures = {}
        for bag in todo:
            future = client.submit(worker.estimate_bag, task_of(bag), pure=False,
                                   key=f"estimate_bag-{os.path.basename(bag['path'])}-"
                                       f"{os.urandom(6).hex()}")
            futures[future] = bag
        for future in as_completed(futures):
            bag = futures[future]
            if future.status == "finished":
                result = future.result()
            else:
                err = future.exception()
                reason = (f"the Dask worker running it died {type(err).__name__}: {err}"
                          if type(err).__name__ == "KilledWorker"
                          else f"task failed on Dask: {type(err).__name__}: {err}")
                result = {"error": reason}
            row = make_row(bag, result)
            on_row(row)
            done.ran += 1
            done.errors += 1 if row["error"] else 0
            future.release()
    except KeyboardInterrupt:
        done.interrupted = True
        print("estimate_fleet: interrupted; rows so far kept", file=sys.stderr)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return done
