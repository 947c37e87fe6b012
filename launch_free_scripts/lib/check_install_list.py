"""Checks that PC_EKF_APT_PACKAGES (lib/common.sh) covers what the package uses.

Usage: check_install_list.py OUT.xml PACKAGE [PACKAGE ...]   (the install list)

On a fresh machine only the install list (and what it pulls in) is there, so
everything the build, the tests and the commands of README.md and docs/ need must be owned
by a Debian package in the closure of that list. For each thing used:
  - every dependency in package.xml (ROS packages via `rospack find`, system
    rosdep keys via a header or library they provide),
  - every command README.md, docs/*.md and the scripts run (ros*, catkin_*, colcon,
    `rosrun nodelet nodelet`, compilers and helpers),
  - every Python module imported by launch_free_scripts/lib/*.py, scripts/*,
    estimate_fleet's package (scripts/pc_ekf_fleet) and its tests (test/fleet),
this finds the file it resolves to, the Debian package owning it (`dpkg -S`),
and fails naming that package when it is neither listed nor pulled in
(`apt-cache depends --recurse --installed` of the list). Something that does
not resolve at all fails too: on a fresh machine it would be missing.
Writes one JUnit test case per kind of use to OUT.xml; exits 1 on a failure.
"""
import ast
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

import junit

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# rosdep keys in package.xml that are not ROS packages: a file each provides.
SYSTEM_KEYS = {
    "eigen": ["/usr/include/eigen3/Eigen/Core"],
    "yaml-cpp": ["/usr/include/yaml-cpp/yaml.h"],
    "boost": ["/usr/include/boost/version.hpp"],
    "gtest": ["/usr/include/gtest/gtest.h", "/usr/src/googletest/CMakeLists.txt"],
    "benchmark": ["/usr/include/benchmark/benchmark.h"],
    "python3-matplotlib": ["/usr/lib/python3/dist-packages/matplotlib/__init__.py"],
    "python3-tk": ["/usr/lib/python3.11/tkinter/__init__.py"],
    "nlohmann-json-dev": ["/usr/include/nlohmann/json.hpp"],
    "python3-distributed": ["/usr/lib/python3/dist-packages/distributed/__init__.py"],
    "python3-yaml": ["/usr/lib/python3/dist-packages/yaml/__init__.py"],
}

# Commands run by the scripts and the README that the word scan below does
# not catch (it finds ros*/catkin_* words).
EXTRA_COMMANDS = [
    "cmake", "make", "g++", "clang", "clang++", "llvm-symbolizer", "colcon",
    "setsid", "timeout", "pgrep", "dpkg-query", "apt-cache",
    "dask-scheduler", "dask-worker",  # lib/fleet_test.sh, docs/fleet.md (estimate_fleet)
    "time",  # lib/bench_long.sh: /usr/bin/time -v (not the shell's keyword)
]


def run(cmd):
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                          universal_newlines=True)
    return proc.returncode, proc.stdout


def closure(packages):
    """Packages installed as the list or as its recursive hard dependencies."""
    code, out = run(["apt-cache", "depends", "--recurse", "--no-recommends",
                     "--no-suggests", "--no-conflicts", "--no-breaks", "--no-replaces",
                     "--no-enhances", "--installed"] + packages)
    names = set(packages)
    # Essential and required packages are on every Debian system.
    code, installed = run(["dpkg-query", "-W", "-f", "${Package} ${Essential} ${Priority}\\n"])
    for line in installed.splitlines():
        parts = line.split()
        if len(parts) == 3 and (parts[1] == "yes" or parts[2] == "required"):
            names.add(parts[0])
    # With --recurse every reached package gets an unindented line of its own.
    for line in out.splitlines():
        if line and not line[0].isspace():
            names.add(line.strip().strip("<>").split(":")[0])
    return names


def owner(path):
    """Debian package owning path (following symlinks if the link is unowned)."""
    for candidate in (path, os.path.realpath(path)):
        code, out = run(["dpkg", "-S", candidate])
        if code == 0 and out:
            # "pkg1, pkg2: /path" (diversions aside): take the first owner.
            line = [l for l in out.splitlines() if not l.startswith("diversion")][0]
            return line.split(":")[0].split(",")[0].strip()
    return None


def package_xml_uses():
    tree = ET.parse(os.path.join(ROOT, "package.xml"))
    keys = []
    for tag in ("buildtool_depend", "depend", "build_depend", "build_export_depend",
                "exec_depend", "test_depend"):
        keys += [e.text.strip() for e in tree.getroot().iter(tag)]
    uses = []
    for key in dict.fromkeys(keys):
        if key in SYSTEM_KEYS:
            found = [p for p in SYSTEM_KEYS[key] if os.path.exists(p)]
            uses.append((f"package.xml dependency '{key}'", found[0] if found else None))
        else:
            code, out = run(["rospack", "find", key])
            path = os.path.join(out.strip(), "package.xml") if code == 0 else None
            uses.append((f"package.xml dependency '{key}' (rospack find)", path))
    return uses


