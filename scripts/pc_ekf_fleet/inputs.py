"""What a fleet run reads: the bags, the vehicle files and the configs.

A row's config_hash is the C++ identity of the config its bag was estimated
with (estimate_offline --config-hash: the config merged with its vehicle
file's contents, as estimator_node's checkpoints hold it), so there is one
config hash in the package.
"""
import fnmatch
import glob
import hashlib
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import yaml

from pc_ekf_fleet.journal import atomic_write
from pc_ekf_fleet.worker import installed_estimate_offline, last_line


class FleetError(Exception):
    """Bad input (exit 2), with a message naming what was wrong."""


def find_bags(specs):
    """Absolute bag paths, sorted: a folder gives its *.bag files (recursively),
    anything else is a glob (** allowed)."""
    found = set()
    for spec in specs:
        if os.path.isdir(spec):
            matches = glob.glob(os.path.join(spec, "**", "*.bag"), recursive=True)
        else:
            matches = glob.glob(spec, recursive=True)
        matches = [m for m in matches if os.path.isfile(m)]
        if not matches:
            raise FleetError(f"--bags '{spec}': no bag file matches")
        found.update(os.path.abspath(m) for m in matches)
    return sorted(found)


def file_hash(path):
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def hash_bags(paths):
    """{path: sha256, or an OSError naming why the bag cannot be read}; reads
    in parallel threads (I/O bound)."""
    def one(path):
        try:
            return file_hash(path)
        except OSError as err:
            return OSError(f"cannot read the bag: {err.strerror}")
    with ThreadPoolExecutor(max_workers=4) as pool:
        return dict(zip(paths, pool.map(one, paths)))


def load_yaml(path, what):
    try:
        with open(path, encoding="utf-8") as f:
            return yaml.safe_load(f)
    except OSError as err:
        raise FleetError(f"{what} {path}: cannot read ({err.strerror})") from err
    except yaml.YAMLError as err:
        raise FleetError(f"{what} {path}: not YAML: {err}") from err


def load_vehicle_map(path):
    """[(pattern, vehicle file)] in file order (the first match wins); a
    pattern is matched (fnmatch) on the bag's file name, or on its path when it
    holds a '/'. Relative vehicle files are relative to the map."""
    data = load_yaml(path, "--vehicle-files")
    if not isinstance(data, dict) or not data:
        raise FleetError(f"--vehicle-files {path}: expected a mapping 'bag-name pattern: "
                         "vehicle file', e.g. \"van01_*.bag: vehicles/van01.yaml\"")
    entries = []
    for pattern, vehicle in data.items():
        if not isinstance(pattern, str) or not isinstance(vehicle, str) or not vehicle:
            raise FleetError(f"--vehicle-files {path}: entry '{pattern}': expected "
                             "'pattern: path of a vehicle file'")
        vehicle = os.path.join(os.path.dirname(os.path.abspath(path)), vehicle)
        entries.append((pattern, os.path.normpath(vehicle)))
    return entries


def vehicle_for(bag, entries):
    """The vehicle file of the bag's first matching pattern, or ""."""
    for pattern, vehicle in entries:
        subject = bag if "/" in pattern else os.path.basename(bag)
        if fnmatch.fnmatchcase(subject, pattern):
            return vehicle
    return ""


def config_hash(exe, path):
    """The identity of the config file path (estimate_offline --config-hash),
    which also checks the config and its vehicle file."""
    try:
        proc = subprocess.run([exe, "--config", path, "--config-hash"], stdin=subprocess.DEVNULL,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              universal_newlines=True, timeout=120)
    except (OSError, subprocess.TimeoutExpired) as err:
        raise FleetError(f"cannot run {exe} --config-hash: {err}") from err
    if proc.returncode != 0 or not proc.stdout.startswith("0x"):
        raise FleetError(f"config {path}: {last_line(proc.stderr or proc.stdout)}")
    return proc.stdout.strip()


def prepare_configs(config, vehicle_files, bags, out, exe):
    """({vehicle file: (config path, config hash)}, the map's entries). The
    bags of a vehicle file are estimated with the config plus
    `vehicle_file: <absolute path>`, written to DIR/configs/; "" is the config
    itself (bags that match no pattern)."""
    base = load_yaml(config, "--config")
    if not isinstance(base, dict):
        raise FleetError(f"--config {config}: expected a mapping (an estimator config)")
    entries = load_vehicle_map(vehicle_files) if vehicle_files else []
    configs = {"": (os.path.abspath(config), config_hash(exe, config))}
    for vehicle_path in sorted({vehicle_for(b, entries) for b in bags} - {""}):
        name = os.path.splitext(os.path.basename(vehicle_path))[0]
        folder = os.path.join(out, "configs")
        os.makedirs(folder, exist_ok=True)
        draft = os.path.join(folder, f".{name}.draft.yaml")
        atomic_write(draft, f"# estimate_fleet: {os.path.abspath(config)} with the "
                     f"vehicle file {vehicle_path}\n" +
                     yaml.safe_dump(dict(base, vehicle_file=vehicle_path), sort_keys=False))
        digest = config_hash(exe, draft)
        path = os.path.join(folder, f"{name}-{digest[2:14]}.yaml")
        os.replace(draft, path)
        configs[vehicle_path] = (path, digest)
    return configs, entries


def find_estimate_offline(given, script):
    """--estimate-offline, else the estimate_offline beside the script
    (installed, or in devel space through catkin's relay), else the one on
    PATH or in the sourced workspaces."""
    if given:
        if not os.access(given, os.X_OK):
            raise FleetError(f"--estimate-offline {given}: not an executable")
        return os.path.abspath(given)
    for folder in {os.path.dirname(os.path.realpath(p)) for p in (script, sys.argv[0])} | \
            {os.path.dirname(os.path.abspath(sys.argv[0]))}:
        candidate = os.path.join(folder, "estimate_offline")
        if os.access(candidate, os.X_OK):
            return candidate
    found = installed_estimate_offline()
    if found:
        return found
    raise FleetError("estimate_offline not found: build pc_ekf and source its setup.bash, or "
                     "give --estimate-offline PATH")
