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
  type_hash   the RIHS01 type hash every cell endpoint announces, beside the built package's
"""

import argparse
import json
import math
import os
import sys
import threading
import time

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
from geometry_msgs.msg import Point

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
        for topic, msg_type, qos in TOPICS:
            name = f"{self.ns}/{topic}"
            self.subscriptions.append(
                self.node.create_subscription(
                    msg_type, name, lambda msg, name=name: self._sample(name, msg), qos
                )
            )
        # One client per action and service for the whole run: a client destroyed while the
        # executor spins can still be handed a late message (rclpy then raises in the executor
        # thread), and a fresh client's endpoints must be discovered again.
        self.actions = {a: ActionClient(self.node, _action_type(a), self.name(a)) for a in ACTIONS}
        self.clients = {}
        self.executor = MultiThreadedExecutor(num_threads=4)
        self.executor.add_node(self.node)
        threading.Thread(target=self.executor.spin, daemon=True).start()

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
        return f"{self.ns}/{relative}"

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
        seen.update(
            status=STATUS_NAMES.get(answer.status, answer.status),
            feedback_count=len(feedback),
            first_feedback=to_plain(feedback[0]) if feedback else None,
            last_feedback=to_plain(feedback[-1]) if feedback else None,
            seconds=round(time.monotonic() - t0, 2),
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
            job_id="jazzy-cancel", root_airfoil="s1223", root_chord_mm=150.0, machine_profile="grbl-xyuv", iterations=200000, seed=8
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

        def command(kind):
            request = SendMachineCommand.Request(command=MachineCommand(machine_id="", command=kind))
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
            resume = command(MachineCommand.COMMAND_RESUME)
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

    def check_type_hash(self):
        """Every endpoint of a cell node on a topic of the namespace, action topics and service
        request/reply topics included (raw DDS names: rt/, rq/, rr/)."""
        built = _built_hashes(self.args.install)
        prefixes = tuple(f"{p}{self.ns[1:]}/" for p in ("rt/", "rq/", "rr/"))
        for name, _ in sorted(self.node.get_topic_names_and_types(no_demangle=True)):
            if not name.startswith(prefixes):
                continue
            endpoints = [
                ("publisher", i) for i in self.node.get_publishers_info_by_topic(name, no_mangle=True)
            ] + [
                ("subscription", i)
                for i in self.node.get_subscriptions_info_by_topic(name, no_mangle=True)
            ]
            for kind, info in endpoints:
                if info.node_name == self.node.get_name():
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


CHECKS = ["graph", "params", "emit", "topic_emit", "plan", "sheet", "slice", "execute", "topics", "type_hash"]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ns", default="/cell", help="the cell nodes' namespace")
    parser.add_argument("--repo", required=True, help="the repository (config/ and tests/data/ inputs)")
    parser.add_argument("--install", required=True, help="cell_msgs' install prefix (type hashes)")
    parser.add_argument("--timeout", type=float, default=30.0, help="discovery and answer bound [s]")
    parser.add_argument("--slice-cancel-layer-mm", type=float, default=0.2)
    parser.add_argument("--only", nargs="*", choices=CHECKS, help="run only these checks")
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
