#!/usr/bin/python3
"""Ordinary driving, road-free: the roll plane on turns, a lane change, a
slalom, cross-fall and IMU biases (config/vehicle_imu.yaml), the full car on
braking, accelerating and a lane change (--full-car: config/full_car_imu.yaml).

  /usr/bin/python3 scripts/driving_study.py BIN_DIR [--config FILE] [--seeds N]
      [--methods one_step,es_mda] [--drives lane,turn,...] [--model-errors]
      [--without-driving-inputs] [--full-car]

Each run synthesises a 10 s, 200 Hz drive of the truth (truth.road: a course
whose manoeuvres carry the lateral acceleration, on a road the estimator is
not told), for one vehicle (the config's, or nine values off by up to 6 %
with the body's centre of mass 2 cm higher and the anti-roll bar 5 % stiffer
than the file says), one load (150 kg at 0.62 m, 0.275 m above the mounts;
280 kg at 0.90 m, 0.70 m above) and the config's sensor noise, and estimates
with `tare`. Counted: covered (M, its position and height within 3 reported
std) and healthy; silent (healthy, one of them beyond 3 std); cg_height
within 3 std in the healthy runs; the median std of cg_height.
--model-errors: instead the body's centre of mass 15 cm higher than the file
says, or no anti-roll bar in the model; every run should be flagged.
--without-driving-inputs: the channels speed and gyro_z left out (a_y not
given to the estimator)."""
import argparse, json, os, re, statistics, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# (mass, position from the left mount, height above the mount plane)
LOADS = [(150.0, 0.62, 0.275), (280.0, 0.90, 0.70)]
LOAD_NAMES = {False: ("added_mass", "added_mass_position", "added_mass_height"),
              True: ("added_mass", "added_mass_x", "added_mass_y", "added_mass_height")}
# Nine values off by up to 6 %, the body's centre of mass 2 cm higher, the bar 5 % off.
OFF = {"unsprung_mass_left": 38.4, "unsprung_mass_right": 34.5, "damping_left": 748.0,
       "damping_right": 680.0, "spring_linear_left": 20325.0, "spring_linear_right": 18600.0,
       "bar_inertia": 66.5, "tyre_stiffness_left": 92500.0, "tyre_stiffness_right": 101000.0,
       "body_cg_height": 0.27, "anti_roll_bar": 8400.0}
ISO = "iso8608: {class: %s, seed: %d, correlation: 0.0}"
# A steady 3.5 m/s^2 turn between two seconds of straight road.
TURN = ["{type: iso8608, duration: 1.0}",
        "{type: turn, duration: 8.0, lateral_acceleration: 3.5, ramp: 1.5, surface: iso8608}",
        "{type: iso8608, duration: 1.0}"]
# name: (speed km/h, ISO class, course segments, extra truth text)
DRIVES = {
    "lane": (72.0, "B", ["{type: iso8608, duration: 2.5}",
                         "{type: lane_change, duration: 2.5, lateral_acceleration: 4.5, surface: iso8608}",
                         "{type: lane_change, duration: 2.5, lateral_acceleration: -4.5, surface: iso8608}",
                         "{type: iso8608, duration: 2.5}"], ""),
    "turn": (54.0, "C", TURN, ""),
    "slalom": (36.0, "A", ["{type: iso8608, duration: 1.0}",
                           "{type: slalom, duration: 8.0, frequency: 0.5, lateral_acceleration: 3.5, surface: iso8608}",
                           "{type: iso8608, duration: 1.0}"], ""),
    "straight": (36.0, "B", ["{type: iso8608, duration: 10.0}"], ""),
    "cross-fall 2 %": (36.0, "B", ["{type: iso8608, duration: 10.0}"],
                       "  cross_fall: {start: 0.02}\n"),
    "crown +2 % to -2 %": (36.0, "B", ["{type: iso8608, duration: 10.0}"],
                           "  cross_fall: {start: 0.02, end: -0.02, at: 4.0, over: 2.0}\n"),
    "IMU biases": (36.0, "B", ["{type: iso8608, duration: 10.0}"], "BIAS"),
    "turn, cross-fall and biases": (
        54.0, "C", TURN, "  cross_fall: {start: 0.02}\nBIAS"),
}
# The full car (config/full_car_imu.yaml): loads (mass, x forward of the rear
# axle, y left of the right wheels, height above the mount plane); nine values
# off by up to 5 %, the body's centre of mass 2 cm higher, the bars 5 % off.
CAR_LOADS = [(150.0, 1.0, 0.62, 0.275), (280.0, 1.6, 0.90, 0.70)]
CAR_OFF = {"body_mass": 1230.0, "spring_linear_front": 21000.0, "spring_linear_rear": 21000.0,
           "damping_front": 1575.0, "damping_rear": 1330.0, "roll_inertia": 420.0,
           "pitch_inertia": 1520.0, "anti_roll_bar_front": 10500.0, "anti_roll_bar_rear": 5700.0,
           "body_cg_height": 0.22}
