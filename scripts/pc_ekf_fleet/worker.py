"""The task a Dask worker runs: estimate_offline --bag on one bag.

Only the standard library is imported at the top: the client sends this
module to the workers by value (scheduling.py), so a worker needs no copy of
the package, only python3-distributed, python3-rosbag and estimate_offline.
"""
import json
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time

# What a worker keeps of estimate_offline's stderr (bytes, its end): the
# last line names a failure, and a long record's progress lines (enkf: one
# per 10 samples) are not held in memory.
STDERR_TAIL = 64 * 1024


def _worker_address():
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):
        return f"{socket.gethostname()}:{os.getpid()}"


def _bag_start_stamp(path):
    """The bag's first stamp (s), or None when rosbag cannot read it."""
    try:
        import rosbag
        with rosbag.Bag(path) as bag:
            return bag.get_start_time()
    except Exception:  # noqa: BLE001 - a corrupt bag is reported by estimate_offline
        return None


def last_line(text):
    lines = [l.strip() for l in text.splitlines() if l.strip()]
    return lines[-1] if lines else "(no output)"


def file_tail(f, limit=STDERR_TAIL):
    """The last `limit` bytes of the binary file f, as text."""
    f.seek(0, os.SEEK_END)
    f.seek(max(0, f.tell() - limit))
    return f.read().decode("utf-8", "replace")


def installed_estimate_offline():
    """This host's estimate_offline: on PATH, or in the sourced catkin
    workspaces (install or devel space), or None."""
    found = shutil.which("estimate_offline")
    if found:
        return found
    try:
        from catkin.find_in_workspaces import find_in_workspaces
        found = find_in_workspaces(["libexec"], project="pc_ekf", path="estimate_offline",
                                   first_match_only=True)
    except ImportError:
        found = []
    return found[0] if found else None


def estimate_bag(task):
    """Runs on a worker: estimate_offline on one bag. Never raises; a failure
    comes back as result["error"]."""
    result = {"worker": _worker_address(), "start_stamp": _bag_start_stamp(task["path"]),
              "estimate": None, "error": None}
    exe = task["exe"]
    if not os.access(exe, os.X_OK):  # another host, another install path
        exe = installed_estimate_offline() or exe
    cmd = [exe, "--config", task["config"], "--bag", task["path"], "--method", task["method"]]
    start = time.monotonic()
    # stderr to a file, of which only the end is read (STDERR_TAIL); stdout
    # is the one JSON object.
    with tempfile.TemporaryFile() as err_file:
        _run(cmd, exe, task["timeout"], err_file, result)
    result["wall_time_s"] = time.monotonic() - start
    return result


def _run(cmd, exe, timeout, err_file, result):
    try:
        proc = subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                              stderr=err_file, timeout=timeout, universal_newlines=True)
    except subprocess.TimeoutExpired:
        result["error"] = (f"timeout: estimate_offline ran longer than {timeout:g} s "
                           "(killed)")
    except OSError as err:
        result["error"] = f"cannot run estimate_offline ({exe}): {err.strerror}"
    else:
        if proc.returncode == 2:
            result["error"] = f"bad input: {last_line(file_tail(err_file))}"
        elif proc.returncode < 0:
            result["error"] = (f"estimate_offline killed by signal "
                               f"{signal.Signals(-proc.returncode).name}")
        elif proc.returncode != 0:
            result["error"] = (f"estimate_offline exited with status {proc.returncode}: "
                               f"{last_line(file_tail(err_file))}")
        else:
            try:
                result["estimate"] = json.loads(proc.stdout)
            except ValueError:
                result["error"] = ("estimate_offline printed no JSON object: "
                                   f"{last_line(proc.stdout)}")
