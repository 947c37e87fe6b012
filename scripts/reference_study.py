#!/usr/bin/python3
"""The filters against the converged reference posterior at n = 15
(docs/real_vehicle_reference.md §5).

  /usr/bin/python3 scripts/reference_study.py BIN_DIR [--samples 25000] [--records 1,2,...]
      [--override YAML]

Each record is test/benchmarks/live_n15.yaml (vehicle_live.yaml's payload, 13
tolerances and design on the speed bump, N = 100 over 3 s, 1 % noise, no
sensor floor) with its own truth: a load and a vehicle whose nine spring,
damper, unsprung, tyre and inertia values are off by up to 6 %. For each,
bench_mcmc_reference runs one-step and ES-MDA and the conditional-Laplace
reference (4 batches of --samples draws) on the same likelihood. Prints per
record the reference's M and d_CG (mean +- std), its largest R-hat, smallest
ESS and time, and for each filter the std ratio (filter / reference) and the
mean's offset in reference std, for M and d_CG. --override: YAML merged into
every record's config (e.g. "filter: {relinearize: {shrink: 0.3}}")."""
import argparse, os, re, subprocess, sys, tempfile

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


def run(bin_dir, path, samples):
    env = dict(os.environ, PC_EKF_MCMC_CONFIG=path, PC_EKF_MCMC_SAMPLER="conditional_laplace",
               PC_EKF_MCMC_CHAINS="4", PC_EKF_MCMC_SAMPLES=str(samples))
    out = subprocess.run([os.path.join(bin_dir, "bench_mcmc_reference")], env=env,
                         capture_output=True, text=True, check=True).stdout
    rows = {}
    for line in out.splitlines():
        f = line.split()
        if len(f) == 14 and f[6] == f[9] == f[12] == "|":
            rows[f[0]] = [float(x) for x in (f[1:6] + f[7:9] + f[10:12] + f[13:14])]
    seconds = float(re.search(r"simulations, ([0-9.]+) s;", out).group(1))
    return rows, seconds


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bin_dir")
    ap.add_argument("--samples", type=int, default=25000)
    ap.add_argument("--override", default="")
    ap.add_argument("--records", default=",".join(str(i + 1) for i in range(len(RECORDS))))
    a = ap.parse_args()
    print("%-3s %-24s %-30s %6s %6s %5s | %-23s | %-23s" % (
        "rec", "truth", "reference M / d_CG", "R-hat", "ESS", "s", "one-step std/ref, dz",
        "ES-MDA std/ref, dz"))
    with tempfile.TemporaryDirectory() as tmp:
        for i in [int(x) for x in a.records.split(",")]:
            mass, position, vehicle, seed = RECORDS[i - 1]
            path = os.path.join(tmp, "record_%d.yaml" % i)
            with open(path, "w") as f:
                f.write(record_config(mass, position, vehicle, seed, a.override))
            rows, seconds = run(a.bin_dir, path, a.samples)
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
