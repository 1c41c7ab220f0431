#!/usr/bin/env python3
"""A stock ROS 2 Jazzy peer for the cell nodes: rclpy on Fast DDS (rmw_fastrtps_cpp) with the
cell_msgs package built by stock rosidl (build_msgs.sh), as an integrator's own code would be.

    jazzy_peer.py --ns /cell --repo REPO [--timeout S] [--only CHECK ...]

Prints one JSON object a line, {"check": NAME, ...what it saw}, for every check; a check that
raised prints {"check": NAME, "error": TEXT} and the others still run. The exit status is 0
unless the peer itself could not start. It judges nothing: tests/ros2_jazzy.rs asserts the
outcomes. The checks, in order (CHECKS below):
  graph       the cell nodes, actions and services are discovered
  params      each node's parameters: list, get, and a set that the node refuses
  emit        the emitter's emit_program service: a good Toolpath and a bad one
  topic_emit  a Toolpath published on <ns>/toolpath becomes a MachineProgram on machine_program
  plan        plan_hotwire: a rejected goal, a goal with feedback and result, a canceled goal
  sheet       sequence_sheet: feedback and result, then a canceled goal
  slice       slice: feedback and result, then a canceled goal
  execute     execute_program on the GRBL simulator: feedback, hold and resume through the
              send_machine_command service, result; then a canceled goal
  topics      one decoded sample of every cell topic (subscribed before the jobs ran)
  views       the standard-type views of the jobs' toolpaths and heat maps, with the stock
              types: <toolpath>/path (nav_msgs/Path) and <toolpath>/markers
              (visualization_msgs/MarkerArray) beside the Toolpath of the same stamp,
              <heat map>/image (sensor_msgs/Image) beside the HeatMap of the same stamp
  machine_views  the bridge's views after the programs ran: joint_states (sensor_msgs/JointState)
              and /tf (tf2_msgs/TFMessage) beside the MachineStatus of the same stamp,
              /tf_static, /diagnostics (diagnostic_msgs/DiagnosticArray)
  sim_time    the peer is the time source: it publishes /clock (rosgraph_msgs/Clock) and a
              Toolpath to an emitter started with use_sim_time:=true (namespace --sim-ns),
              whose MachineProgram is stamped with the peer's clock
  bag_clock   the replayer is the time source: /clock while it plays a bag (it waits for the
              peer's subscriber on <sim-ns>/bag_chatter)
  rosout      the log lines of every cell node on /rosout (rcl_interfaces/Log)
  type_hash   the RIHS01 type hash every cell endpoint announces, beside the built package's
Only with --only (a bridge driving the Marlin simulator marlin-sim must be running):
  heaters     the printer's hotend on marlin_sim/temperature/hotend (sensor_msgs/Temperature)
              and its heaters' values in /diagnostics
"""

import argparse
import json
import math
import os
import sys
import threading
import time

import numpy
import rclpy
from action_msgs.msg import GoalStatus
from rclpy.action import ActionClient
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import GetParameters, ListParameters, SetParameters

from cell_msgs.action import ExecuteProgram, PlanHotwire, SequenceSheet, Slice
from cell_msgs.msg import (
    CutPlan,
    HeatMap,
    LayerStack,
    MachineCommand,
    MachineProgram,
    MachineStatus,
    Toolpath,
    ToolpathSegment,
)
from cell_msgs.srv import EmitProgram, SendMachineCommand
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Point
from nav_msgs.msg import Path
from rcl_interfaces.msg import Log
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Image, JointState, Temperature
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage  # the stand-in build_msgs.sh builds (no wheel on PyPI)
from visualization_msgs.msg import Marker, MarkerArray

STATUS_NAMES = {
    GoalStatus.STATUS_UNKNOWN: "UNKNOWN",
    GoalStatus.STATUS_ACCEPTED: "ACCEPTED",
    GoalStatus.STATUS_EXECUTING: "EXECUTING",
    GoalStatus.STATUS_CANCELING: "CANCELING",
    GoalStatus.STATUS_SUCCEEDED: "SUCCEEDED",
    GoalStatus.STATUS_CANCELED: "CANCELED",
    GoalStatus.STATUS_ABORTED: "ABORTED",
}

# The cell nodes' QoS presets (crates/runtime/src/qos.rs).
PLAN_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
    history=HistoryPolicy.KEEP_LAST,
    depth=16,
)
STREAM_QOS = QoSProfile(
    reliability=ReliabilityPolicy.BEST_EFFORT,
    durability=DurabilityPolicy.VOLATILE,
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
)
STATUS_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
    history=HistoryPolicy.KEEP_LAST,
    depth=32,
)

# Every topic the cell nodes publish in the test's wiring (tests/ros2_jazzy.rs): the sequencer's
# and slicer's toolpaths are remapped as in launch_scripts/demo.launch.yaml.
TOPICS = [
    ("toolpath", Toolpath, PLAN_QOS),
    ("sheet_toolpath", Toolpath, PLAN_QOS),
    ("waam_toolpath", Toolpath, PLAN_QOS),
    ("cut_plan", CutPlan, PLAN_QOS),
    ("layer_stack", LayerStack, PLAN_QOS),
    ("machine_program", MachineProgram, PLAN_QOS),
    ("exposure", HeatMap, STREAM_QOS),
    ("exposure_matrix", HeatMap, STREAM_QOS),
    ("sheet_heat", HeatMap, STREAM_QOS),
    ("machine_status", MachineStatus, STATUS_QOS),
]

# A ROS 2 time source (rclcpp's ClockQoS), tf2's static broadcaster and rcl's /rosout.
CLOCK_QOS = QoSProfile(
    reliability=ReliabilityPolicy.BEST_EFFORT,
    durability=DurabilityPolicy.VOLATILE,
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
)
TF_STATIC_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
    history=HistoryPolicy.KEEP_LAST,
    depth=16,
)
ROSOUT_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
    history=HistoryPolicy.KEEP_LAST,
    depth=1000,
)

