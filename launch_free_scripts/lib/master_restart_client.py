#!/usr/bin/python3
"""One side of master_restart_test.sh (run with the workspace sourced, so
rospy and pc_ekf.msg import): publishes samples FROM..TO (1-based rows of a
measurement CSV t,u1,u2,v1,v2) as suspension/joint_states stamped
1000 s + t, each once the estimator is connected and the previous estimate
arrived, and prints one JSON line per estimate (sample_index, mean, stddev).
--since T (wall time, s): also print how long after T the first estimate
arrived. --diagnostics: wait for the estimator's "checkpoints and master"
status and print its values. Exit 1 on a timeout.
"""
import argparse
import csv
import json
import sys
import threading
import time

import rospy
from collect_estimates import wait_until  # beside this script
from diagnostic_msgs.msg import DiagnosticArray
from pc_ekf.msg import ParameterEstimate
from sensor_msgs.msg import JointState


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--csv", required=True)
    parser.add_argument("--first", type=int, required=True)
    parser.add_argument("--last", type=int, required=True)
    parser.add_argument("--since", type=float)
    parser.add_argument("--diagnostics", action="store_true")
    parser.add_argument("--timeout", type=float, default=10.0, help="s per wait")
    args = parser.parse_args(rospy.myargv()[1:])
    with open(args.csv) as f:
        rows = list(csv.DictReader(f))

    rospy.init_node("master_restart_client", anonymous=True, disable_signals=True)
    lock = threading.Lock()
    estimates, upkeep = [], {}

    def on_estimate(msg):
        with lock:
            estimates.append((time.time(), msg))

    def on_diagnostics(msg):
        for s in msg.status:
            if s.name.endswith("checkpoints and master"):
                with lock:
                    upkeep.update({kv.key: kv.value for kv in s.values})

    sub = rospy.Subscriber("parameter_estimate", ParameterEstimate, on_estimate, queue_size=1000)
    pub = rospy.Publisher("suspension/joint_states", JointState, queue_size=1000)
    if args.diagnostics:
        rospy.Subscriber("/diagnostics", DiagnosticArray, on_diagnostics, queue_size=100)
    if not wait_until(lambda: pub.get_num_connections() > 0 and sub.get_num_connections() > 0,
                      args.timeout):
        print(json.dumps({"error": "estimator not connected within %g s" % args.timeout}))
        return 1
    for k in range(args.first, args.last + 1):
        row = rows[k - 1]
        t = float(row["t"])
        msg = JointState()
        msg.header.stamp = rospy.Time(1000) + rospy.Duration.from_sec(t)
        msg.name = ["left_suspension", "right_suspension"]
        msg.position = [float(row["u1"]), float(row["u2"])]
        msg.velocity = [float(row["v1"]), float(row["v2"])]
        before = len(estimates)
        pub.publish(msg)
        if not wait_until(lambda: len(estimates) > before, args.timeout):
            print(json.dumps({"error": "no estimate for sample %d within %g s" % (k, args.timeout)}))
            return 1
    with lock:
        for arrived, e in estimates:
            line = {"sample_index": e.sample_index, "mean": list(e.mean), "stddev": list(e.stddev)}
            if args.since is not None:
                line["after_master_s"] = arrived - args.since
            print(json.dumps(line))
    if args.diagnostics:
        if not wait_until(lambda: upkeep.get("master restarts (re-registered)", "0") != "0", 5.0):
            print(json.dumps({"error": "no diagnostics reporting the re-registration", **upkeep}))
            return 1
        with lock:
            print(json.dumps({"diagnostics": upkeep}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