CAR_DRIVES = {
    "braking 5 m/s^2": (72.0, "B", ["{type: iso8608, duration: 2.0}",
                                    "{type: brake, duration: 3.0, deceleration: 5.0, surface: iso8608}",
                                    "{type: iso8608, duration: 5.1, speed_kmh: 18.0}"], ""),
    "accelerating 2.5 m/s^2": (36.0, "B", ["{type: iso8608, duration: 2.0}",
                                           "{type: accelerate, duration: 4.0, acceleration: 2.5, surface: iso8608}",
                                           "{type: iso8608, duration: 4.1, speed_kmh: 72.0}"], ""),
    "lane change": (72.0, "B", ["{type: iso8608, duration: 2.0}",
                                "{type: lane_change, duration: 2.5, lateral_acceleration: 4.5, surface: iso8608}",
                                "{type: lane_change, duration: 2.5, lateral_acceleration: -4.5, surface: iso8608}",
                                "{type: iso8608, duration: 3.1}"], ""),
    "straight": (36.0, "B", ["{type: iso8608, duration: 10.1}"], ""),
}
# accel_y, accel_z, gyro_x biases (m/s^2, m/s^2, rad/s), the gyro_z's as gyro_x's.
BIAS = {"accel_y": 0.025, "accel_z": -0.02, "accel_x": 0.02, "gyro_x": 0.0015, "gyro_z": -0.0015}


def germ(text, name, value):
    """The germ coordinate of `value` for the config's uncertain `name`."""
    m = re.search(r"- name: %s\n\s+nominal: ([0-9.eE+-]+)[^\n]*\n\s+relative_range: ([0-9.eE+-]+)" % name,
                  text)
    nominal, spread = float(m.group(1)), float(m.group(2))
    return (value / nominal - 1.0) / spread


def vehicle_value(text, name):
    m = re.search(r"\n  %s: ([0-9.eE+-]+)" % name, text)
    return float(m.group(1)) if m else 0.0


def channels(text):
    return [c.strip() for c in re.search(r"\n  channels: \[([^\]]*)\]", text).group(1).split(",")]


def drop_channels(text, names):
    """The channels `names` out of measurement: and truth.sensor's per-channel lists."""
    old = channels(text)
    keep = [i for i, c in enumerate(old) if c not in names]

    def cut(m):
        items = [v.strip() for v in m.group(2).split(",")]
        if len(items) != len(old):
            return m.group(0)
        return m.group(1) + "[" + ", ".join(items[i] for i in keep) + "]"
    return re.sub(r"((?:channels|sensor_std|r_relative|noise_relative|noise_floor): )\[([^\]]*)\]", cut, text)


