"""DIR/results.jsonl and what is made from it: a row per bag, appended as it
finishes, the final table sorted by path, superseded rows kept, results.csv."""
import csv
import io
import json
import os
import sys
import time

ROW_FIELDS = ["path", "content_hash", "config_hash", "vehicle_file", "method"]
TAIL_FIELDS = ["healthy", "warnings", "samples", "start_stamp", "wall_time_s", "worker",
               "error"]


def atomic_write(path, text):
    tmp = f"{path}.tmp.{os.getpid()}"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


class Journal:
    """DIR/results.jsonl opened for appending: one write() of one whole line
    per row, then fsync (a kill leaves at most a torn last line, dropped on
    reading)."""

    def __init__(self, path):
        self.fd = os.open(path, os.O_RDWR | os.O_APPEND | os.O_CREAT, 0o644)
        size = os.fstat(self.fd).st_size
        # A torn last line (a killed run) is closed, so the next row starts a
        # line of its own.
        if size and os.pread(self.fd, 1, size - 1) != b"\n":
            os.write(self.fd, b"\n")

    def append(self, row):
        line = (json.dumps(row) + "\n").encode()
        if os.write(self.fd, line) != len(line):
            raise OSError(f"short write to results.jsonl ({len(line)} bytes)")
        os.fsync(self.fd)

    def close(self):
        os.close(self.fd)


def read_rows(path):
    """Rows of a results.jsonl; a torn or unreadable line is skipped (said)."""
    rows = []
    if not os.path.exists(path):
        return rows
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    for number, line in enumerate(lines[:-1], 1):
        try:
            rows.append(json.loads(line))
        except ValueError:
            print(f"estimate_fleet: {path}:{number}: unreadable row skipped: {line[:60]}",
                  file=sys.stderr)
    if lines[-1]:
        print(f"estimate_fleet: {path}: torn last line (a killed run) dropped", file=sys.stderr)
    return rows


def make_row(bag, result):
    """The row of a bag ({ROW_FIELDS}) from its task's result (worker.py)."""
    estimate = result.get("estimate") or {}
    error = result.get("error")
    if estimate and not estimate.get("healthy", False) and not error:
        error = "unhealthy: " + ("; ".join(estimate.get("warnings", [])) or "(no warning)")
    row = {k: bag[k] for k in ROW_FIELDS}
    row["parameters"] = {p["name"]: {"mean": p["mean"], "std": p["stddev"]}
                         for p in estimate.get("parameters", [])}
    row.update(healthy=estimate.get("healthy") if estimate else None,
               warnings=estimate.get("warnings", []), samples=estimate.get("samples"),
               start_stamp=result.get("start_stamp"), wall_time_s=result.get("wall_time_s"),
               worker=result.get("worker"), error=error,
               finished=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()))
    return row


def write_final(out, final):
    """Rewrites DIR/results.jsonl as the rows `final` (one per bag, in path
    order); journal rows not among them (an error row redone, another config,
    a changed bag) are appended to superseded.jsonl, not dropped."""
    results_path = os.path.join(out, "results.jsonl")
    final_lines = [json.dumps(r) + "\n" for r in final]
    chosen = set(final_lines)
    superseded = [json.dumps(r) + "\n" for r in read_rows(results_path)]
    superseded = [line for line in superseded if line not in chosen]
    if superseded:
        with open(os.path.join(out, "superseded.jsonl"), "a", encoding="utf-8") as f:
            f.writelines(superseded)
            f.flush()
            os.fsync(f.fileno())
    atomic_write(results_path, "".join(final_lines))
    atomic_write(os.path.join(out, "results.csv"), csv_text(final))


def csv_text(rows):
    """The rows as CSV: a <name>_mean and <name>_std column per parameter,
    floats by repr (they read back bit for bit), lists joined by ' | '."""
    names = list(dict.fromkeys(n for r in rows for n in r["parameters"]))
    header = ROW_FIELDS + [f"{n}_{s}" for n in names for s in ("mean", "std")] + TAIL_FIELDS

    def cell(value):
        if value is None:
            return ""
        if isinstance(value, float):
            return repr(value)
        if isinstance(value, list):
            return " | ".join(value)
        return value

    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    for r in rows:
        values = [r[k] for k in ROW_FIELDS]
        for n in names:
            p = r["parameters"].get(n, {})
            values += [p.get("mean"), p.get("std")]
        values += [r[k] for k in TAIL_FIELDS]
        writer.writerow([cell(v) for v in values])
    return buffer.getvalue()