def text_files():
    files = [os.path.join(ROOT, "README.md")]
    docs = os.path.join(ROOT, "docs")
    if os.path.isdir(docs):
        files += [os.path.join(docs, n) for n in sorted(os.listdir(docs)) if n.endswith(".md")]
    for folder, _, names in os.walk(os.path.join(ROOT, "launch_free_scripts")):
        files += [os.path.join(folder, n) for n in names if n.endswith((".sh", ".py"))]
    files.append(os.path.join(ROOT, ".ci", "run"))
    return [f for f in files if os.path.isfile(f) and f != os.path.abspath(__file__)]


def command_uses():
    words, rosruns = set(EXTRA_COMMANDS), set()
    for path in text_files():
        text = open(path, encoding="utf-8").read()
        words.update(re.findall(r"(?<![\w/.-])((?:ros|catkin_)[a-z_]+)\b", text))
        rosruns.update(re.findall(r"rosrun\s+([a-z_]+)\s+([A-Za-z_]+)", text))
    uses = []
    for word in sorted(words):
        exe = shutil.which(word, path="/usr/bin:/bin:/usr/sbin:/sbin")
        # A ros*/catkin_* word that is no command (a topic, a file name) is skipped;
        # the explicit list must resolve.
        if exe or word in EXTRA_COMMANDS:
            uses.append((f"command '{word}'", exe))
    for pkg, exe in sorted(rosruns):
        if pkg == "pc_ekf":
            continue
        found = [os.path.join(d, pkg, exe) for d in ("/usr/lib", "/usr/share")
                 if os.access(os.path.join(d, pkg, exe), os.X_OK)]
        uses.append((f"'rosrun {pkg} {exe}'", found[0] if found else None))
    return uses


def python_sources():
    """launch_free_scripts/lib/*.py, the Python programs in scripts/, the
    package scripts/pc_ekf_fleet and its tests (test/fleet)."""
    paths = []
    for folder in (("launch_free_scripts", "lib"), ("scripts", "pc_ekf_fleet"), ("test", "fleet")):
        folder = os.path.join(ROOT, *folder)
        paths += [os.path.join(folder, n) for n in sorted(os.listdir(folder)) if n.endswith(".py")]
    scripts = os.path.join(ROOT, "scripts")
    for name in sorted(os.listdir(scripts)) if os.path.isdir(scripts) else []:
        path = os.path.join(scripts, name)
        if os.path.isfile(path):
            with open(path, encoding="utf-8") as f:
                if "python" in f.readline():
                    paths.append(path)
    return paths


def python_module_uses():
    lib = os.path.join(ROOT, "launch_free_scripts", "lib")
    local = {n[:-3] for n in os.listdir(lib) if n.endswith(".py")}
    modules = set()
    for path in python_sources():
        for node in ast.walk(ast.parse(open(path).read())):
            if isinstance(node, ast.Import):
                modules.update(a.name.split(".")[0] for a in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                modules.add(node.module.split(".")[0])
    # This package's own modules: scripts/*.py are imported by test/fleet too.
    local |= {n[:-3] for n in os.listdir(os.path.join(ROOT, "scripts")) if n.endswith(".py")}
    modules -= local | {"pc_ekf", "pc_ekf_fleet"}
    probe = ("import importlib.util, sys\n"
             "for m in sys.argv[1:]:\n"
             "    s = importlib.util.find_spec(m)\n"
             "    o = s.origin if s and s.origin not in (None, 'built-in', 'frozen') else ''\n"
             "    if s and not o and s.submodule_search_locations:\n"
             "        o = list(s.submodule_search_locations)[0]\n"
             "    print(m, (o or 'builtin') if s else 'missing')\n")
    code, out = run(["/usr/bin/python3", "-c", probe] + sorted(modules))
    uses = []
    for line in out.splitlines():
        parts = line.split()
        module, origin = parts[0], parts[1]
        if origin == "builtin":
            continue  # compiled into the interpreter (python3 itself is checked)
        uses.append((f"python module '{module}'", None if origin == "missing" else origin))
    uses.append(("python interpreter /usr/bin/python3", "/usr/bin/python3"))
    return uses


def check(uses, covered):
    problems, lines = [], []
    for what, path in uses:
        if not path or not os.path.exists(path):
            problems.append(f"{what}: not found on this machine")
            continue
        pkg = owner(path)
        if pkg is None:
            problems.append(f"{what}: {path} belongs to no Debian package")
        elif pkg not in covered:
            problems.append(f"{what}: {path} is in Debian package '{pkg}', which "
                            "PC_EKF_APT_PACKAGES (launch_free_scripts/lib/common.sh) "
                            "neither lists nor pulls in: add it")
        lines.append(f"{what}: {path} ({pkg})")
    return problems, lines


def main():
    out, listed = sys.argv[1], sys.argv[2:]
    covered = closure(listed)
    cases = []
    for name, uses in (("package_xml", package_xml_uses()), ("commands", command_uses()),
                       ("python_modules", python_module_uses())):
        problems, lines = check(uses, covered)
        case = junit.Case(name, system_out="\n".join(lines))
        if problems:
            case.failure, case.failure_text = f"{len(problems)} not covered", "\n".join(problems)
            for p in problems:
                print(f"install list: {p}", file=sys.stderr)
        cases.append(case)
        print(f"install_list.{name}: {len(uses)} checked, {len(problems)} not covered",
              file=sys.stderr)
    sys.exit(1 if junit.write(out, "install_list", cases) else 0)


if __name__ == "__main__":
    main()
