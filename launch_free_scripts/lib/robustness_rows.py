"""The scenarios of robustness.sh: data the estimator's model did not generate.

Usage: robustness_rows.py OUT_DIR [ROW ...]
Writes OUT_DIR/configs/<row>.yaml (config/speed_bump.yaml, or
config/load_change_course.yaml, with the row's changes) and prints one line
per row: "<row> <config> <samples> <methods>". Every row keeps the
estimator's settings of the paper config except where it says so; the truth
section is what differs. ES-MDA runs with config/vehicle_live.yaml's
inflation schedule and restarts (not its local covariance) and the one-step
filters with its re-linearisation in every row: the table judges the methods as they are configured for data from
a real vehicle (the paper configs keep [4, 4, 4, 4] and no re-linearisation;
what both cost there is measured in docs/studies/results.md).
"""
import os
import sys

import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ALL_METHODS = "one_step_paper,one_step_square_root,whole_set_square_root,es_mda,grid,enkf_small"
# Four uncertain parameters: no 4-D grid posterior (its coarse grid alone is 101^4 runs).
NO_GRID = "one_step_paper,one_step_square_root,whole_set_square_root,es_mda,enkf_small"

BETA = {"family": "beta", "alpha": 2.0, "beta": 2.0}
VEHICLE = yaml.safe_load(open(os.path.join(ROOT, "config", "speed_bump.yaml")))["vehicle"]
LIVE_FILTER = yaml.safe_load(open(os.path.join(ROOT, "config", "vehicle_live.yaml")))["filter"]

# Mismatched vehicle values: (row, keys, factor). Both sides change together.
MISMATCH = [
    ("spring_rate", ["spring_linear_left", "spring_linear_right"], 1.05),
    ("damping", ["damping_left", "damping_right"], 1.10),
    ("unsprung_mass", ["unsprung_mass_left", "unsprung_mass_right"], 1.10),
    ("tyre_stiffness", ["tyre_stiffness_left", "tyre_stiffness_right"], 1.10),
    ("bar_inertia", ["bar_inertia"], 1.10),
]


def base(name):
    return yaml.safe_load(open(os.path.join(ROOT, "config", name)))


def rows():
    out = []
    c = base("speed_bump.yaml")
    out.append(("exact", c, 100, ALL_METHODS))
    for row, keys, factor in MISMATCH:
        c = base("speed_bump.yaml")
        c["truth"]["vehicle"] = {k: VEHICLE[k] * factor for k in keys}
        out.append((row, c, 100, ALL_METHODS))
    c = base("speed_bump.yaml")
    c["truth"]["sensor"] = {"bias": [0.001, 0.001, 0.0, 0.0]}  # 1 mm on both displacements
    out.append(("sensor_bias", c, 100, ALL_METHODS))
    c = base("speed_bump.yaml")
    # An unmodelled floor (the filter keeps the paper's purely relative R).
    c["truth"]["sensor"] = {"noise_floor": [0.0005, 0.0005, 0.005, 0.005]}
    out.append(("noise_floor", c, 100, ALL_METHODS))
    c = base("speed_bump.yaml")
    # Irregular but correctly stamped sampling, 10 % lost: the model explains it.
    c["truth"]["timing"] = {"jitter": 0.003, "drop_fraction": 0.1, "seed": 3}
    out.append(("jitter_drops", c, 100, ALL_METHODS))
    c = base("load_change_course.yaml")
    out.append(("load_change", c, 450, ALL_METHODS))
    c = base("load_change_course.yaml")
    c["filter"] = {"reopen": {"mode": "width", "width": 0.5, "after": 3}}
    out.append(("load_change_reopen", c, 450, "one_step_paper,one_step_square_root"))
    c = base("load_change_course.yaml")
    c["filter"] = {"drift": [2.0, 0.0]}  # M may change by 2 kg / sqrt(s)
    out.append(("load_change_drift", c, 450, "one_step_paper,one_step_square_root"))
    c = base("load_change_course.yaml")
    c["filter"] = {"drift": [2.0, 0.0], "reopen": {"mode": "width", "width": 0.5, "after": 3}}
    out.append(("load_change_drift_reopen", c, 450, "one_step_paper,one_step_square_root"))
    # The mismatch rows again, the mismatched values declared uncertain
    # (+-2 x the error, so the truth sits at xi = 0.5).
    for row, keys, factor in MISMATCH:
        c = base("speed_bump.yaml")
        for k in keys:
            c["uncertain"].append({"name": k, "nominal": VEHICLE[k],
                                   "relative_range": 2.0 * (factor - 1.0), "germ": dict(BETA)})
        c["truth"]["xi"] = c["truth"]["xi"] + [0.5] * len(keys)
        n = len(c["uncertain"])
        # 4 S at p = 4: with 2 S, ES-MDA's surrogate error put it 4.5 std off on
        # exact data of the declared bar inertia (measured); the point set, not
        # the update, was the limit.
        c["collocation"]["points"] = 280 if n == 4 else 140
        out.append((row + "_declared", c, 100, NO_GRID))
    return out


def main():
    out_dir, wanted = sys.argv[1], set(sys.argv[2:])
    os.makedirs(os.path.join(out_dir, "configs"), exist_ok=True)
    for name, config, samples, methods in rows():
        if wanted and name not in wanted:
            continue
        for key in ("es_mda", "relinearize"):
            config.setdefault("filter", {})[key] = dict(LIVE_FILTER[key])
        # The passes and their restarts; the local covariance (vehicle_live.yaml's
        # es_mda.covariance) is for its 13 tolerances' ridge and measured there
        # (docs/studies/real_vehicle_reference.md §5), not on these two- to four-parameter rows.
        config["filter"]["es_mda"].pop("covariance", None)
        path = os.path.join(out_dir, "configs", name + ".yaml")
        with open(path, "w") as f:
            f.write("# robustness.sh row '%s' (generated by lib/robustness_rows.py)\n" % name)
            yaml.safe_dump(config, f, sort_keys=False)
        print(name, path, samples, methods)


if __name__ == "__main__":
    main()
