"""report.md's numbers: counts, the fleet distribution, the vehicle table."""
from pc_ekf_fleet.journal import make_row
from pc_ekf_fleet.report import kind_of, report_text, stats


def row(path, vehicle, mean=None, healthy=True, error=None):
    bag = {"path": path, "content_hash": "c" * 64, "config_hash": "0x" + "1" * 16,
           "vehicle_file": vehicle, "method": "one_step"}
    if mean is None:
        return make_row(bag, {"error": error})
    return make_row(bag, {"estimate": {"healthy": healthy, "warnings": ["w"], "samples": 10,
                                       "parameters": [{"name": "added_mass", "mean": mean,
                                                       "stddev": 2.0}]}})


def test_stats_mean_sample_std_median():
    assert stats([3.0, 1.0, 2.0]) == (2.0, 1.0, 1.0, 2.0, 3.0)
    assert stats([1.0, 2.0, 3.0, 10.0])[3] == 2.5
    assert stats([5.0]) == (5.0, 0.0, 5.0, 5.0, 5.0)


def test_report_counts_healthy_unhealthy_and_failed():
    rows = [row("/a.bag", "", 200.0), row("/b.bag", "", 202.0),
            row("/c.bag", "/v/van.yaml", 300.0, healthy=False),
            row("/d.bag", "/v/van.yaml", error="bad input: no road")]
    assert [kind_of(r) for r in rows] == ["healthy", "healthy", "unhealthy", "failed"]
    run = {"started": "2026-01-01T00:00:00Z", "scheduler": "LocalCluster", "workers": 2,
           "bags": 4, "skipped": 0, "ran": 4, "errors": 2, "wall_s": 3.0, "estimate_s": 2.0,
           "bags_per_s": 2.0, "interrupted": False}
    text = report_text(rows, [run], "/cfg.yaml", "one_step", None, {"vehicles": {}})
    assert "# Fleet estimate: 4 bags" in text
    assert "- rows: 2 estimated and healthy, 2 error rows (1 unhealthy with an estimate, " \
           "1 without one)" in text
    assert "health fraction: 2/4 = 0.500" in text
    # Only healthy rows make the fleet distribution: 200 and 202.
    assert "| M (kg) | 2 | 201 | 1.414 | 200 | 201 | 202 | 2 |" in text
    assert "| `(config's vehicle)` | 2 | 2 | 0 | 0 | 201 |" in text
    assert "| `/v/van.yaml` | 2 | 0 | 1 | 1 | - |" in text
    assert "| `/d.bag` | bad input: no road |" in text
    assert "| 2026-01-01T00:00:00Z | LocalCluster | 2 | 4 | 0 | 4 | 2 | 3.0 | 2.0 | 2.00 |" in text
