#!/usr/bin/python3
"""Coverage and spread of M and d_CG with and without the IMU, with zero: rest
and zero: tare, on synthetic drives over the paper's speed bump
(config/vehicle_imu.yaml, road replaced by the analytic bump).

  /usr/bin/python3 scripts/imu_coverage_study.py BIN_DIR [--seeds N] [--samples N]

Prints one row per (channels, zero, method): runs, covered within 3 reported
std and healthy, silent (off by more than 3 std and healthy), median std of M
and d_CG. Loads: 150 kg at 0.62 m and 280 kg at 0.90 m; noise seeds 1..N."""
import argparse, json, os, statistics, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LOADS = [(150.0, 0.62), (280.0, 0.90)]


def config_text(zero, imu, samples, mass, position):
    text = open(os.path.join(ROOT, "config", "vehicle_imu.yaml")).read()
    text = text.replace("  source: none ", "  source: speed_bump #", 1)  # the road as told
    # A told road gives the model dynamic states: the collocation filter.
    text = text.replace("  linearization: mean ", "  linearization: collocation #", 1)
    text = text.replace("reopen: {mode: load", "reopen: {mode: \"off\"", 1)
    start = text.index("  road:                         # the road the simulated")
    text = text[:start] + text[text.index("  sensor:", start):]  # the truth on that road too
    text = text.replace("  samples: 2000 ", "  samples: %d #" % samples, 1)
    text = text.replace("  duration: 10.0\n", "  duration: 3.0\n", 1)
    text = text.replace("  zero: tare ", "  zero: %s #" % zero, 1)
    if not imu:
        text = text.replace("  channels: [u1, u2, v1, v2, accel_y, accel_z, gyro_x]",
                            "  channels: [u1, u2, v1, v2]", 1)
        text = text.replace("  sensor_std: [5.0e-4, 5.0e-4, 5.0e-3, 5.0e-3, 0.03, 0.03, 0.002]",
                            "  sensor_std: [5.0e-4, 5.0e-4, 5.0e-3, 5.0e-3]", 1)
        text = text.replace("  r_relative: [0.01, 0.01, 0.01, 0.01, 0.0, 0.0, 0.0]",
                            "  r_relative: 0.01", 1)
        text = text.replace("  noise_relative: [0.01, 0.01, 0.01, 0.01, 0.0, 0.0, 0.0]",
                            "  noise_relative: 0.01", 1)
        text = text.replace("    noise_floor: [5.0e-4, 5.0e-4, 5.0e-3, 5.0e-3, 0.03, 0.03, 0.002]",
                            "    noise_floor: [5.0e-4, 5.0e-4, 5.0e-3, 5.0e-3]", 1)
    import yaml  # the germs as the file declares them (nominal, relative_range)
    u = {q["name"]: q for q in yaml.safe_load(text)["uncertain"]}
    xi_m = (mass / u["added_mass"]["nominal"] - 1.0) / u["added_mass"]["relative_range"]
    xi_d = (position / u["added_mass_position"]["nominal"] - 1.0) / \
        u["added_mass_position"]["relative_range"]
    text = text.replace("truth:                          # synthetic drives only",
                        "truth:\n  xi: [%.10f, %.10f] #" % (xi_m, xi_d), 1)
    return text


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("bin")
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--samples", type=int, default=300)
    a = ap.parse_args()
    exe = os.path.join(a.bin, "estimate_offline")
    print("| channels | zero | method | runs | covered & healthy | silent | median std M (kg) | median std d_CG (mm) |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for imu in (False, True):
            for zero in ("rest", "tare"):
                for method in ("one_step", "es_mda"):
                    runs = covered = silent = 0
                    sm, sd = [], []
                    for mass, position in LOADS:
                        cfg = os.path.join(tmp, "c.yaml")
                        open(cfg, "w").write(config_text(zero, imu, a.samples, mass, position))
                        for seed in range(1, a.seeds + 1):
                            out = subprocess.run([exe, "--config", cfg, "--method", method,
                                                  "--seed", str(seed)], capture_output=True, text=True)
                            if out.returncode != 0:
                                sys.exit(out.stderr)
                            d = json.loads(out.stdout)
                            p = {q["name"]: q for q in d["parameters"]}
                            off = max(abs(p["added_mass"]["mean"] - mass) / p["added_mass"]["stddev"],
                                      abs(p["added_mass_position"]["mean"] - position) /
                                      p["added_mass_position"]["stddev"])
                            runs += 1
                            covered += off <= 3.0 and d["healthy"]
                            silent += off > 3.0 and d["healthy"]
                            sm.append(p["added_mass"]["stddev"])
                            sd.append(1000.0 * p["added_mass_position"]["stddev"])
                    print("| %s | %s | %s | %d | %d | %d | %.2f | %.2f |" % (
                        "u, v + IMU" if imu else "u, v", zero, method, runs, covered, silent,
                        statistics.median(sm), statistics.median(sd)), flush=True)


if __name__ == "__main__":
    main()