def config_text(base, drive, seed, vehicle, load, car=False):
    """The config with a synthetic truth: the drive's course, the load, the vehicle."""
    text = base
    speed, road_class, course, extra = (CAR_DRIVES if car else DRIVES)[drive]
    text = text.replace("  samples: 2000 ", "  samples: 2000 #", 1)
    start = text.index("\ntruth:")
    end = text.index("\n  sensor:", start)
    names = LOAD_NAMES[car]
    height = load[-1]
    xi = [germ(text, n, v) for n, v in zip(names, load)]
    truth = "\ntruth:\n  road:\n    source: course\n    speed_kmh: %.1f\n    %s\n    course:\n" % (
        speed, ISO % (road_class, seed))
    truth += "".join("      - %s\n" % s for s in course)
    truth += "  xi: [%s]\n  seed: %d\n" % (", ".join("%.10f" % v for v in xi), seed)
    vals = dict(CAR_OFF if car else OFF) if vehicle else {}
    if "- name: added_mass_height" not in text:
        vals["added_mass_height"] = height
    if vals:
        truth += "  vehicle: {%s}\n" % ", ".join("%s: %s" % kv for kv in vals.items())
    if "BIAS" in extra:
        bias = [BIAS.get(c, 0.0) for c in channels(text)]
        extra = extra.replace("BIAS", "")
        text_bias = "    bias: [%s]\n" % ", ".join("%g" % b for b in bias)
    else:
        text_bias = ""
    truth += extra
    text = text[:start] + truth + text[end:]
    if text_bias:
        s = text.index("\n  sensor:", text.index("\ntruth:")) + len("\n  sensor:\n")
        text = text[:s] + text_bias + text[s:]
    return text


def without_value(text, name):
    """The config with vehicle value `name` 0: its tolerance and its walk's entry out."""
    text = re.sub(r"\n  %s: [0-9.eE+-]+" % name, "\n  %s: 0.0" % name, text, 1)
    head, tail = text.split("\ntolerances:\n", 1)
    block = tail.split("\n\n", 1)[0] if "\n\n" in tail else tail
    names = re.findall(r"^  (\w+):", block, re.M)
    if name not in names:
        return text
    tail = re.sub(r"\n  %s: [^\n]*" % name, "", "\n" + tail, 1)[1:]
    text = head + "\ntolerances:\n" + tail
    loads = len(re.findall(r"^  - name: ", head.split("\nuncertain:", 1)[1], re.M))
    m = re.search(r"\n  drift_relative: \[([^\]]*)\]", text)
    if m:
        items = [v.strip() for v in m.group(1).split(",")]
        del items[loads + names.index(name)]
        text = text[:m.start(1)] + ", ".join(items) + text[m.end(1):]
    return text


def truth_cg_height(text, vehicle, load, car=False):
    """The cg_height of the truth: ((m + M) h_P + S + sum m_u r_w) / (m + M + sum m_u)."""
    keys = ("body_mass", "unsprung_mass_front", "unsprung_mass_rear") if car else (
        "bar_mass", "unsprung_mass_left", "unsprung_mass_right")
    v = {k: vehicle_value(text, k) for k in keys + ("body_cg_height", "mount_height", "wheel_radius")}
    if vehicle:
        v.update({k: x for k, x in (CAR_OFF if car else OFF).items() if k in v})
    mass, height = load[0], load[-1]
    body = v[keys[0]]
    mu = (2.0 if car else 1.0) * (v[keys[1]] + v[keys[2]])
    s = body * v["body_cg_height"] + mass * height
    return ((body + mass) * v["mount_height"] + s + mu * v["wheel_radius"]) / (body + mass + mu)


