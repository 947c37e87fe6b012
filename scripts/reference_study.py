#!/usr/bin/python3
"""The filters against the converged reference posterior at n = 15
(docs/studies/real_vehicle_reference.md §5), or on the full car (--full-car, §3).

  /usr/bin/python3 scripts/reference_study.py BIN_DIR [--samples 25000] [--records 1,2,...]
      [--override YAML] [--full-car [--config FILE] [--exact-body]]

Each record is test/benchmarks/live_n15.yaml (vehicle_live.yaml's payload, 13
tolerances and design on the speed bump, N = 100 over 3 s, 1 % noise, no
sensor floor) with its own truth: a load and a vehicle whose nine spring,
damper, unsprung, tyre and inertia values are off by up to 6 %. For each,
bench_mcmc_reference runs one-step and ES-MDA and the conditional-Laplace
reference (4 batches of --samples draws) on the same likelihood. Prints per
record the reference's M and d_CG (mean +- std), its largest R-hat, smallest
ESS and time, and for each filter the std ratio (filter / reference) and the
mean's offset in reference std, for M and d_CG. --override: YAML merged into
every record's config (e.g. "filter: {relinearize: {shrink: 0.3}}").

--full-car: config/full_car_live.yaml (or --config FILE) as shipped but the
road (the full car's oblique speed bump, N = 100 over 3 s) and the noise (1 %
of the reading, no sensor floor: the paper's R rule, in the data and in the
filters), on six loaded records: three vehicles (D, E, F) whose nine spring,
damper, unsprung, tyre and inertia values are off by up to 6 % and whose body
mass is off by 1-2.5 % (--exact-body: the body mass as configured), loads
150 kg at x 1.0 m, y 0.62 m and 280 kg at x 1.6 m, y 0.90 m. Prints the same
columns for M and y, then per record and method the error of M, x and y in
the filter's own reported std and whether it is healthy, and a summary per
method: covered (all three within 3 reported std), healthy, silent (healthy
and not covered), the reported std of M, x and y. --no-reference: the
filters only (estimate_offline; seconds per record instead of minutes), the
reference columns then the truth."""
import argparse, json, os, re, statistics, subprocess, sys, tempfile

import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Vehicles: the nine values' relative offsets (inside vehicle_live.yaml's tolerances).
NOMINAL = {"unsprung_mass_left": 36.26, "unsprung_mass_right": 36.26, "damping_left": 710.70,
           "damping_right": 710.70, "spring_linear_left": 19357.2,
           "spring_linear_right": 19357.2, "bar_inertia": 63.3316,
           "tyre_stiffness_left": 96319.76, "tyre_stiffness_right": 96319.76}
VEHICLES = {
    "A": [0.04, -0.03, -0.05, 0.06, 0.03, -0.04, 0.05, -0.02, 0.04],
    "B": [-0.04, 0.03, 0.05, -0.06, -0.03, 0.04, -0.05, 0.02, -0.04],
    "C": [0.06, 0.06, -0.02, -0.02, -0.05, -0.05, 0.03, 0.01, 0.01],
}
# (M kg, d_CG m, vehicle, noise seed)
RECORDS = [(223.26, 0.6882, "A", 1), (150.0, 0.62, "A", 2), (280.0, 0.90, "B", 3),
           (150.0, 0.62, "B", 4), (280.0, 0.90, "C", 5), (200.0, 0.762, "C", 6)]
# The full car: relative offsets of the vehicle values (the nine inside
# full_car_live.yaml's tolerances, the body mass inside 3 %).
CAR_VEHICLES = {
    "D": {"spring_linear_front": 0.04, "spring_linear_rear": -0.03, "damping_front": -0.05,
          "damping_rear": 0.06, "tyre_stiffness": -0.02, "unsprung_mass_front": 0.04,
          "unsprung_mass_rear": -0.03, "roll_inertia": 0.05, "pitch_inertia": -0.04,
          "body_mass": 0.02},
    "E": {"spring_linear_front": -0.05, "spring_linear_rear": 0.04, "damping_front": 0.06,
          "damping_rear": -0.04, "tyre_stiffness": 0.03, "unsprung_mass_front": -0.06,
          "unsprung_mass_rear": 0.05, "roll_inertia": -0.03, "pitch_inertia": 0.06,
          "body_mass": -0.025},
    "F": {"spring_linear_front": 0.06, "spring_linear_rear": 0.05, "damping_front": -0.02,
          "damping_rear": -0.03, "tyre_stiffness": 0.04, "unsprung_mass_front": 0.02,
          "unsprung_mass_rear": 0.06, "roll_inertia": 0.01, "pitch_inertia": -0.06,
          "body_mass": 0.01},
}
# (M kg, x m, y m, vehicle, noise seed)
CAR_RECORDS = [(150.0, 1.0, 0.62, "D", 1), (280.0, 1.6, 0.90, "D", 2),
               (150.0, 1.0, 0.62, "E", 3), (280.0, 1.6, 0.90, "E", 4),
               (150.0, 1.0, 0.62, "F", 5), (280.0, 1.6, 0.90, "F", 6)]