TOOLPATH_TOPICS = ["toolpath", "sheet_toolpath", "waam_toolpath"]
HEAT_TOPICS = ["exposure", "exposure_matrix", "sheet_heat"]

# The standard-type views (crates/runtime/src/views.rs); relative names are in the namespace.
VIEWS = (
    [(f"{t}/path", Path, PLAN_QOS) for t in TOOLPATH_TOPICS]
    + [(f"{t}/markers", MarkerArray, PLAN_QOS) for t in TOOLPATH_TOPICS]
    + [(f"{t}/image", Image, STATUS_QOS) for t in HEAT_TOPICS]
    + [
        ("joint_states", JointState, STATUS_QOS),
        # The printer marlin-sim's hotend (the `heaters` check): <machine as a name
        # token>/temperature/<heater>.
        ("marlin_sim/temperature/hotend", Temperature, STATUS_QOS),
        ("/tf", TFMessage, STATUS_QOS),
        ("/tf_static", TFMessage, TF_STATIC_QOS),
        ("/diagnostics", DiagnosticArray, STATUS_QOS),
        ("/rosout", Log, ROSOUT_QOS),
    ]
)

NODES = ["planner", "sequencer", "slicer", "emitter", "machine_bridge"]
ACTIONS = ["plan_hotwire", "sequence_sheet", "slice", "execute_program"]
SERVICES = ["emit_program", "machine_command"]


def emit(check, **fields):
    print(json.dumps({"check": check, **fields}, default=str), flush=True)


