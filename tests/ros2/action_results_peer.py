#!/usr/bin/env python3
"""A stock rclpy ActionClient asks a cell action server for a result late, as ROS 2 allows.

    action_results_peer.py --action NAME --ms MS [--timeout S]

Sends one cell_msgs/action/PlanHotwire goal (`iterations` = MS, the server's run time in the
test), asks for no result while it runs, and watches NAME/_action/status (a plain subscription,
transient local as rclcpp's status publisher) until the goal shows a terminal status. Then it
asks for the result twice with get_result_async. Prints one JSON line of what it saw; judges
nothing: tests/jazzy_action_results.rs asserts the outcome.
"""

import argparse
import json
import time

import rclpy
from action_msgs.msg import GoalStatus, GoalStatusArray
from rclpy.action import ActionClient
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from cell_msgs.action import PlanHotwire

TERMINAL = {
    GoalStatus.STATUS_SUCCEEDED: "SUCCEEDED",
    GoalStatus.STATUS_ABORTED: "ABORTED",
    GoalStatus.STATUS_CANCELED: "CANCELED",
}
NAMES = {
    GoalStatus.STATUS_UNKNOWN: "UNKNOWN",
    GoalStatus.STATUS_ACCEPTED: "ACCEPTED",
    GoalStatus.STATUS_EXECUTING: "EXECUTING",
    GoalStatus.STATUS_CANCELING: "CANCELING",
    **TERMINAL,
}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--action", required=True)
    parser.add_argument("--ms", type=int, required=True)
    parser.add_argument("--timeout", type=float, default=30.0)
    args = parser.parse_args()

    rclpy.init()
    node = rclpy.create_node("jazzy_results_peer")
    seen = []  # status names of our goal, in order, without repeats

    def on_status(array):
        for s in array.status_list:
            if goal_uuid is not None and bytes(s.goal_info.goal_id.uuid) == goal_uuid:
                name = NAMES.get(s.status, s.status)
                if not seen or seen[-1] != name:
                    seen.append(name)

    status_qos = QoSProfile(
        depth=1,
        history=HistoryPolicy.KEEP_LAST,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )
    goal_uuid = None
    node.create_subscription(GoalStatusArray, f"{args.action}/_action/status", on_status, status_qos)
    client = ActionClient(node, PlanHotwire, args.action)

    def wait(future, what):
        rclpy.spin_until_future_complete(node, future, timeout_sec=args.timeout)
        if not future.done():
            raise TimeoutError(what)
        return future.result()

    out = {"check": "late_result"}
    try:
        if not client.wait_for_server(timeout_sec=args.timeout):
            raise TimeoutError(f"action server {args.action}")
        handle = wait(client.send_goal_async(PlanHotwire.Goal(job_id="jazzy-late", iterations=args.ms)), "goal")
        out["accepted"] = handle.accepted
        goal_uuid = bytes(handle.goal_id.uuid)
        t0 = time.monotonic()
        deadline = t0 + args.timeout
        while not (seen and seen[-1] in TERMINAL.values()) and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.1)
        out["statuses"] = list(seen)
        out["terminal_after_s"] = round(time.monotonic() - t0, 2)
        # Well after the end: the server keeps the result (result_timeout) and answers each request.
        time.sleep(1.0)
        answers = []
        for _ in range(2):
            t = time.monotonic()
            answer = wait(handle.get_result_async(), "result")
            answers.append(
                {
                    "status": NAMES.get(answer.status, answer.status),
                    "message": answer.result.message,
                    "seconds": round(time.monotonic() - t, 2),
                }
            )
        out["answers"] = answers
        out["handle_status"] = NAMES.get(handle.status, handle.status)
    except Exception as e:  # reported, judged by the test
        out["error"] = f"{type(e).__name__}: {e}"
    print(json.dumps(out), flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
