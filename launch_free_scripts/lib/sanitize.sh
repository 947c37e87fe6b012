# test.sh --sanitize: the catkin workspace .build/catkin_ws_sanitize built
# with AddressSanitizer + UndefinedBehaviorSanitizer (GCC's, RelWithDebInfo),
# and the sanitizer reports of every instrumented process the tests start
# (gtests, tools they run, nodes rostest launches) collected as one test case.
# Source after common.sh.

PC_EKF_SANITIZE_FLAGS="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer -Wno-maybe-uninitialized"

pc_ekf_sanitize_cmake_args() {
  echo "-DCMAKE_CXX_FLAGS=$PC_EKF_SANITIZE_FLAGS"
  echo "-DCMAKE_EXE_LINKER_FLAGS=$PC_EKF_SANITIZE_FLAGS"
  echo "-DCMAKE_SHARED_LINKER_FLAGS=$PC_EKF_SANITIZE_FLAGS"
}

# ASan and LSan reports go to LOG_DIR/asan.<pid> (log_path) instead of the
# test's output, so a report after a test has written its passing XML (a
# leak found at exit) is still seen. GCC's UBSan runtime, linked beside
# ASan's, ignores log_path and prints to stderr (checked with a one-line
# out-of-bounds program): its "runtime error:" lines are found in the test
# log and in the ROS logs, which go to LOG_DIR/ros_log for this run.
# Leak suppressions: lib/lsan.supp.
pc_ekf_sanitize_env() {
  local dir=$1
  rm -rf "$dir"
  mkdir -p "$dir/ros_log"
  export ROS_LOG_DIR=$dir/ros_log
  export ASAN_OPTIONS="log_path=$dir/asan:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1"
  export UBSAN_OPTIONS="log_path=$dir/ubsan:print_stacktrace=1:halt_on_error=1"
  export LSAN_OPTIONS="suppressions=$PC_EKF_ROOT/launch_free_scripts/lib/lsan.supp:print_suppressions=0"
}

# Writes RESULTS/sanitizer.xml: test case sanitizer.reports, failed with the
# summary of each report file in LOG_DIR and of each UBSan "runtime error:"
# in TEXT_LOG... and LOG_DIR/ros_log.
#   pc_ekf_sanitize_results RESULTS LOG_DIR [TEXT_LOG...]
pc_ekf_sanitize_results() {
  PYTHONPATH=$PC_EKF_JUNIT_PATH /usr/bin/python3 - "$1/sanitizer.xml" "$2" "${@:3}" <<'PY'
import glob, os, re, sys
import junit
out, logs, texts = sys.argv[1], sys.argv[2], sys.argv[3:]
texts += [p for p in glob.glob(os.path.join(logs, "ros_log", "**"), recursive=True) if os.path.isfile(p)]
found = []  # (where, summary lines)
for path in sorted(glob.glob(os.path.join(logs, "*san.*"))):
    lines = open(path, errors="replace").read().splitlines()
    keep = [l for l in lines if re.search(r"ERROR:|SUMMARY:|runtime error:|^\s+#[0-5] ", l)]
    found.append((os.path.basename(path), keep[:12]))
for path in texts:
    lines = open(path, errors="replace").read().splitlines()
    for i, l in enumerate(lines):
        if "runtime error:" in l:
            found.append(("%s line %d" % (path, i + 1), lines[i:i + 6]))
case = junit.Case("reports")
if found:
    case.failure = "%d sanitizer report(s)" % len(found)
    case.failure_text = "\n".join("%s:\n  %s" % (where, "\n  ".join(keep)) for where, keep in found)
    print(case.failure_text)
junit.write(out, "sanitizer", [case])
PY
}
