# Shared by the launch-free scripts: apt dependencies and the catkin workspace.
# Source it; it sets PC_EKF_ROOT, PC_EKF_WS, PC_EKF_STATE (where runs write),
# PC_EKF_RESULTS, PC_EKF_EXE_DIR, PC_EKF_SETUP and puts /usr/bin first in PATH (a pyenv
# python3 earlier on PATH lacks catkin_pkg and breaks catkin).
#
# The scripts run from a clone (they build .build/catkin_ws and write below
# .build) or from an install space (`catkin_make install`: they are in
# share/pc_ekf/launch_free_scripts, next to no CMakeLists.txt; they use the
# installed executables, build nothing and write below ROS_HOME, ~/.ros).

PC_EKF_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
PC_EKF_WS=${PC_EKF_WS:-$PC_EKF_ROOT/.build/catkin_ws}
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
if [ -f "$PC_EKF_ROOT/CMakeLists.txt" ]; then
  PC_EKF_INSTALLED=0
  PC_EKF_STATE=$PC_EKF_ROOT/.build
  export ROS_HOME=${ROS_HOME:-$PC_EKF_STATE/ros_home}
  export ROS_LOG_DIR=${ROS_LOG_DIR:-$ROS_HOME/log}
  PC_EKF_EXE_DIR=$PC_EKF_WS/devel/lib/pc_ekf
  PC_EKF_SETUP=$PC_EKF_WS/devel/setup.bash
  PC_EKF_RESULTS=$PC_EKF_ROOT/results
else
  PC_EKF_INSTALLED=1
  PC_EKF_PREFIX=$(cd "$PC_EKF_ROOT/../.." && pwd)
  PC_EKF_STATE=${ROS_HOME:-$HOME/.ros}/pc_ekf
  PC_EKF_EXE_DIR=$PC_EKF_PREFIX/lib/pc_ekf
  PC_EKF_SETUP=$PC_EKF_PREFIX/setup.bash
  PC_EKF_RESULTS=$PC_EKF_STATE/results
fi

PC_EKF_APT_PACKAGES=(
  build-essential cmake libeigen3-dev libboost-dev libyaml-cpp-dev libgtest-dev
  libbenchmark-dev ros-core-dev python3-rostest python3-roslaunch python3-rosmaster
  python3-rosbag rosbash libnav-msgs-dev libdiagnostic-updater-dev libnodeletlib-dev libnodeletlib-tools colcon
  python3-colcon-ros python3-matplotlib python3-numpy python3-rospy python3-std-srvs
  python3-tk                     # plot_estimates' live window (matplotlib's TkAgg)
  python3-sensor-msgs python3-diagnostic-msgs  # master_restart_client.py
  catkin-lint                    # test.sh: the package is catkin_lint clean
  nlohmann-json3-dev             # estimate_offline's JSON output
  clang libclang-rt-14-dev llvm  # fuzz targets: clang, libFuzzer + ASan/UBSan runtimes, llvm-symbolizer
  ccache                         # compiler cache: clones and worktrees on one machine share objects
  python3-distributed            # scripts/estimate_fleet: Dask (dask-scheduler, dask-worker, client); optional at run time
  python3-pytest                 # test.sh: estimate_fleet's modules (test/fleet)
  time                           # bench.sh (lib/bench_long.sh): estimate_offline's peak RSS, /usr/bin/time -v
)

pc_ekf_log() { echo "[pc_ekf] $*" >&2; }

# The scripts' own JUnit results (test.sh counts them): one test case,
#   pc_ekf_junit OUT.xml SUITE CASE [--time S] [--system-out FILE]
#                [--failure MESSAGE] [--failure-text FILE] [--tail N]
# (an empty MESSAGE is a pass). Python callers import lib/junit.py with
# PYTHONPATH=$PC_EKF_JUNIT_PATH.
PC_EKF_JUNIT_PATH=$PC_EKF_ROOT/launch_free_scripts/lib
pc_ekf_junit() { /usr/bin/python3 "$PC_EKF_JUNIT_PATH/junit.py" "$@"; }

# Installs whatever of PC_EKF_APT_PACKAGES (plus "$@") is missing.
pc_ekf_ensure_packages() {
  local missing=() p
  for p in "${PC_EKF_APT_PACKAGES[@]}" "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  pc_ekf_log "installing missing packages: ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq >&2 || return 1
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >&2 || return 1
}

# catkin workspace whose src/ links to the repository, and to the example
# model plugin package (test/plugin_example/pc_ekf_quarter_car: a package of
# its own, built against pc_ekf like a user's would be; its rostest is
# estimator_plugin_model).
pc_ekf_prepare_workspace() {
  mkdir -p "$PC_EKF_WS/src" "$PC_EKF_ROOT/.build"
  ln -sfn "$PC_EKF_ROOT" "$PC_EKF_WS/src/pc_ekf"
  ln -sfn "$PC_EKF_ROOT/test/plugin_example/pc_ekf_quarter_car" "$PC_EKF_WS/src/pc_ekf_quarter_car"
}

# catkin_make in the workspace; extra arguments go to catkin_make.
# With ccache on PATH the compiler calls go through it, paths relative to the
# clone (CCACHE_BASEDIR), so two clones of one tree share their objects.
pc_ekf_catkin_make() {
  pc_ekf_prepare_workspace
  local launcher=()
  if command -v ccache >/dev/null 2>&1 && [ "${PC_EKF_CCACHE:-1}" != 0 ]; then
    export CCACHE_BASEDIR="$PC_EKF_ROOT" CCACHE_NOHASHDIR=1
    launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
  fi
  (cd "$PC_EKF_WS" && catkin_make -DCMAKE_BUILD_TYPE="${PC_EKF_BUILD_TYPE:-Release}" \
     -DCATKIN_ENABLE_TESTING=ON "${launcher[@]}" "$@" -j"$(nproc)")
}

# Builds from the sources (log .build/build.log; arguments go to catkin_make);
# an install space is used as it is.
pc_ekf_build() {
  [ "$PC_EKF_INSTALLED" = 1 ] && return 0
  pc_ekf_log "building (log: .build/build.log)"
  mkdir -p "$PC_EKF_ROOT/.build"
  pc_ekf_catkin_make "$@" >"$PC_EKF_ROOT/.build/build.log" 2>&1 || {
    tail -30 "$PC_EKF_ROOT/.build/build.log" >&2; return 1; }
}

# For the scripts that build and test the package itself (test.sh, bench.sh,
# fuzz.sh): refuses to run from an install space, naming the script.
pc_ekf_require_sources() {
  [ "$PC_EKF_INSTALLED" = 0 ] && return 0
  echo "$1: builds and tests pc_ekf from its sources, which an install space does not" \
    "have ($PC_EKF_ROOT); run it from a clone of the repository" >&2
  exit 2
}

pc_ekf_source_workspace() {
  # setup.bash reads unset variables; relax nounset around it.
  set +u
  # shellcheck disable=SC1090
  source "$PC_EKF_SETUP"
  set -u
}

# Sets PC_EKF_BIN (the tools' folder): as given, or installs what is missing
# and builds (log .build/build.log); the install space's own from there.
pc_ekf_tools_bin() {
  [ -n "${PC_EKF_BIN:-}" ] && return 0
  pc_ekf_ensure_packages || return 1
  pc_ekf_build || return 1
  PC_EKF_BIN=$PC_EKF_EXE_DIR
}
