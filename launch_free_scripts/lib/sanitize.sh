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

# Every report goes to LOG_DIR/{asan,ubsan}.<pid> (log_path) instead of the
# test's output, so a report after a test has written its passing XML (a
# leak found at exit) is still seen. Leak suppressions: lib/lsan.supp.
pc_ekf_sanitize_env() {
  local dir=$1
  rm -rf "$dir"
  mkdir -p "$dir"
  export ASAN_OPTIONS="log_path=$dir/asan:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1"
  export UBSAN_OPTIONS="log_path=$dir/ubsan:print_stacktrace=1:halt_on_error=1"
  export LSAN_OPTIONS="suppressions=$PC_EKF_ROOT/launch_free_scripts/lib/lsan.supp:print_suppressions=0"
}

# Writes RESULTS/sanitizer.xml: test case sanitizer.reports, failed with the
# summary of each report file in LOG_DIR.
pc_ekf_sanitize_results() {
  /usr/bin/python3 - "$1/sanitizer.xml" "$2" <<'PY'
import glob, os, re, sys, xml.etree.ElementTree as ET
out, logs = sys.argv[1], sys.argv[2]
reports = sorted(glob.glob(os.path.join(logs, "*san.*")))
suite = ET.Element("testsuite", name="sanitizer", tests="1", failures=str(int(bool(reports))))
case = ET.SubElement(suite, "testcase", classname="sanitizer", name="reports")
if reports:
    text = []
    for path in reports:
        lines = open(path, errors="replace").read().splitlines()
        keep = [l for l in lines if re.search(r"ERROR:|SUMMARY:|runtime error:|^\s+#[0-5] ", l)]
        text.append("%s:\n  %s" % (os.path.basename(path), "\n  ".join(keep[:12])))
    ET.SubElement(case, "failure", message="%d sanitizer report(s) in %s" % (len(reports), logs)).text = "\n".join(text)
    print("\n".join(text))
ET.ElementTree(suite).write(out, encoding="utf-8", xml_declaration=True)
PY
}
