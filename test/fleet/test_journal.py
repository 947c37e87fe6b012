"""results.jsonl: rows survive a kill, the final table is sorted and keeps
what it replaces, the CSV reads back bit for bit."""
import csv
import io
import json
import os

from pc_ekf_fleet.journal import Journal, csv_text, make_row, read_rows, write_final


def bag(path, **extra):
    return dict({"path": path, "content_hash": "c" * 64, "config_hash": "0x" + "1" * 16,
                 "vehicle_file": "", "method": "one_step"}, **extra)


def estimate(healthy=True, warnings=(), mean=200.1):
    return {"healthy": healthy, "warnings": list(warnings), "samples": 10,
            "parameters": [{"name": "added_mass", "mean": mean, "stddev": 0.1 + 0.2}]}


def test_a_torn_last_line_is_closed_and_dropped(tmp_path, capsys):
    path = str(tmp_path / "results.jsonl")
    journal = Journal(path)
    journal.append({"path": "/a.bag"})
    journal.close()
    with open(path, "a") as f:
        f.write('{"path": "/b.b')  # a run killed mid-write
    journal = Journal(path)
    journal.append({"path": "/c.bag"})
    journal.close()
    assert [r["path"] for r in read_rows(path)] == ["/a.bag", "/c.bag"]
    assert "unreadable row skipped" in capsys.readouterr().err


def test_a_torn_line_at_the_end_is_reported(tmp_path, capsys):
    path = tmp_path / "results.jsonl"
    path.write_text('{"path": "/a.bag"}\n{"pa')
    assert [r["path"] for r in read_rows(str(path))] == ["/a.bag"]
    assert "torn last line" in capsys.readouterr().err


def test_unhealthy_estimate_is_an_error_row_with_its_estimate():
    row = make_row(bag("/u.bag"), {"estimate": estimate(False, ["windowed NIS 9.1"]),
                                   "wall_time_s": 1.5, "worker": "w"})
    assert row["error"] == "unhealthy: windowed NIS 9.1"
    assert row["healthy"] is False
    assert row["parameters"] == {"added_mass": {"mean": 200.1, "std": 0.1 + 0.2}}
    failed = make_row(bag("/f.bag"), {"error": "bad input: x"})
    assert failed["error"] == "bad input: x" and failed["parameters"] == {}
    assert failed["healthy"] is None


def test_final_table_sorted_and_replaced_rows_superseded(tmp_path):
    out = str(tmp_path)
    old = make_row(bag("/b.bag"), {"error": "timeout: 0.01 s"})
    journal = Journal(os.path.join(out, "results.jsonl"))
    journal.append(old)
    new_b = make_row(bag("/b.bag"), {"estimate": estimate()})
    new_a = make_row(bag("/a.bag"), {"estimate": estimate(mean=199.0)})
    journal.append(new_b)
    journal.append(new_a)
    journal.close()
    write_final(out, [new_a, new_b])
    assert read_rows(os.path.join(out, "results.jsonl")) == [new_a, new_b]
    assert read_rows(os.path.join(out, "superseded.jsonl")) == [old]


def test_csv_floats_read_back_bit_for_bit():
    rows = [make_row(bag("/a.bag"), {"estimate": estimate(mean=1.0 / 3.0)}),
            make_row(bag("/b.bag"), {"error": "bad input: y"})]
    table = list(csv.DictReader(io.StringIO(csv_text(rows))))
    assert float(table[0]["added_mass_mean"]) == 1.0 / 3.0
    assert float(table[0]["added_mass_std"]) == 0.1 + 0.2
    assert table[1]["added_mass_mean"] == "" and table[1]["error"] == "bad input: y"
    assert json.loads(json.dumps(rows[0]))["parameters"]["added_mass"]["mean"] == 1.0 / 3.0
