"""The task a worker runs (worker.estimate_bag), on a stand-in for
estimate_offline: the JSON on stdout is the estimate, a failure is named by
the last line of stderr, and of a long stderr (a long record's progress)
only the end is read."""
import os
import stat
import textwrap

from pc_ekf_fleet import worker


def fake_offline(tmp_path, body):
    exe = tmp_path / "estimate_offline"
    exe.write_text("#!/bin/sh\n" + textwrap.dedent(body))
    exe.chmod(exe.stat().st_mode | stat.S_IXUSR)
    return str(exe)


def task(exe, timeout=60.0):
    return {"exe": exe, "config": "/cfg.yaml", "path": "/no/such.bag", "method": "enkf",
            "timeout": timeout}


def test_the_estimate_is_stdouts_json_whatever_stderr_held(tmp_path):
    exe = fake_offline(tmp_path, """\
        i=0
        while [ $i -lt 20000 ]; do echo "[progress] enkf: sample $i/20000" >&2; i=$((i+1)); done
        echo '{"method": "enkf", "healthy": true}'
        """)
    result = worker.estimate_bag(task(exe))
    assert result["error"] is None
    assert result["estimate"] == {"method": "enkf", "healthy": True}


def test_a_failure_is_named_by_the_last_line_of_a_long_stderr(tmp_path):
    exe = fake_offline(tmp_path, """\
        i=0
        while [ $i -lt 20000 ]; do echo "[progress] enkf: sample $i/20000" >&2; i=$((i+1)); done
        echo "estimate_offline: error: the bag's last message is torn" >&2
        exit 1
        """)
    result = worker.estimate_bag(task(exe))
    assert result["estimate"] is None
    assert result["error"] == ("estimate_offline exited with status 1: "
                               "estimate_offline: error: the bag's last message is torn")
    bad = fake_offline(tmp_path, """\
        echo "estimate_offline: --config is required" >&2
        exit 2
        """)
    assert worker.estimate_bag(task(bad))["error"] == "bad input: estimate_offline: --config is required"


def test_only_the_end_of_stderr_is_read(tmp_path):
    path = tmp_path / "stderr"
    path.write_bytes(b"x" * (3 * worker.STDERR_TAIL) + b"\nlast words\n")
    with open(path, "rb") as f:
        tail = worker.file_tail(f)
    assert len(tail) == worker.STDERR_TAIL
    assert worker.last_line(tail) == "last words"
    assert os.path.getsize(path) > len(tail)
