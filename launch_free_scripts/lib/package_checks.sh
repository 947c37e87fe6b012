# test.sh's install-space case: `catkin_make install` in the test workspace,
# then the example model package (test/plugin_example/pc_ekf_quarter_car)
# built in a workspace of its own against the install space only (its
# <pc_ekf/...> headers, libraries and pluginlib), and the installed
# estimate_offline run once. Writes RESULTS_DIR/install_space.xml (one case).
pc_ekf_install_check() {
  local results=$1 log=$PC_EKF_ROOT/.build/install_check.log status=ok why=""
  local down=$PC_EKF_ROOT/.build/downstream_ws
  : >"$log"
  if ! (cd "$PC_EKF_WS" && catkin_make install -j"$(nproc)") >>"$log" 2>&1; then
    status=FAILED why="catkin_make install failed"
  else
    rm -rf "$down" && mkdir -p "$down/src"
    cp -r "$PC_EKF_ROOT/test/plugin_example/pc_ekf_quarter_car" "$down/src/"
    if ! (set +u; source "$PC_EKF_WS/install/setup.bash"; set -u
          cd "$down" && catkin_make -j"$(nproc)") >>"$log" 2>&1; then
      status=FAILED why="the example package did not build against the install space"
    elif ! (set +u; source "$PC_EKF_WS/install/setup.bash"; set -u
            "$PC_EKF_WS/install/lib/pc_ekf/estimate_offline" \
              --config "$PC_EKF_WS/install/share/pc_ekf/config/speed_bump.yaml") >>"$log" 2>&1; then
      status=FAILED why="the installed estimate_offline failed"
    elif grep -rq -- "$PC_EKF_ROOT/src" "$down/build/pc_ekf_quarter_car/CMakeFiles/pc_ekf_quarter_car.dir/flags.make"; then
      status=FAILED why="the example package saw the source tree's headers"
    fi
  fi
  mkdir -p "$results"
  /usr/bin/python3 - "$results/install_space.xml" "$status" "$why" "$log" <<'PY'
import sys, xml.etree.ElementTree as ET
out, status, why, log = sys.argv[1:]
suite = ET.Element("testsuite", name="install_space", tests="1", failures="0" if status == "ok" else "1")
case = ET.SubElement(suite, "testcase", classname="install_space", name="downstream_build")
if status != "ok":
    ET.SubElement(case, "failure", message=why).text = open(log).read()[-4000:]
ET.ElementTree(suite).write(out, encoding="utf-8", xml_declaration=True)
PY
  [ "$status" = ok ] || pc_ekf_log "install space check FAILED: $why (log: .build/install_check.log)"
}

# test.sh's catkin_lint case: no errors in pc_ekf or the example package
# (warnings are listed in the log). Writes RESULTS_DIR/catkin_lint.xml.
pc_ekf_lint_check() {
  local results=$1 log=$PC_EKF_ROOT/.build/catkin_lint.log status=ok
  (cd "$PC_EKF_WS/src" && catkin_lint -W1 .) >"$log" 2>&1 || status=FAILED
  grep -q ": error: " "$log" && status=FAILED
  mkdir -p "$results"
  /usr/bin/python3 - "$results/catkin_lint.xml" "$status" "$log" <<'PY'
import sys, xml.etree.ElementTree as ET
out, status, log = sys.argv[1:]
text = open(log).read()
suite = ET.Element("testsuite", name="catkin_lint", tests="1", failures="0" if status == "ok" else "1")
case = ET.SubElement(suite, "testcase", classname="catkin_lint", name="errors")
ET.SubElement(case, "system-out").text = text
if status != "ok":
    errors = [l for l in text.splitlines() if ": error: " in l]
    ET.SubElement(case, "failure", message="%d catkin_lint errors" % len(errors)).text = "\n".join(errors) or text[-2000:]
ET.ElementTree(suite).write(out, encoding="utf-8", xml_declaration=True)
PY
  [ "$status" = ok ] || pc_ekf_log "catkin_lint FAILED (log: .build/catkin_lint.log)"
}