def to_plain(value):
    """A message as JSON-ready data (rosidl_runtime_py is not among the wheels we install)."""
    if hasattr(value, "get_fields_and_field_types"):
        return {f: to_plain(getattr(value, f)) for f in value.get_fields_and_field_types()}
    if isinstance(value, (list, tuple)) or type(value).__name__ in ("array", "ndarray"):
        return [to_plain(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, bytes):
        return list(value)
    return value


class Waiter:
    """Waits for rclpy futures and conditions while the executor spins in its own thread."""

    def __init__(self, timeout):
        self.timeout = timeout

    def future(self, future, what, timeout=None):
        done = threading.Event()
        future.add_done_callback(lambda _: done.set())
        if not done.wait(timeout or self.timeout):
            raise TimeoutError(f"{what}: no answer in {timeout or self.timeout} s")
        if future.exception() is not None:
            raise future.exception()
        return future.result()

    def until(self, condition, what, timeout=None):
        """Polls `condition` (graph state, samples received) until it is true."""
        deadline = time.monotonic() + (timeout or self.timeout)
        while time.monotonic() < deadline:
            value = condition()
            if value:
                return value
            time.sleep(0.05)
        raise TimeoutError(f"{what}: not within {timeout or self.timeout} s")


# How long a goal's late feedback may trail its result (see `run_goal`).
FEEDBACK_GRACE_S = 0.5


def toolpath_summary(tp):
    points = sum(len(s.points) for s in tp.segments)
    return {
        "job_id": tp.job_id,
        "frame_id": tp.header.frame_id,
        "process": tp.process,
        "power_unit": tp.power_unit,
        "segments": len(tp.segments),
        "points": points,
        "kinds": sorted({s.kind for s in tp.segments}),
    }


def program_summary(p):
    text = p.files[0].text if p.files else ""
    return {
        "job_id": p.job_id,
        "dialect": p.dialect,
        "machine_profile": p.machine_profile,
        "files": [f.name for f in p.files],
        "line_count": p.line_count,
        "sha256": p.sha256,
        "motion_lines": sum(1 for line in text.splitlines() if line.lstrip().startswith(("G0", "G1"))),
    }


def wing_panel(job_id, feed=4.0, n=24):
    """A 4-axis hot-wire loop (root on X/Y, a smaller tip on U/V) inside grbl-xyuv's travel."""
    root, tip = [], []
    for i in range(n + 1):
        t = 2 * math.pi * i / n
        c, s = math.cos(t), math.sin(t)
        root.append(Point(x=90 + 60 * c, y=60 + 8 * s * (1 + 0.3 * c), z=0.0))
        tip.append(Point(x=95 + 45 * c, y=60 + 6 * s * (1 + 0.3 * c), z=0.0))
    cut = ToolpathSegment(
        kind=ToolpathSegment.KIND_CUT,
        points=root,
        secondary_points=tip,
        feed_mm_s=[feed] * len(root),
        power=[1.5] * len(root),
    )
    tp = Toolpath(
        job_id=job_id,
        process=Toolpath.PROCESS_HOTWIRE,
        power_unit=Toolpath.POWER_WIRE_CURRENT_A,
        plane_separation_mm=1000.0,
        segments=[cut],
    )
    tp.header.frame_id = "machine"
    return tp


class Peer:
    def __init__(self, args):
        self.args = args
        self.ns = args.ns.rstrip("/")
        self.node = Node("jazzy_peer")
        self.wait = Waiter(args.timeout)
        self.samples = {}
        self.lock = threading.Lock()
        self.subscriptions = []
        self.sim_ns = args.sim_ns.rstrip("/")
        self.started = time.time()
        for topic, msg_type, qos in TOPICS + VIEWS + [
            (f"{self.sim_ns}/machine_program", MachineProgram, PLAN_QOS)
        ]:
            name = self.name(topic)
            self.subscriptions.append(
                self.node.create_subscription(
                    msg_type, name, lambda msg, name=name: self._sample(name, msg), qos
                )
            )
        # One client per action and service for the whole run: a client destroyed while the
        # executor spins can still be handed a late message (rclpy then raises in the executor
        # thread), and a fresh client's endpoints must be discovered again.
        self.actions = {a: ActionClient(self.node, _action_type(a), self.name(a)) for a in ACTIONS}
        # Every feedback message by goal, from a plain subscription: an ActionClient forgets a
        # goal's feedback callback once its result is in, and drops feedback it takes after that
        # (the result is taken first when both wait), though the server sent it first.
        self.feedback = {}
        for a in ACTIONS:
            self.subscriptions.append(
                self.node.create_subscription(
                    _action_type(a).Impl.FeedbackMessage,
                    f"{self.name(a)}/_action/feedback",
                    self._feedback,
                    QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE),
                )
            )
        self.clients = {}
        self.executor = MultiThreadedExecutor(num_threads=4)
        self.executor.add_node(self.node)
        threading.Thread(target=self.executor.spin, daemon=True).start()

    def _feedback(self, msg):
        with self.lock:
            self.feedback.setdefault(bytes(msg.goal_id.uuid), []).append(msg.feedback)

    def _sample(self, topic, msg):
        with self.lock:
            self.samples.setdefault(topic, []).append(msg)

    def client(self, srv_type, name):
        """The service client for `name`, made once and discovered."""
        if name not in self.clients:
            self.clients[name] = self.node.create_client(srv_type, name)
        client = self.clients[name]
        if not client.wait_for_service(timeout_sec=self.args.timeout):
            raise TimeoutError(f"service {name}")
        return client

    def name(self, relative):
        return relative if relative.startswith("/") else f"{self.ns}/{relative}"

    def received(self, topic):
        with self.lock:
            return list(self.samples.get(self.name(topic), []))

    def repo_file(self, relative):
        return os.path.join(self.args.repo, relative)

    # -- graph -------------------------------------------------------------------------------

    def check_graph(self):
        def nodes_up():
            names = {
                (ns.rstrip("/") + "/" + n) for n, ns in self.node.get_node_names_and_namespaces()
            }
            return all(self.name(n) in names for n in NODES) and names

        names = self.wait.until(nodes_up, "the cell nodes")
        for action, client in self.actions.items():
            if not client.wait_for_server(timeout_sec=self.args.timeout):
                raise TimeoutError(f"action server {self.name(action)}")
        services = dict(self.node.get_service_names_and_types())
        topics = dict(self.node.get_topic_names_and_types())
        emit(
            "graph",
            nodes=sorted(n for n in names if n.startswith(self.ns + "/")),
            actions=[self.name(a) for a in ACTIONS],
            services={k: v for k, v in services.items() if k.startswith(self.ns + "/")},
            topics={k: v for k, v in topics.items() if k.startswith(self.ns + "/")},
        )

    # -- parameters --------------------------------------------------------------------------

    def check_params(self):
        for node in NODES:
            base = self.name(node)
            lister = self.client(ListParameters, f"{base}/list_parameters")
            getter = self.client(GetParameters, f"{base}/get_parameters")
            setter = self.client(SetParameters, f"{base}/set_parameters")
            listed = self.wait.future(
                lister.call_async(ListParameters.Request(depth=0)), f"{base}/list_parameters"
            ).result.names
            # The node's own parameters are read once at start-up, so a set is refused; the
            # first one (machine_profile where there is one) is the one set.
            own = [n for n in listed if n != "use_sim_time"]
            own.sort(key=lambda n: n != "machine_profile")
            wanted = own[:1] + [n for n in listed if n == "use_sim_time"]
            got = self.wait.future(
                getter.call_async(GetParameters.Request(names=wanted)), f"{base}/get_parameters"
            ).values
            values = {name: _param_value(v) for name, v in zip(wanted, got)}
            target = wanted[0]
            new_value = _changed(got[0])
            results = self.wait.future(
                setter.call_async(
                    SetParameters.Request(parameters=[Parameter(name=target, value=new_value)])
                ),
                f"{base}/set_parameters",
            ).results
            after = self.wait.future(
                getter.call_async(GetParameters.Request(names=[target])), f"{base}/get_parameters"
            ).values
            emit(
                "params",
                node=base,
                listed=sorted(listed),
                values=values,
                set_name=target,
                set_successful=[r.successful for r in results],
                set_reason=[r.reason for r in results],
                value_after_set=_param_value(after[0]) if after else None,
            )

    # -- the emitter -------------------------------------------------------------------------

    def check_emit(self):
        client = self.client(EmitProgram, self.name("emit_program"))
        good = self.wait.future(
            client.call_async(
                EmitProgram.Request(
                    toolpath=wing_panel("jazzy-emit"), machine_profile="grbl-xyuv", job_id=""
                )
            ),
            "emit_program",
        )
        emit(
            "emit",
            case="good",
            success=good.success,
            message=good.message,
            program=program_summary(good.program),
        )
        self.emitted = good.program
        bad = self.wait.future(
            client.call_async(
                EmitProgram.Request(toolpath=wing_panel("jazzy-bad", feed=0.0), machine_profile="grbl-xyuv")
            ),
            "emit_program",
        )
        emit("emit", case="bad", success=bad.success, message=bad.message, files=len(bad.program.files))

    def check_topic_emit(self):
        topic = self.name("toolpath")
        publisher = self.node.create_publisher(Toolpath, topic, PLAN_QOS)
        self.wait.until(lambda: publisher.get_subscription_count() > 0, f"a subscriber of {topic}")
        publisher.publish(wing_panel("jazzy-topic"))

        def program():
            with self.lock:
                return next(
                    (p for p in self.samples.get(self.name("machine_program"), []) if p.job_id == "jazzy-topic"),
                    None,
                )

        emit("topic_emit", program=program_summary(self.wait.until(program, "the program of jazzy-topic")))

    # -- actions -----------------------------------------------------------------------------

    def run_goal(self, action, goal, cancel_after_feedback=False, during=None):
        """Sends `goal`; returns what was seen. With cancel_after_feedback, asks to cancel at the
        first feedback; `during(feedback)` runs at the first feedback otherwise."""
        client = self.actions[action]
        if not client.wait_for_server(timeout_sec=self.args.timeout):
            raise TimeoutError(f"action server {self.name(action)}")
        feedback = []
        first = threading.Event()

        def on_feedback(message):
            feedback.append(message.feedback)
            first.set()

        t0 = time.monotonic()
        handle = self.wait.future(client.send_goal_async(goal, feedback_callback=on_feedback), f"{action} goal")
        seen = {"accepted": handle.accepted}
        if not handle.accepted:
            return seen
        result_future = handle.get_result_async()
        if cancel_after_feedback or during:
            if not first.wait(self.args.timeout):
                raise TimeoutError(f"{action}: no feedback")
        if cancel_after_feedback:
            cancel = self.wait.future(handle.cancel_goal_async(), f"{action} cancel")
            seen["cancel_return_code"] = cancel.return_code
            seen["goals_canceling"] = len(cancel.goals_canceling)
        elif during:
            seen.update(during(feedback))
        answer = self.wait.future(result_future, f"{action} result", timeout=3 * self.args.timeout)
        seconds = round(time.monotonic() - t0, 2)
        # Feedback and the result travel on different DDS endpoints, and ROS 2 does not order one
        # against the other: a feedback sent just before the result may land just after it. It
        # still counts (the plain subscription's copy; see __init__).
        time.sleep(FEEDBACK_GRACE_S)
        with self.lock:
            every = list(self.feedback.get(bytes(handle.goal_id.uuid), feedback))
        seen.update(
            status=STATUS_NAMES.get(answer.status, answer.status),
            feedback_count=len(every),
            first_feedback=to_plain(every[0]) if every else None,
            last_feedback=to_plain(every[-1]) if every else None,
            seconds=seconds,
        )
        seen["result"] = answer.result
        return seen

    def check_plan(self):
        goal = PlanHotwire.Goal(
            job_id="jazzy-wing",
            root_airfoil="s1223",
            root_chord_mm=150.0,
            machine_profile="grbl-xyuv",
            iterations=60,
            seed=7,
        )
        bad = PlanHotwire.Goal(job_id="jazzy-bad", root_airfoil="s1223", root_chord_mm=-1.0)
        emit("plan", case="rejected", **self.run_goal("plan_hotwire", bad))
        seen = self.run_goal("plan_hotwire", goal)
        r = seen.pop("result")
        emit(
            "plan",
            case="goal",
            **seen,
            success=r.success,
            message=r.message,
            toolpath=toolpath_summary(r.toolpath),
            final_loss=r.final_loss,
            baseline_loss=r.baseline_loss,
        )
        long = PlanHotwire.Goal(
            job_id="jazzy-cancel", root_airfoil="s1223", root_chord_mm=150.0, machine_profile="grbl-xyuv", iterations=100000, seed=8
        )
        seen = self.run_goal("plan_hotwire", long, cancel_after_feedback=True)
        r = seen.pop("result")
        emit("plan", case="cancel", **seen, success=r.success, message=r.message)

    def check_sheet(self):
        layout = self.repo_file("config/sheets/plate-nest.json")
        goal = SequenceSheet.Goal(
            job_id="jazzy-sheet", layout_file=layout, improve=True, time_budget_s=1.0, machine_profile="grbl-laser", seed=3
        )
        seen = self.run_goal("sequence_sheet", goal)
        r = seen.pop("result")
        emit(
            "sheet",
            case="goal",
            **seen,
            success=r.success,
            message=r.message,
            order=list(r.plan.order),
            cut_length_mm=r.plan.cut_length_mm,
            toolpath=toolpath_summary(r.toolpath),
        )
        long = SequenceSheet.Goal(
            job_id="jazzy-sheet-cancel", layout_file=layout, improve=True, time_budget_s=120.0, machine_profile="grbl-laser", seed=4
        )
        seen = self.run_goal("sequence_sheet", long, cancel_after_feedback=True)
        r = seen.pop("result")
        emit("sheet", case="cancel", **seen, success=r.success, message=r.message)

    def check_slice(self):
        goal = Slice.Goal(job_id="jazzy-waam", stl_file=self.repo_file("tests/data/stl/20mm-xyz-cube.stl"))
        seen = self.run_goal("slice", goal)
        r = seen.pop("result")
        report = json.loads(r.report_json) if r.report_json else {}
        emit(
            "slice",
            case="goal",
            **seen,
            success=r.success,
            message=r.message,
            layers=len(r.layer_stack.layers),
            contours=sum(len(layer.contours) for layer in r.layer_stack.layers),
            toolpath=toolpath_summary(r.toolpath),
            report_keys=sorted(report) if isinstance(report, dict) else [],
        )
        long = Slice.Goal(
            job_id="jazzy-waam-cancel",
            stl_file=self.repo_file("tests/data/stl/torus.STL"),
            layer_height_mm=self.args.slice_cancel_layer_mm,
        )
        seen = self.run_goal("slice", long, cancel_after_feedback=True)
        r = seen.pop("result")
        emit("slice", case="cancel", **seen, success=r.success, message=r.message)

    def _stopped_in_hold(self):
        with self.lock:
            last = self.samples.get(self.name("machine_status"), [])[-2:]
        return (
            len(last) == 2
            and all(s.state == MachineStatus.STATE_HOLD for s in last)
            and list(last[0].axis_positions) == list(last[1].axis_positions)
        )

    def check_execute(self):
        program = getattr(self, "emitted", None)
        if program is None or not program.files:
            raise RuntimeError("no program from emit_program to run")
        commands = self.client(SendMachineCommand, self.name("machine_command"))

        # An empty machine_id addresses every machine for hold and abort only; a resume names it.
        def command(kind, machine_id=""):
            request = SendMachineCommand.Request(command=MachineCommand(machine_id=machine_id, command=kind))
            answer = self.wait.future(commands.call_async(request), "machine_command")
            return {"success": answer.success, "message": answer.message}

        def hold_and_resume(feedback):
            hold = command(MachineCommand.COMMAND_HOLD)
            held = self.wait.until(
                lambda: any(f.state == MachineStatus.STATE_HOLD for f in feedback), "feedback in HOLD"
            )
            # GRBL takes a cycle start only once the hold is complete (Hold:0, stopped); the
            # status says HOLD from the start of the deceleration, so wait until it stands still.
            self.wait.until(self._stopped_in_hold, "the machine standing still in HOLD")
            resume = command(MachineCommand.COMMAND_RESUME, "cutter")
            emit("execute", case="hold", hold=hold, resume=resume, feedback=len(feedback))
            return {"hold": hold, "saw_hold": bool(held), "resume": resume}

        seen = self.run_goal("execute_program", ExecuteProgram.Goal(program=program), during=hold_and_resume)
        r = seen.pop("result")
        emit(
            "execute",
            case="goal",
            **seen,
            success=r.success,
            message=r.message,
            outcome=r.outcome,
            final_state=r.final_state,
            last_acked_line=r.last_acked_line,
            program_lines=program.line_count,
        )
        seen = self.run_goal("execute_program", ExecuteProgram.Goal(program=program), cancel_after_feedback=True)
        r = seen.pop("result")
        emit("execute", case="cancel", **seen, success=r.success, message=r.message, outcome=r.outcome)

    # -- topics and type hashes --------------------------------------------------------------

    def check_topics(self):
        for topic, msg_type, _ in TOPICS:
            name = self.name(topic)
            try:
                msg = self.wait.until(lambda: self.samples.get(name), f"a sample on {name}", timeout=10)[-1]
                with self.lock:
                    count = len(self.samples[name])
                summary = {
                    Toolpath: lambda m: toolpath_summary(m),
                    MachineProgram: lambda m: program_summary(m),
                    HeatMap: lambda m: {
                        "quantity": m.quantity,
                        "width": m.width,
                        "height": m.height,
                        "cells": len(m.data),
                    },
                    CutPlan: lambda m: {"job_id": m.job_id, "order": list(m.order), "policy": m.policy},
                    LayerStack: lambda m: {"job_id": m.job_id, "layers": len(m.layers)},
                    MachineStatus: lambda m: {
                        "machine_id": m.machine_id,
                        "state": m.state,
                        "axis_names": list(m.axis_names),
                        "axis_positions": list(m.axis_positions),
                    },
                }[msg_type](msg)
                emit("topics", topic=name, type=_type_name(msg_type), count=count, sample=summary)
            except TimeoutError as e:
                emit("topics", topic=name, type=_type_name(msg_type), count=0, error=str(e))

    # -- standard-type views -------------------------------------------------------------------

    def _by_stamp(self, topic, stamp, stamp_of=lambda m: m.header.stamp):
        """The last sample on `topic` stamped `stamp`."""
        return next((m for m in reversed(self.received(topic)) if _same_time(stamp_of(m), stamp)), None)

    def _viewed(self, view_topic, source_topic, stamp_of):
        """The last view on `view_topic` with a source sample of the same stamp: (view, source)."""

        def pair():
            for view in reversed(self.received(view_topic)):
                source = self._by_stamp(source_topic, stamp_of(view))
                if source is not None:
                    return view, source
            return None

        return self.wait.until(pair, f"a view on {self.name(view_topic)} of a sample on {source_topic}", timeout=10)

    def check_views(self):
        for topic in TOOLPATH_TOPICS:
            path, tp = self._viewed(f"{topic}/path", topic, lambda p: p.header.stamp)
            points = [p for s in tp.segments for p in s.points]
            poses = [p.pose.position for p in path.poses]
            diffs = [
                max(abs(q.x - p.x / 1000.0), abs(q.y - p.y / 1000.0), abs(q.z - p.z / 1000.0))
                for q, p in zip(poses, points)
            ]
            emit(
                "views",
                view="path",
                topic=self.name(f"{topic}/path"),
                count=len(self.received(f"{topic}/path")),
                job_id=tp.job_id,
                frame_id=path.header.frame_id,
                toolpath_frame_id=tp.header.frame_id,
                pose_frame_ids=sorted({p.header.frame_id for p in path.poses}),
                poses=len(poses),
                points=len(points),
                max_abs_diff_m=max(diffs, default=None),
                equal_poses=sum(d == 0.0 for d in diffs),
            )
            array, tp = self._viewed(
                f"{topic}/markers", topic, lambda a: a.markers[0].header.stamp if a.markers else None
            )
            # What the toolpath asks for, per (kind, layer, secondary): line pairs and the first
            # point drawn (a segment of fewer than two points draws nothing).
            groups = {}
            for s in tp.segments:
                for secondary, pts in ((False, s.points), (True, s.secondary_points)):
                    if len(pts) < 2:
                        continue
                    g = groups.setdefault(
                        (s.kind, s.layer, secondary), {"pairs": 0, "first_mm": [pts[0].x, pts[0].y, pts[0].z]}
                    )
                    g["pairs"] += len(pts) - 1
            emit(
                "views",
                view="markers",
                topic=self.name(f"{topic}/markers"),
                count=len(self.received(f"{topic}/markers")),
                job_id=tp.job_id,
                toolpath_frame_id=tp.header.frame_id,
                first_action=array.markers[0].action,
                markers=[
                    {
                        "ns": m.ns,
                        "id": m.id,
                        "type": m.type,
                        "action": m.action,
                        "frame_id": m.header.frame_id,
                        "points": len(m.points),
                        "first_m": [m.points[0].x, m.points[0].y, m.points[0].z] if m.points else None,
                        "color": [m.color.r, m.color.g, m.color.b, m.color.a],
                        "scale_x": m.scale.x,
                    }
                    for m in array.markers[1:]
                ],
                groups=[{"kind": k, "layer": layer, "secondary": sec, **g} for (k, layer, sec), g in groups.items()],
            )
        for topic in HEAT_TOPICS:
            image, heat = self._viewed(f"{topic}/image", topic, lambda i: i.header.stamp)
            images = self.received(f"{topic}/image")
            matched = equal = 0
            for i in images:
                h = self._by_stamp(topic, i.header.stamp)
                if h is None:
                    continue
                matched += 1
                # The image's bytes as little-endian float32, bit for bit against the HeatMap's.
                got = numpy.frombuffer(bytes(i.data), dtype="<u4")
                want = numpy.asarray(h.data, dtype=numpy.float32).view(numpy.uint32)
                equal += int((i.width, i.height) == (h.width, h.height) and numpy.array_equal(got, want))
            emit(
                "views",
                view="image",
                topic=self.name(f"{topic}/image"),
                count=len(images),
                heat_maps=len(self.received(topic)),
                matched=matched,
                equal=equal,
                encodings=sorted({i.encoding for i in images}),
                is_bigendian=sorted({i.is_bigendian for i in images}),
                steps_ok=sum(i.step == 4 * i.width and len(i.data) == i.step * i.height for i in images),
                width=image.width,
                height=image.height,
                step=image.step,
                frame_id=image.header.frame_id,
                heat_width=heat.width,
                heat_height=heat.height,
                heat_frame_id=heat.header.frame_id,
            )

    def check_machine_views(self):
        status_topic = "machine_status"

        def moved(status):
            return any(p != 0.0 for p in status.axis_positions)

        def joint_state_of_a_move():
            for js in reversed(self.received("joint_states")):
                s = self._by_stamp(status_topic, js.header.stamp)
                if s is not None and moved(s):
                    return js, s
            return None

        js, status = self.wait.until(joint_state_of_a_move, "a joint state of a moved machine", timeout=10)
        emit(
            "machine_views",
            view="joint_states",
            count=len(self.received("joint_states")),
            frame_id=js.header.frame_id,
            name=list(js.name),
            position=list(js.position),
            velocity=len(js.velocity),
            effort=len(js.effort),
            machine_id=status.machine_id,
            axis_names=list(status.axis_names),
            axis_positions=list(status.axis_positions),
            max_abs_diff_m=max(abs(q - p / 1000.0) for q, p in zip(js.position, status.axis_positions)),
        )

        def tool_frame_of_a_move():
            for message in reversed(self.received("/tf")):
                for t in message.transforms:
                    s = self._by_stamp(status_topic, t.header.stamp)
                    if s is not None and moved(s):
                        return t, s
            return None

        t, status = self.wait.until(tool_frame_of_a_move, "a tool frame of a moved machine", timeout=10)
        axis = dict(zip(status.axis_names, status.axis_positions))
        tr, rot = t.transform.translation, t.transform.rotation
        emit(
            "machine_views",
            view="tf",
            count=len(self.received("/tf")),
            parent=t.header.frame_id,
            child=t.child_frame_id,
            translation=[tr.x, tr.y, tr.z],
            rotation=[rot.x, rot.y, rot.z, rot.w],
            axis_positions=list(status.axis_positions),
            max_abs_diff_m=max(
                abs(tr.x - axis.get("X", 0.0) / 1000.0),
                abs(tr.y - axis.get("Y", 0.0) / 1000.0),
                abs(tr.z - axis.get("Z", 0.0) / 1000.0),
            ),
        )
        pairs = sorted(
            {(t.header.frame_id, t.child_frame_id) for m in self.received("/tf_static") for t in m.transforms}
        )
        emit("machine_views", view="tf_static", count=len(self.received("/tf_static")), frames=pairs)

        def latest_diagnostics():
            # The last array that a later status follows: the status of its own tick, sent
            # before it, has surely arrived.
            statuses = self.received(status_topic)
            newest = _ns(statuses[-1].header.stamp) if statuses else 0
            arrays = [a for a in self.received("/diagnostics") if a.status and _ns(a.header.stamp) < newest]
            return arrays[-1] if arrays else None

        array = self.wait.until(latest_diagnostics, "a diagnostic array", timeout=10)
        # The status the bridge reported last before it: the same tick's, or the one before.
        before = [s for s in self.received(status_topic) if _ns(s.header.stamp) <= _ns(array.header.stamp)]
        status = before[-1] if before else None
        emit(
            "machine_views",
            view="diagnostics",
            count=len(self.received("/diagnostics")),
            stamp_ns=_ns(array.header.stamp),
            status=[
                {
                    "name": d.name,
                    "level": _byte(d.level),
                    "message": d.message,
                    "hardware_id": d.hardware_id,
                    "values": {kv.key: kv.value for kv in d.values},
                }
                for d in array.status
            ],
            last_status=None
            if status is None
            else {
                "stamp_ns": _ns(status.header.stamp),
                "state": status.state,
                "axis_names": list(status.axis_names),
                "axis_positions": list(status.axis_positions),
            },
        )

    # -- time sources ----------------------------------------------------------------------------

    def check_sim_time(self):
        """The peer as the time source of an emitter on simulated time: a clock that starts at
        --sim-time-s and advances 0.1 s a tick, every 0.1 s; a Toolpath; the program's stamp."""
        clock = self.node.create_publisher(Clock, "/clock", CLOCK_QOS)
        toolpaths = self.node.create_publisher(Toolpath, f"{self.sim_ns}/toolpath", PLAN_QOS)
        try:
            # The emitter's /clock reader (the cell nodes' other /clock readers are ros2-client's,
            # of builtin_interfaces/Time: they never match) and its toolpath reader.
            self.wait.until(lambda: clock.get_subscription_count() > 0, "a /clock reader on sim time")
            self.wait.until(lambda: toolpaths.get_subscription_count() > 0, f"a reader of {self.sim_ns}/toolpath")
            ticks = []
            stop = threading.Event()

            def tick():
                t = int(self.args.sim_time_s * 1e9)
                while not stop.is_set():
                    ticks.append(t)
                    clock.publish(Clock(clock=_time(t)))
                    t += 100_000_000
                    stop.wait(0.1)

            ticker = threading.Thread(target=tick, daemon=True)
            ticker.start()
            # Best effort: until the emitter's reader has matched the peer's writer, ticks are
            # lost and its time is still zero (as rclpy's would be), so its program says 0.
            # Send toolpaths until a program carries a clock time; each is reported.
            attempts = []
            try:
                for attempt in range(1, 8):
                    job_id = f"jazzy-sim-{attempt}"
                    toolpaths.publish(wing_panel(job_id))

                    def program(job_id=job_id):
                        return next((p for p in self.received(f"{self.sim_ns}/machine_program") if p.job_id == job_id), None)

                    p = self.wait.until(program, f"the program of {job_id}", timeout=self.args.timeout)
                    attempts.append({"job_id": job_id, "stamp_ns": _ns(p.header.stamp), "ticks_sent": len(ticks)})
                    if _ns(p.header.stamp) != 0:
                        break
            finally:
                stop.set()
                ticker.join()
            stamp = attempts[-1]["stamp_ns"]
            emit(
                "sim_time",
                attempts=attempts,
                stamp_ns=stamp,
                first_tick_ns=ticks[0],
                last_tick_ns=ticks[-1],
                ticks=len(ticks),
                stamp_is_a_tick=stamp in ticks,
                wall_ns=time.time_ns(),
            )
        finally:
            self.node.destroy_publisher(toolpaths)
            self.node.destroy_publisher(clock)

    def check_bag_clock(self):
        """The cell's replayer as the time source: /clock while it plays a bag, which it starts
        once this peer subscribes to the bag's topic <sim-ns>/bag_chatter."""
        ticks, chatter = [], []
        lock = threading.Lock()

        def on_clock(m):
            with lock:
                ticks.append(_ns(m.clock))

        def on_chatter(m):
            with lock:
                chatter.append((m.data, ticks[-1] if ticks else None))

        subs = [
            self.node.create_subscription(Clock, "/clock", on_clock, CLOCK_QOS),
            self.node.create_subscription(String, f"{self.sim_ns}/bag_chatter", on_chatter, STATUS_QOS),
        ]
        try:

            def ended():
                with lock:
                    return any(text == "end" for text, _ in chatter)

            self.wait.until(ended, "the bag's last message", timeout=3 * self.args.timeout)
            # The ticks up to the end of the bag (the replayer keeps its clock while it lingers).
            self.wait.until(lambda: len(ticks) > 0, "a /clock tick")
            with lock:
                seen, texts = list(ticks), list(chatter)
            emit(
                "bag_clock",
                ticks=len(seen),
                first_ns=seen[0],
                last_ns=seen[-1],
                monotonic=all(a <= b for a, b in zip(seen, seen[1:])),
                chatter=[text for text, _ in texts],
                clock_at_chatter_ns=[at for _, at in texts],
            )
        finally:
            for sub in subs:
                self.node.destroy_subscription(sub)

    # -- /rosout ---------------------------------------------------------------------------------

    def check_rosout(self):
        # rcl's logger names: namespace and node name joined by dots (/cell/emitter: cell.emitter).
        prefix = self.ns.strip("/").replace("/", ".")
        loggers = [f"{prefix}.{n}" if prefix else n for n in NODES]

        def every_node_logged():
            names = {line.name for line in self.received("/rosout")}
            return all(n in names for n in loggers)

        try:
            self.wait.until(every_node_logged, "a /rosout line of every cell node", timeout=10)
        except TimeoutError:
            pass  # what was seen is reported; the test names who is missing
        lines = self.received("/rosout")
        by_name = {}
        for line in lines:
            entry = by_name.setdefault(
                line.name,
                {"count": 0, "levels": set(), "min_stamp_ns": None, "max_stamp_ns": None, "sample": None, "worst": None},
            )
            entry["count"] += 1
            entry["levels"].add(line.level)
            t = _ns(line.stamp)
            entry["min_stamp_ns"] = t if entry["min_stamp_ns"] is None else min(t, entry["min_stamp_ns"])
            entry["max_stamp_ns"] = t if entry["max_stamp_ns"] is None else max(t, entry["max_stamp_ns"])
            seen = {"level": line.level, "msg": line.msg, "function": line.function, "line": line.line}
            if entry["sample"] is None or line.level == Log.INFO:
                entry["sample"] = seen
            if entry["worst"] is None or line.level > entry["worst"]["level"]:
                entry["worst"] = seen
        for entry in by_name.values():
            entry["levels"] = sorted(entry["levels"])
        emit(
            "rosout",
            lines=len(lines),
            by_name=by_name,
            # The emitter's INFO line for the program it made of the peer's toolpath.
            emitter_topic_lines=[
                {"name": line.name, "level": line.level, "msg": line.msg}
                for line in lines
                if "jazzy-topic" in line.msg and line.name == loggers[NODES.index("emitter")]
            ][:3],
            peer_started_ns=int(self.started * 1e9),
            now_ns=time.time_ns(),
        )

    def check_heaters(self):
        hotend = "marlin_sim/temperature/hotend"
        t = self.wait.until(lambda: (self.received(hotend) or [None])[-1], "a hotend temperature")
        emit(
            "heaters",
            view="temperature",
            count=len(self.received(hotend)),
            frame_id=t.header.frame_id,
            stamp_ns=_ns(t.header.stamp),
            temperature=t.temperature,
            variance=t.variance,
        )

        def printer_status():
            for array in reversed(self.received("/diagnostics")):
                for d in array.status:
                    if d.hardware_id == "marlin-sim" and any(kv.key.startswith("heater/") for kv in d.values):
                        return d
            return None

        d = self.wait.until(printer_status, "the printer's heaters in /diagnostics")
        emit("heaters", view="diagnostics", name=d.name, values={kv.key: kv.value for kv in d.values})

    def check_type_hash(self):
        """Every endpoint of a cell node (namespaces --ns and --sim-ns) on any topic: the
        namespace's topics, action topics and service request/reply topics (raw DDS names: rt/,
        rq/, rr/), and the global ones (/tf, /tf_static, /diagnostics, /clock, /rosout,
        /parameter_events)."""
        built = _built_hashes(self.args.install)
        cell = {self.ns, self.sim_ns}
        for name, _ in sorted(self.node.get_topic_names_and_types(no_demangle=True)):
            endpoints = [
                ("publisher", i) for i in self.node.get_publishers_info_by_topic(name, no_mangle=True)
            ] + [
                ("subscription", i)
                for i in self.node.get_subscriptions_info_by_topic(name, no_mangle=True)
            ]
            for kind, info in endpoints:
                if info.node_name == self.node.get_name() or info.node_namespace.rstrip("/") not in cell:
                    continue
                type_name = _ros_type_name(info.topic_type)
                # A service's request and reply endpoints may carry the service's own hash.
                service = type_name.rsplit("_", 1)[0] if type_name.endswith(("_Request", "_Response")) else None
                emit(
                    "type_hash",
                    topic=name,
                    kind=kind,
                    node=f"{info.node_namespace.rstrip('/')}/{info.node_name}",
                    type=type_name,
                    announced=str(info.topic_type_hash),
                    built=built.get(type_name),
                    built_service=built.get(service) if service else None,
                )


