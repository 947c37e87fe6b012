"""Which bags a run estimates (resume, --redo-errors), and the vehicle of a
bag; without Dask."""
import subprocess
import sys

from pc_ekf_fleet.inputs import find_bags, load_vehicle_map, vehicle_for
from pc_ekf_fleet.journal import make_row
from pc_ekf_fleet.scheduling import plan, previous_rows, row_key

CONFIGS = {"": ("/cfg.yaml", "0x" + "a" * 16), "/v/van.yaml": ("/out/van.yaml", "0x" + "b" * 16)}
ENTRIES = [("van_*.bag", "/v/van.yaml")]


def plan_of(previous, method="one_step", redo_errors=False, hashes=None):
    paths = ["/bags/other.bag", "/bags/van_1.bag", "/bags/van_2.bag"]
    hashes = hashes or {p: p[-5] * 64 for p in paths}
    return plan(paths, ENTRIES, CONFIGS, hashes, previous, method, redo_errors)


def test_a_fresh_run_runs_every_bag_with_its_vehicles_config():
    bags, rows, todo = plan_of({})
    assert rows == {} and [b["path"] for b in todo] == [b["path"] for b in bags]
    assert [b["config_hash"] for b in bags] == ["0x" + "a" * 16] + ["0x" + "b" * 16] * 2
    assert bags[1]["config"] == "/out/van.yaml" and bags[0]["vehicle_file"] == ""


def test_resume_skips_same_content_config_and_method_only():
    bags, _, _ = plan_of({})
    done = make_row(bags[1], {"estimate": {"healthy": True, "parameters": []}})
    failed = make_row(bags[2], {"error": "timeout: killed"})
    previous = {row_key(done): done, row_key(failed): failed}
    _, rows, todo = plan_of(previous)
    assert sorted(rows) == ["/bags/van_1.bag", "/bags/van_2.bag"]
    assert [b["path"] for b in todo] == ["/bags/other.bag"]
    _, rows, todo = plan_of(previous, redo_errors=True)
    assert [b["path"] for b in todo] == ["/bags/other.bag", "/bags/van_2.bag"]
    _, rows, todo = plan_of(previous, method="es_mda")  # another method: all again
    assert rows == {} and len(todo) == 3


def test_an_unreadable_bag_is_an_error_row_not_a_task():
    paths = ["/bags/other.bag", "/bags/van_1.bag", "/bags/van_2.bag"]
    hashes = {p: "1" * 64 for p in paths}
    hashes["/bags/van_1.bag"] = OSError("cannot read the bag: Permission denied")
    _, rows, todo = plan_of({}, hashes=hashes)
    assert rows["/bags/van_1.bag"]["error"] == "cannot read the bag: Permission denied"
    assert rows["/bags/van_1.bag"]["content_hash"] == ""
    assert len(todo) == 2


def test_previous_rows_the_journal_wins_over_superseded(tmp_path):
    row = {"content_hash": "c", "config_hash": "h", "method": "m", "error": None}
    (tmp_path / "superseded.jsonl").write_text('{"content_hash": "c", "config_hash": "h", '
                                               '"method": "m", "error": "timeout"}\n')
    (tmp_path / "results.jsonl").write_text(
        '{"content_hash": "c", "config_hash": "h", "method": "m", "error": null}\n')
    assert previous_rows(str(tmp_path)) == {("c", "h", "m"): row}


def test_vehicle_patterns_name_or_path_first_match(tmp_path):
    (tmp_path / "map.yaml").write_text('"van_*.bag": vehicles/van.yaml\n'
                                       '"*/2025/*": /abs/old.yaml\n"*": any.yaml\n')
    entries = load_vehicle_map(str(tmp_path / "map.yaml"))
    assert entries[0] == ("van_*.bag", str(tmp_path / "vehicles" / "van.yaml"))
    assert vehicle_for("/x/2025/van_3.bag", entries) == str(tmp_path / "vehicles" / "van.yaml")
    assert vehicle_for("/x/2025/truck.bag", entries) == "/abs/old.yaml"
    assert vehicle_for("/x/truck.bag", entries[:2]) == ""


def test_bags_from_folders_and_globs_sorted(tmp_path):
    for name in ("b/2.bag", "a/1.bag", "a/notes.txt"):
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_text("x")
    assert find_bags([str(tmp_path / "b"), str(tmp_path / "a" / "*.bag")]) == \
        [str(tmp_path / "a" / "1.bag"), str(tmp_path / "b" / "2.bag")]


def test_dask_is_not_imported_until_bags_run():
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import pc_ekf_fleet.cli; "
            "print(any(m.split('.')[0] in ('distributed', 'dask') for m in sys.modules))")
    scripts = __import__("os").path.dirname(__import__("pc_ekf_fleet").__path__[0])
    out = subprocess.run([sys.executable, "-c", code, scripts], stdout=subprocess.PIPE,
                         universal_newlines=True, check=True).stdout
    assert out.strip() == "False"