CAR_LOAD = ["added_mass", "added_mass_x", "added_mass_y"]


def merge(base, extra):
    for key, value in extra.items():
        if isinstance(value, dict) and isinstance(base.get(key), dict):
            merge(base[key], value)
        else:
            base[key] = value
    return base


def record_config(mass, position, vehicle, seed, override=None):
    text = open(os.path.join(ROOT, "test", "benchmarks", "live_n15.yaml")).read()
    start = text.index("truth:")
    truth = "truth:\n  xi: [%.10f, %.10f]\n  seed: %d\n  vehicle:\n" % (
        (mass / 200.0 - 1.0) / 0.5, (position / 0.762 - 1.0) / 0.25, seed)
    for (name, value), off in zip(NOMINAL.items(), VEHICLES[vehicle]):
        truth += "    %s: %.6g\n" % (name, value * (1.0 + off))
    if not override:
        return text[:start] + truth
    return yaml.safe_dump(merge(yaml.safe_load(text[:start] + truth), yaml.safe_load(override)))


def car_record_config(config, load, vehicle, seed, exact_body, override=None):
    c = yaml.safe_load(open(config))
    c["road"] = {"source": "speed_bump"}
    c["sampling"] = {"samples": 100, "duration": 3.0}
    m = c["measurement"]
    for key in ("sensor_std", "r_relative"):
        m.pop(key, None)
    m.update({"r_rule": "paper", "r_relative": 0.01, "noise_relative": 0.01, "noise_floor": 0.0})
    c.setdefault("pdf", {})["draws"] = 1000
    xi = []
    for value, u in zip(load, c["uncertain"][:3]):
        xi.append((value / u["nominal"] - 1.0) / u["relative_range"])
    truth = {"xi": xi, "seed": seed, "vehicle": {}}
    for name, off in CAR_VEHICLES[vehicle].items():
        if name == "body_mass" and exact_body:
            continue
        truth["vehicle"][name] = c["vehicle"][name] * (1.0 + off)
    c["truth"] = truth
    if override:
        merge(c, yaml.safe_load(override))
    return yaml.safe_dump(c)


def run(bin_dir, path, samples):
    env = dict(os.environ, PC_EKF_MCMC_CONFIG=path, PC_EKF_MCMC_SAMPLER="conditional_laplace",
               PC_EKF_MCMC_CHAINS="4", PC_EKF_MCMC_SAMPLES=str(samples))
    out = subprocess.run([os.path.join(bin_dir, "bench_mcmc_reference")], env=env,
                         capture_output=True, text=True, check=True).stdout
    rows = {}
    for line in out.splitlines():
        # parameter, ref mean, std, R-hat, ESS, lapl/ref | 1step dz, std/ref | ESMDA dz,
        # std/ref | truth dz [| mode dz]
        f = line.split()
        if len(f) >= 14 and f[6] == f[9] == f[12] == "|":
            try:
                rows[f[0]] = [float(x) for x in (f[1:6] + f[7:9] + f[10:12] + f[13:14])]
            except ValueError:
                pass  # the header
    seconds = float(re.search(r"simulations, ([0-9.]+) s;", out).group(1))
    health = re.search(r"one-step [0-9.]+ s healthy (\d), ES-MDA [0-9.]+ s healthy (\d)", out)
    return rows, seconds, (int(health.group(1)), int(health.group(2)))


def filters_only(bin_dir, path, truth):
    """estimate_offline, one-step and ES-MDA, without the reference: rows as run()'s
    with the truth as the reference (mean = truth, std = 1)."""
    rows, healthy = {p: [t, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0] for p, t in
                     zip(CAR_LOAD, truth)}, []
    for method, dz in (("one_step", 5), ("es_mda", 7)):
        out = json.loads(subprocess.run(
            [os.path.join(bin_dir, "estimate_offline"), "--config", path, "--method", method],
            capture_output=True, text=True, check=True).stdout)
        healthy.append(int(out["healthy"]))
        for p in out["parameters"]:
            if p["name"] in rows:
                rows[p["name"]][dz] = p["mean"] - rows[p["name"]][0]
                rows[p["name"]][dz + 1] = p["stddev"]
    return rows, 0.0, tuple(healthy)


