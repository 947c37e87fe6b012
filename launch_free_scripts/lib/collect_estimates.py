#!/usr/bin/python3
"""Collects the estimator's answers for demo.sh (run by /usr/bin/python3 with
the workspace sourced, so rospy and pc_ekf.msg import).

Subscribes parameter_estimate, parameter_estimate/batch and ground_truth
(relative names), touches --ready once the estimator's publisher is
connected, waits for --expect estimates, optionally calls the estimator's
~estimate_batch service (std_srvs/Trigger) and waits for the batch result,
then prints one JSON object: counts, distinct stamps, the last one-step
estimate, the batch estimate, the ground truth.
"""
import argparse
import json
import pathlib
import sys
import threading
import time

import rospy
from pc_ekf.msg import ParameterEstimate
from std_srvs.srv import Trigger


def summary(msg):
    if msg is None:
        return None
    return {
        "stamp": msg.header.stamp.to_sec(),
        "sample_index": msg.sample_index,
        "method": msg.method,
        "update_rule": msg.update_rule,
        "healthy": msg.healthy,
        "warnings": list(msg.warnings),
        "parameters": [
            {"name": n, "mean": m, "stddev": s}
            for n, m, s in zip(msg.names, msg.mean, msg.stddev)
        ],
    }


class Collector:
    def __init__(self):
        self.lock = threading.Lock()
        self.estimates, self.batch, self.truth = [], None, None
        self.sub = rospy.Subscriber("parameter_estimate", ParameterEstimate, self.on_estimate,
                                    queue_size=100000)
        rospy.Subscriber("parameter_estimate/batch", ParameterEstimate, self.on_batch,
                         queue_size=10)
        rospy.Subscriber("ground_truth", ParameterEstimate, self.on_truth, queue_size=10)

    def on_estimate(self, msg):
        with self.lock:
            self.estimates.append(msg)

    def on_batch(self, msg):
        with self.lock:
            self.batch = msg

    def on_truth(self, msg):
        with self.lock:
            self.truth = msg


def wait_until(condition, timeout):
    deadline = time.monotonic() + timeout
    while not condition():
        if rospy.is_shutdown() or time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--expect", type=int, required=True, help="estimates to wait for")
    parser.add_argument("--ready", required=True, help="file touched once connected")
    parser.add_argument("--estimator", default="estimator_node", help="its node name")
    parser.add_argument("--batch", action="store_true", help="call ~estimate_batch at the end")
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds")
    args = parser.parse_args(rospy.myargv()[1:])

    rospy.init_node("demo_estimate_collector", anonymous=True)
    c = Collector()
    if not wait_until(lambda: c.sub.get_num_connections() > 0, args.timeout):
        print("collect_estimates: no estimator publishes parameter_estimate", file=sys.stderr)
        return 1
    pathlib.Path(args.ready).touch()
    wait_until(lambda: len(c.estimates) >= args.expect, args.timeout)
    time.sleep(0.5)  # an extra (duplicate) estimate would arrive now

    reply = None
    if args.batch:
        service = rospy.resolve_name(args.estimator) + "/estimate_batch"
        try:
            rospy.wait_for_service(service, timeout=5.0)
            response = rospy.ServiceProxy(service, Trigger)()
            reply = {"success": response.success, "message": response.message}
            if response.success:
                wait_until(lambda: c.batch is not None, 30.0)
        except (rospy.ROSException, rospy.ServiceException) as e:
            reply = {"success": False, "message": str(e)}

    with c.lock:
        stamps = {m.header.stamp.to_nsec() for m in c.estimates}
        result = {
            "received": len(c.estimates),
            "distinct_stamps": len(stamps),
            "last": summary(c.estimates[-1] if c.estimates else None),
            "batch": summary(c.batch),
            "batch_reply": reply,
            "truth": summary(c.truth),
        }
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
