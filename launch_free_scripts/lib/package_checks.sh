# test.sh's install-space case: `catkin_make install` in the test workspace,
# then the example model package (test/plugin_example/pc_ekf_quarter_car)
# built in a workspace of its own against the install space only (its
# <pc_ekf/...> headers, libraries and pluginlib), the deprecated forwarding
# header <pc_ekf/io/model_type.h> compiled alone, the installed
# estimate_offline run once, no link from the install space into the sources,
# and, in an environment with the install space alone (lib/install_space_run.sh):
# rosrun estimator_node, demo.sh, plot_estimates. Writes
# RESULTS_DIR/install_space.xml (one case).
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
    elif ! printf '#include <pc_ekf/io/model_type.h>\nint main() { return !pc_ekf::ModelRegistry::builtins().find("roll_plane"); }\n' |
           g++ -std=c++17 -fsyntax-only -I"$PC_EKF_WS/install/include" -isystem /usr/include/eigen3 \
             -x c++ - >>"$log" 2>&1; then
      status=FAILED why="the deprecated <pc_ekf/io/model_type.h> does not compile against the install space"
    elif ! (set +u; source "$PC_EKF_WS/install/setup.bash"; set -u
            "$PC_EKF_WS/install/lib/pc_ekf/estimate_offline" \
              --config "$PC_EKF_WS/install/share/pc_ekf/config/speed_bump.yaml") >>"$log" 2>&1; then
      status=FAILED why="the installed estimate_offline failed"
    elif grep -rq -- "$PC_EKF_ROOT/src" "$down/build/pc_ekf_quarter_car/CMakeFiles/pc_ekf_quarter_car.dir/flags.make"; then
      status=FAILED why="the example package saw the source tree's headers"
    elif find "$PC_EKF_WS/install" -type l -lname "$PC_EKF_ROOT/*" | grep -q .; then
      status=FAILED why="the install space links into the source tree: $(find "$PC_EKF_WS/install" -type l -lname "$PC_EKF_ROOT/*" | head -3)"
    elif ! env -i HOME="$HOME" PATH=/usr/bin:/bin:/usr/sbin:/sbin \
             ROS_HOME="$PC_EKF_ROOT/.build/install_space_home" \
             bash "$PC_EKF_ROOT/launch_free_scripts/lib/install_space_run.sh" \
             "$PC_EKF_WS/install" >>"$log" 2>&1; then
      status=FAILED why="$(grep "install space: FAILED" "$log" | tail -1)"
    fi
  fi
  mkdir -p "$results"
  [ "$status" = ok ] && why=""
  pc_ekf_junit "$results/install_space.xml" install_space downstream_build \
    --failure "$why" --failure-text "$log" --tail 4000
  [ "$status" = ok ] || pc_ekf_log "install space check FAILED: $why (log: .build/install_check.log)"
}

# test.sh's catkin_lint case: no error and no warning in pc_ekf or the
# example package (--strict makes warnings fail too; notices, -W2, are not
# checked). Writes RESULTS_DIR/catkin_lint.xml.
pc_ekf_lint_check() {
  local results=$1 log=$PC_EKF_ROOT/.build/catkin_lint.log status=ok
  local problems=$PC_EKF_ROOT/.build/catkin_lint.problems failure=()
  (cd "$PC_EKF_WS/src" && catkin_lint -W1 --strict .) >"$log" 2>&1 || status=FAILED
  grep -qE ": (error|warning): " "$log" && status=FAILED
  mkdir -p "$results"
  if [ "$status" != ok ]; then
    # The failure's text: the errors and warnings, or the log's end without any.
    grep -E ": (error|warning): " "$log" >"$problems" || tail -c 2000 "$log" >"$problems"
    failure=(--failure "$(grep -cE ": (error|warning): " "$log") catkin_lint errors and warnings"
             --failure-text "$problems")
  fi
  pc_ekf_junit "$results/catkin_lint.xml" catkin_lint clean --system-out "$log" "${failure[@]}"
  [ "$status" = ok ] || pc_ekf_log "catkin_lint FAILED (log: .build/catkin_lint.log)"
}