def full_car(a):
    config = a.config or os.path.join(ROOT, "config", "full_car_live.yaml")
    print("%-3s %-30s %-44s %6s %6s %5s | %-23s | %-23s" % (
        "rec", "truth", "reference M / y", "R-hat", "ESS", "s", "one-step std/ref, dz",
        "ES-MDA std/ref, dz"))
    runs = {"one-step": [], "ES-MDA": []}
    records = [int(x) for x in a.records.split(",")] if a.records else range(1, len(CAR_RECORDS) + 1)
    with tempfile.TemporaryDirectory() as tmp:
        for i in records:
            mass, x, y, vehicle, seed = CAR_RECORDS[i - 1]
            path = os.path.join(tmp, "car_record_%d.yaml" % i)
            with open(path, "w") as f:
                f.write(car_record_config(config, (mass, x, y), vehicle, seed, a.exact_body,
                                          a.override))
            if a.no_reference:
                rows, seconds, healthy = filters_only(a.bin_dir, path, (mass, x, y))
            else:
                rows, seconds, healthy = run(a.bin_dir, path, a.samples)
            m, d = rows["added_mass"], rows["added_mass_y"]
            r_hat = max(r[2] for r in rows.values())
            ess = min(r[3] for r in rows.values())
            print("%-3d %-30s %-44s %6.4f %6.0f %5.1f | %-23s | %-23s" % (
                i, "%.0f kg %.1f m %.2f m, %s, seed %d" % (mass, x, y, vehicle, seed),
                "%.1f+-%.1f kg %.4f+-%.4f m" % (m[0], m[1], d[0], d[1]), r_hat, ess, seconds,
                "%.2f %.2f, %+.2f %+.2f" % (m[6], d[6], m[5], d[5]),
                "%.2f %.2f, %+.2f %+.2f" % (m[8], d[8], m[7], d[7])))
            for method, dz, ratio, ok in (("one-step", 5, 6, healthy[0]), ("ES-MDA", 7, 8, healthy[1])):
                # the filter's error in its own reported std: (mean - truth) / std
                z = [(rows[p][dz] - rows[p][9]) / rows[p][ratio] for p in CAR_LOAD]
                std = [rows[p][1] * rows[p][ratio] for p in CAR_LOAD]
                runs[method].append((z, ok, std))
                print("    %-8s z M %+.2f x %+.2f y %+.2f, healthy %d, std M %.2f kg x %.4f m y %.4f m"
                      % (method, z[0], z[1], z[2], ok, std[0], std[1], std[2]))
            sys.stdout.flush()
    for method, rs in runs.items():
        covered = sum(all(abs(v) <= 3.0 for v in z) for z, _, _ in rs)
        healthy = sum(ok for _, ok, _ in rs)
        silent = sum(ok and not all(abs(v) <= 3.0 for v in z) for z, ok, _ in rs)
        print("%s: %d/%d covered, %d healthy, %d silent, largest |z| %.2f, std M %.2f-%.2f kg "
              "(median %.2f), x %.4f-%.4f m, y %.4f-%.4f m" % (
                  method, covered, len(rs), healthy, silent, max(max(abs(v) for v in z) for z, _, _ in rs),
                  min(s[0] for _, _, s in rs), max(s[0] for _, _, s in rs),
                  statistics.median(s[0] for _, _, s in rs), min(s[1] for _, _, s in rs),
                  max(s[1] for _, _, s in rs), min(s[2] for _, _, s in rs), max(s[2] for _, _, s in rs)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bin_dir")
    ap.add_argument("--samples", type=int, default=25000)
    ap.add_argument("--override", default="")
    ap.add_argument("--records", default="")
    ap.add_argument("--full-car", action="store_true",
                    help="config/full_car_live.yaml on six loaded full-car records")
    ap.add_argument("--config", default="", help="--full-car: this file instead of full_car_live.yaml")
    ap.add_argument("--exact-body", action="store_true",
                    help="--full-car: the truth's body mass as configured")
    ap.add_argument("--no-reference", action="store_true",
                    help="--full-car: the filters only (estimate_offline), no reference")
    a = ap.parse_args()
    if a.full_car:
        return full_car(a)
    if not a.records:
        a.records = ",".join(str(i + 1) for i in range(len(RECORDS)))
    print("%-3s %-24s %-30s %6s %6s %5s | %-23s | %-23s" % (
        "rec", "truth", "reference M / d_CG", "R-hat", "ESS", "s", "one-step std/ref, dz",
        "ES-MDA std/ref, dz"))
    with tempfile.TemporaryDirectory() as tmp:
        for i in [int(x) for x in a.records.split(",")]:
            mass, position, vehicle, seed = RECORDS[i - 1]
            path = os.path.join(tmp, "record_%d.yaml" % i)
            with open(path, "w") as f:
                f.write(record_config(mass, position, vehicle, seed, a.override))
            rows, seconds, _ = run(a.bin_dir, path, a.samples)
            m, d = rows["added_mass"], rows["added_mass_position"]
            r_hat = max(r[2] for r in rows.values())
            ess = min(r[3] for r in rows.values())
            # row: mean, std, R-hat, ESS, lapl/ref, 1step dz, 1step ratio, ESMDA dz, ESMDA ratio, truth dz
            print("%-3d %-24s %-30s %6.4f %6.0f %5.1f | %-23s | %-23s" % (
                i, "%.0f kg %.2f m, %s, seed %d" % (mass, position, vehicle, seed),
                "%.1f+-%.1f kg %.4f+-%.4f m" % (m[0], m[1], d[0], d[1]), r_hat, ess, seconds,
                "%.2f %.2f, %+.2f %+.2f" % (m[6], d[6], m[5], d[5]),
                "%.2f %.2f, %+.2f %+.2f" % (m[8], d[8], m[7], d[7])))
            sys.stdout.flush()


if __name__ == "__main__":
    main()