def _ros_type_name(dds_or_ros):
    """`cell_msgs::msg::dds_::Toolpath_` or `cell_msgs/msg/Toolpath` -> `cell_msgs/msg/Toolpath`."""
    if "::dds_::" in dds_or_ros:
        package, kind, _, name = dds_or_ros.split("::")
        return f"{package}/{kind}/{name.rstrip('_')}"
    return dds_or_ros


def _ns(t):
    """builtin_interfaces/Time in nanoseconds."""
    return t.sec * 1_000_000_000 + t.nanosec


def _time(ns):
    from builtin_interfaces.msg import Time

    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def _same_time(a, b):
    return a is not None and b is not None and (a.sec, a.nanosec) == (b.sec, b.nanosec)


def _byte(value):
    """A `byte` field (rclpy gives bytes of length 1) as an int."""
    return value[0] if isinstance(value, (bytes, bytearray)) else int(value)


def _action_type(name):
    return {
        "plan_hotwire": PlanHotwire,
        "sequence_sheet": SequenceSheet,
        "slice": Slice,
        "execute_program": ExecuteProgram,
    }[name]


def _type_name(msg_type):
    module = msg_type.__module__.split(".")
    return f"{module[0]}/{module[1]}/{msg_type.__name__}"


def _param_value(v):
    return {
        ParameterType.PARAMETER_NOT_SET: None,
        ParameterType.PARAMETER_BOOL: v.bool_value,
        ParameterType.PARAMETER_INTEGER: v.integer_value,
        ParameterType.PARAMETER_DOUBLE: v.double_value,
        ParameterType.PARAMETER_STRING: v.string_value,
        ParameterType.PARAMETER_BYTE_ARRAY: list(v.byte_array_value),
        ParameterType.PARAMETER_BOOL_ARRAY: list(v.bool_array_value),
        ParameterType.PARAMETER_INTEGER_ARRAY: list(v.integer_array_value),
        ParameterType.PARAMETER_DOUBLE_ARRAY: list(v.double_array_value),
        ParameterType.PARAMETER_STRING_ARRAY: list(v.string_array_value),
    }.get(v.type, f"type {v.type}")