def estimate(exe, tmp, text, method):
    cfg = os.path.join(tmp, "c.yaml")
    open(cfg, "w").write(text)
    out = subprocess.run([exe, "--config", cfg, "--method", method], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(cfg + ": " + out.stderr)
    d = json.loads(out.stdout)
    return d, {q["name"]: q for q in d["parameters"] + d.get("derived", [])}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("bin")
    ap.add_argument("--config", default=os.path.join(ROOT, "config", "vehicle_imu.yaml"))
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--methods", default="one_step,es_mda")
    ap.add_argument("--drives", default="", help="only the drives whose name contains one of these words")
    ap.add_argument("--model-errors", action="store_true")
    ap.add_argument("--without-driving-inputs", action="store_true")
    ap.add_argument("--keep", default="", help="a directory to keep each run's config and JSON in")
    ap.add_argument("--full-car", action="store_true",
                    help="config/full_car_imu.yaml (unless --config) on braking, accelerating, a "
                         "double lane change and a straight control")
    a = ap.parse_args()
    car = a.full_car
    if car and a.config == ap.get_default("config"):
        a.config = os.path.join(ROOT, "config", "full_car_imu.yaml")
    base = open(a.config).read()
    if a.without_driving_inputs:
        base = drop_channels(base, ("speed", "gyro_z"))
    drives = [d for d in (CAR_DRIVES if car else DRIVES)
              if not a.drives or any(w in d for w in a.drives.split(","))]
    exe = os.path.join(a.bin, "estimate_offline")
    if a.model_errors:
        return model_errors(a, exe, base, drives)
    print("| drive | method | runs | covered & healthy | silent | flagged | cg_height within 3 std (healthy) "
          "| median std cg_height (cm) | median std M (kg) | median std h_M (cm) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    total = [0, 0, 0, 0]
    with tempfile.TemporaryDirectory() as tmp:
        for drive in drives:
            for method in a.methods.split(","):
                runs = covered = silent = flagged = cg_ok = cg_runs = 0
                s_cg, s_m, s_h = [], [], []
                for vehicle in (False, True):
                    for load in CAR_LOADS if car else LOADS:
                        for seed in range(a.first_seed, a.first_seed + a.seeds):
                            text = config_text(base, drive, seed, vehicle, load, car)
                            d, p = estimate(exe, tmp, text, method)
                            if a.keep:
                                os.makedirs(a.keep, exist_ok=True)
                                tag = "%s_%s_%d_%d_%d" % (re.sub(r"\W+", "_", drive), method, vehicle,
                                                          int(load[0]), seed)
                                open(os.path.join(a.keep, tag + ".yaml"), "w").write(text)
                                json.dump(d, open(os.path.join(a.keep, tag + ".json"), "w"))
                            names = [(n, v) for n, v in zip(LOAD_NAMES[car], load) if n in p]
                            off = max(abs(p[n]["mean"] - v) / p[n]["stddev"] for n, v in names)
                            runs += 1
                            covered += off <= 3.0 and d["healthy"]
                            silent += off > 3.0 and d["healthy"]
                            flagged += not d["healthy"]
                            s_m.append(p["added_mass"]["stddev"])
                            if "added_mass_height" in p:
                                s_h.append(100.0 * p["added_mass_height"]["stddev"])
                            if "cg_height" in p:
                                s_cg.append(100.0 * p["cg_height"]["stddev"])
                                if d["healthy"]:
                                    cg_runs += 1
                                    truth = truth_cg_height(text, vehicle, load, car)
                                    cg_ok += abs(p["cg_height"]["mean"] - truth) <= 3.0 * p["cg_height"]["stddev"]
                med = lambda x: "%.2f" % statistics.median(x) if x else "-"
                print("| %s | %s | %d | %d | %d | %d | %d of %d | %s | %s | %s |" % (
                    drive, method, runs, covered, silent, flagged, cg_ok, cg_runs, med(s_cg), med(s_m),
                    med(s_h)), flush=True)
                for i, v in enumerate((runs, covered, silent, flagged)):
                    total[i] += v
    print("\nall: %d runs, %d covered and healthy, %d silent, %d flagged" % tuple(total))


def model_errors(a, exe, base, drives):
    h_b = vehicle_value(base, "body_cg_height")
    errors = {"body's CG 15 cm higher than told": ("truth", {"body_cg_height": h_b + 0.15}),
              "no anti-roll bar in the model": ("model", "anti_roll_bar")}
    print("| model error | drive | method | flagged | silent |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for label, (where, what) in errors.items():
            for drive in drives:
                for method in a.methods.split(","):
                    flagged = silent = 0
                    for load in LOADS:
                        text = config_text(base, drive, a.first_seed, False, load)
                        if where == "truth":
                            text = text.replace("  xi: [", "  vehicle: {%s}\n  xi: [" % ", ".join(
                                "%s: %s" % kv for kv in what.items()), 1)
                        else:  # the model without it; the truth keeps the file's value
                            value = vehicle_value(base, what)
                            text = without_value(text, what)
                            text = text.replace("  xi: [", "  vehicle: {%s: %s}\n  xi: [" % (what, value), 1)
                        d, p = estimate(exe, tmp, text, method)
                        flagged += not d["healthy"]
                        names = [(n, v) for n, v in zip(LOAD_NAMES[False], load) if n in p]
                        miss = any(abs(p[n]["mean"] - v) > 3 * p[n]["stddev"] for n, v in names)
                        silent += d["healthy"] and miss
                    print("| %s | %s | %s | %d/%d | %d |" % (label, drive, method, flagged, len(LOADS), silent),
                          flush=True)


if __name__ == "__main__":
    main()
