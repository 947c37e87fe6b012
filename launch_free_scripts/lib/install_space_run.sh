# shellcheck shell=bash
# test.sh's install-space run (lib/package_checks.sh runs it with `env -i`
# so that nothing of the source tree or its devel space is on any path):
#   bash install_space_run.sh INSTALL_PREFIX
# With only INSTALL_PREFIX/setup.bash sourced: pc_ekf resolves to the install
# space, `rosrun pc_ekf estimator_node _config_file:=$(rospack find
# pc_ekf)/config/speed_bump.yaml` comes up on a roscore of its own and answers
# ~reset with its prior on parameter_estimate, `rosrun pc_ekf demo.sh
# --samples 10` runs end to end and writes its figure, plot_estimates runs by
# rosrun, and the scripts that need the sources refuse with a clear message.
# Prints what it checks; exits non-zero at the first failure.
set -uo pipefail
prefix=$1
fail() { echo "install space: FAILED: $*" >&2; exit 1; }

set +u
# shellcheck disable=SC1091
source "$prefix/setup.bash"
set -u
share=$(rospack find pc_ekf) || fail "rospack find pc_ekf"
[ "$share" = "$prefix/share/pc_ekf" ] || fail "rospack find pc_ekf is $share, not the install space"
echo "rospack find pc_ekf: $share"

# The issue-style command, by rosrun, on a roscore of our own.
source "$share/launch_free_scripts/lib/common.sh"
source "$share/launch_free_scripts/lib/roscore.sh"
[ "$PC_EKF_INSTALLED" = 1 ] || fail "the installed scripts do not see an install space"
trap pc_ekf_stop_owned EXIT
out=$PC_EKF_STATE/install_check
rm -rf "$out" && mkdir -p "$out"
pc_ekf_roscore_start "$out/roscore.log" || fail "roscore"
pc_ekf_start_owned estimator_node "$out/estimator_node.log" \
  rosrun pc_ekf estimator_node "_config_file:=$share/config/speed_bump.yaml" __name:=estimator_node
for _ in $(seq 300); do
  rosservice list 2>/dev/null | grep -qx /estimator_node/reset && break
  sleep 0.1
done
rosservice list 2>/dev/null | grep -qx /estimator_node/reset ||
  { tail -5 "$out/estimator_node.log" >&2; fail "rosrun pc_ekf estimator_node did not come up"; }
timeout 30 rostopic echo -n 1 /parameter_estimate/sample_index >"$out/prior.txt" 2>&1 &
echo_pid=$!
sleep 2  # rostopic echo subscribed
rosservice call /estimator_node/reset >"$out/reset.txt" 2>&1 || fail "~reset: $(cat "$out/reset.txt")"
wait "$echo_pid" || fail "no parameter_estimate after ~reset: $(cat "$out/prior.txt")"
grep -qx "0" "$out/prior.txt" || fail "the prior is not sample 0: $(cat "$out/prior.txt")"
echo "rosrun pc_ekf estimator_node: up, ~reset answered with its prior"
pc_ekf_stop_owned
trap - EXIT

# The demo from the install space (its own roscore, installed executables).
rosrun pc_ekf demo.sh --samples 10 >"$out/demo.txt" 2>"$out/demo.err" ||
  { tail -20 "$out/demo.err" >&2; fail "rosrun pc_ekf demo.sh --samples 10"; }
figure=$(sed -n 's/^figure: \([^ ]*\) (from 10 estimates)$/\1/p' "$out/demo.txt")
[ -n "$figure" ] && [ -s "$figure" ] || { cat "$out/demo.txt" >&2; fail "demo.sh printed no figure of 10 estimates"; }
case "$figure" in "$PC_EKF_STATE"/*) ;; *) fail "the demo wrote $figure, outside $PC_EKF_STATE" ;; esac
echo "rosrun pc_ekf demo.sh --samples 10: ok, figure $figure"

rosrun pc_ekf plot_estimates --help >"$out/plot_help.txt" 2>&1 || fail "rosrun pc_ekf plot_estimates --help"
echo "rosrun pc_ekf plot_estimates --help: ok"

for script in test.sh bench.sh; do
  rosrun pc_ekf "$script" >"$out/$script.txt" 2>&1
  rc=$?
  [ "$rc" = 2 ] && grep -q "run it from a clone" "$out/$script.txt" ||
    fail "rosrun pc_ekf $script: exit $rc, $(cat "$out/$script.txt")"
done
echo "test.sh, bench.sh: refused (they need the sources)"