def _changed(v):
    """A value of the same type as `v` and different from it."""
    new = ParameterValue(type=v.type)
    if v.type == ParameterType.PARAMETER_BOOL:
        new.bool_value = not v.bool_value
    elif v.type == ParameterType.PARAMETER_INTEGER:
        new.integer_value = v.integer_value + 1
    elif v.type == ParameterType.PARAMETER_DOUBLE:
        new.double_value = v.double_value + 1.0
    elif v.type == ParameterType.PARAMETER_STRING_ARRAY:
        new.string_array_value = list(v.string_array_value) + ["changed"]
    else:
        new.type = ParameterType.PARAMETER_STRING
        new.string_value = v.string_value + "-changed"
    return new


def _built_hashes(install):
    """Type name -> RIHS01 hash, from the type descriptions rosidl wrote beside the interface
    files (share/<package>/{msg,srv,action}/<T>.json): cell_msgs' install prefix first, then
    the other prefixes on AMENT_PREFIX_PATH (the wheels' std_msgs, rcl_interfaces, ...)."""
    hashes = {}
    prefixes = [install] + os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep)
    for prefix in filter(None, prefixes):
        share = os.path.join(prefix, "share")
        for package in sorted(os.listdir(share)) if os.path.isdir(share) else []:
            for kind in ("msg", "srv", "action"):
                folder = os.path.join(share, package, kind)
                for file in sorted(os.listdir(folder)) if os.path.isdir(folder) else []:
                    if file.endswith(".json"):
                        with open(os.path.join(folder, file)) as f:
                            for entry in json.load(f).get("type_hashes", []):
                                hashes.setdefault(entry["type_name"], entry["hash_string"])
    return hashes


