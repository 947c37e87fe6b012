# shellcheck shell=bash
# Processes a launch-free script starts and must stop: each runs in its own
# process group (setsid), is remembered by PID and stopped by that PID's
# group only - never by name, so other roscores and nodes on the machine are
# left alone. Source after common.sh; install the trap with
#   trap pc_ekf_stop_owned EXIT
# and start things with pc_ekf_start_owned / pc_ekf_roscore_start.

PC_EKF_OWNED_PIDS=()
PC_EKF_OWNED_NAMES=()
PC_EKF_OWNED_CHILDREN=()  # per owned process: "pid:start_time ..." of its own-session children
PC_EKF_LAST_PID=

# pc_ekf_start_owned NAME LOG COMMAND...: starts COMMAND in the background in
# a new session (its PID = its process group), output to LOG; sets
# PC_EKF_LAST_PID.
pc_ekf_start_owned() {
  local name=$1 log=$2
  shift 2
  # A non-interactive shell's background child is no group leader, so setsid
  # execs COMMAND directly: $! is COMMAND's PID and its group's ID.
  setsid "$@" >"$log" 2>&1 </dev/null &
  PC_EKF_LAST_PID=$!
  PC_EKF_OWNED_PIDS+=("$PC_EKF_LAST_PID")
  PC_EKF_OWNED_NAMES+=("$name")
  PC_EKF_OWNED_CHILDREN+=("")
}

# "PID:START_TIME" (start time in clock ticks since boot, /proc/PID/stat field
# 22): a PID that was reused by another process no longer matches it.
pc_ekf_process_identity() {
  local stat
  stat=$(cat "/proc/$1/stat" 2>/dev/null) || return 1
  stat=${stat##*) }  # fields after "(comm)", which may hold spaces
  echo "$1:$(echo "$stat" | cut -d' ' -f20)"
}

# Remembers the current children of the last started process. roslaunch (so
# roscore) starts rosmaster and rosout in sessions of their own, outside the
# group that pc_ekf_stop_group signals; they are checked after it stops.
pc_ekf_adopt_children() {
  local last=$((${#PC_EKF_OWNED_PIDS[@]} - 1)) child ids=""
  for child in $(pgrep -P "${PC_EKF_OWNED_PIDS[$last]}"); do
    ids+=" $(pc_ekf_process_identity "$child")"
  done
  PC_EKF_OWNED_CHILDREN[last]=$ids
}

# pc_ekf_stop_identity PID:START_TIME NAME: stops that process if it is
# still the same one (SIGINT, SIGTERM, SIGKILL).
pc_ekf_stop_identity() {
  local pid=${1%%:*} signal
  for signal in INT TERM KILL; do
    [ "$(pc_ekf_process_identity "$pid")" = "$1" ] || return 0
    kill -s "$signal" "$pid" 2>/dev/null
    for _ in $(seq 50); do
      [ "$(pc_ekf_process_identity "$pid")" = "$1" ] || return 0
      sleep 0.1
    done
    pc_ekf_log "$2 child (pid $pid) still running after SIG$signal"
  done
}

# True while any process of the group led by PID is alive.
pc_ekf_group_alive() { kill -0 -- "-$1" 2>/dev/null; }

# pc_ekf_stop_group PID NAME: SIGINT to the group (ROS nodes and roslaunch
# shut down cleanly on it), then SIGTERM, then SIGKILL; reaps the leader.
pc_ekf_stop_group() {
  local pid=$1 name=$2 signal
  for signal in INT TERM KILL; do
    pc_ekf_group_alive "$pid" || break
    kill -s "$signal" -- "-$pid" 2>/dev/null
    for _ in $(seq 50); do
      pc_ekf_group_alive "$pid" || break
      sleep 0.1
    done
    pc_ekf_group_alive "$pid" && pc_ekf_log "$name (pid $pid) still running after SIG$signal"
  done
  wait "$pid" 2>/dev/null || true
}

# Stops every owned process, the last started first (nodes before roscore).
pc_ekf_stop_owned() {
  local i child
  for ((i = ${#PC_EKF_OWNED_PIDS[@]} - 1; i >= 0; i--)); do
    pc_ekf_stop_group "${PC_EKF_OWNED_PIDS[$i]}" "${PC_EKF_OWNED_NAMES[$i]}"
    for child in ${PC_EKF_OWNED_CHILDREN[$i]}; do
      pc_ekf_stop_identity "$child" "${PC_EKF_OWNED_NAMES[$i]}"
    done
  done
  PC_EKF_OWNED_PIDS=()
  PC_EKF_OWNED_NAMES=()
  PC_EKF_OWNED_CHILDREN=()
}

# A TCP port nobody listens on now (the kernel's pick for port 0).
pc_ekf_free_port() {
  /usr/bin/python3 -c 'import socket
s = socket.socket(); s.bind(("", 0)); print(s.getsockname()[1]); s.close()'
}

# True when the master at $ROS_MASTER_URI answers.
pc_ekf_master_up() {
  /usr/bin/python3 -c 'import sys, xmlrpc.client
code, _, _ = xmlrpc.client.ServerProxy(sys.argv[1]).getPid("/pc_ekf_probe")
sys.exit(0 if code == 1 else 1)' "$ROS_MASTER_URI" 2>/dev/null
}

# pc_ekf_roscore_start LOG: roscore on a free port; exports ROS_MASTER_URI
# (and ROS_HOSTNAME=localhost unless ROS_HOSTNAME/ROS_IP are set, so the
# nodes reach each other whatever the machine's name resolves to). Sets
# PC_EKF_ROSCORE_PID. Retries with another port if the first is taken.
pc_ekf_roscore_start() {
  local log=$1 attempt port
  [ -z "${ROS_HOSTNAME:-}" ] && [ -z "${ROS_IP:-}" ] && export ROS_HOSTNAME=localhost
  for attempt in 1 2 3; do
    port=$(pc_ekf_free_port)
    export ROS_MASTER_URI="http://localhost:$port"
    pc_ekf_start_owned "roscore:$port" "$log" roscore -p "$port"
    PC_EKF_ROSCORE_PID=$PC_EKF_LAST_PID
    for _ in $(seq 300); do
      if pc_ekf_master_up; then
        # rosout may start a moment after the master.
        for _ in $(seq 50); do
          [ "$(pgrep -c -P "$PC_EKF_ROSCORE_PID")" -ge 2 ] && break
          sleep 0.1
        done
        pc_ekf_adopt_children
        return 0
      fi
      kill -0 "$PC_EKF_ROSCORE_PID" 2>/dev/null || break
      sleep 0.1
    done
    pc_ekf_log "roscore on port $port did not come up (attempt $attempt; log: $log)"
    pc_ekf_stop_group "$PC_EKF_ROSCORE_PID" "roscore:$port"
  done
  return 1
}