CHECKS = [
    "graph",
    "params",
    "emit",
    "topic_emit",
    "plan",
    "sheet",
    "slice",
    "execute",
    "topics",
    "views",
    "machine_views",
    "sim_time",
    "bag_clock",
    "rosout",
    "type_hash",
]
# Checks that run only when --only names them.
EXTRA_CHECKS = ["heaters"]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ns", default="/cell", help="the cell nodes' namespace")
    parser.add_argument("--repo", required=True, help="the repository (config/ and tests/data/ inputs)")
    parser.add_argument("--install", required=True, help="cell_msgs' install prefix (type hashes)")
    parser.add_argument("--timeout", type=float, default=30.0, help="discovery and answer bound [s]")
    parser.add_argument("--slice-cancel-layer-mm", type=float, default=0.2)
    parser.add_argument("--sim-ns", default="/sim", help="namespace of the emitter on simulated time")
    parser.add_argument("--sim-time-s", type=float, default=1_000_000_000.0, help="the peer's /clock start [s]")
    parser.add_argument("--only", nargs="*", choices=CHECKS + EXTRA_CHECKS, help="run only these checks")
    args = parser.parse_args()
    rclpy.init()
    peer = Peer(args)
    for check in args.only or CHECKS:
        t0 = time.monotonic()
        try:
            getattr(peer, f"check_{check}")()
        except Exception as e:  # one failing check must not hide the others
            emit(check, error=f"{type(e).__name__}: {e}")
        print(f"jazzy_peer: {check} took {time.monotonic() - t0:.1f} s", file=sys.stderr, flush=True)
    peer.executor.shutdown(timeout_sec=2)
    peer.node.destroy_node()
    rclpy.try_shutdown()


if __name__ == "__main__":
    main()
