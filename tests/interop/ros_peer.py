#!/usr/bin/env python3
"""Cyclone DDS test peer speaking ROS 2 topic/type naming, for cellsuite interop tests.

listen: print one JSON line per sample received on each rt/<NAME>; exit 0 when every
        topic got one, 3 on timeout.
talk:   publish a std_msgs/String on rt/<NAME> COUNT times, PERIOD seconds apart.
"""

import argparse
import json
import os
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

# Loopback-only discovery config next to this file, unless the caller chose one; set before
# cyclonedds (and its bundled libddsc) is imported.
os.environ.setdefault("CYCLONEDDS_URI", "file://" + str(Path(__file__).resolve().with_name("cyclonedds.xml")))

from cyclonedds.core import Policy, Qos  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.idl.types import float32, float64, int32, sequence, uint8, uint32  # noqa: E402
from cyclonedds.internal import InvalidSample  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402


# --- ROS 2 message types (IdlStruct default extensibility is @final, as in ROS 2) ---

@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class String(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64
    y: float64
    z: float64


@dataclass
class ToolpathSegment(IdlStruct, typename="cell_msgs::msg::dds_::ToolpathSegment_"):
    kind: uint8
    layer: uint32
    points: sequence[Point]
    secondary_points: sequence[Point]
    normals: sequence[Vector3]
    feed_mm_s: sequence[float32]
    power: sequence[float32]
    bead_width_mm: sequence[float32]
    bead_height_mm: sequence[float32]


@dataclass
class Toolpath(IdlStruct, typename="cell_msgs::msg::dds_::Toolpath_"):
    header: Header
    job_id: str
    process: uint8
    power_unit: uint8
    plane_separation_mm: float64
    segments: sequence[ToolpathSegment]


TYPES: dict[str, type[IdlStruct]] = {"std_msgs/String": String, "cell_msgs/Toolpath": Toolpath}


def ros_qos() -> Qos:
    """QoS shared with the Rust side: reliable, transient-local, keep-last 10, plain CDR (XCDR1)."""
    return Qos(
        Policy.Reliability.Reliable(max_blocking_time=duration(seconds=1)),
        Policy.Durability.TransientLocal,
        Policy.History.KeepLast(10),
        Policy.DataRepresentation(use_cdrv0_representation=True),
    )


def dds_topic(name: str) -> str:
    """Map a ROS 2 topic name (`/chatter` or `chatter`) to its DDS name (`rt/chatter`)."""
    return "rt/" + name.lstrip("/")


def listen(domain: int, timeout: float, topics: list[tuple[str, str]]) -> int:
    """Subscribe to every (name, type) pair and print samples as JSON until each topic has one."""
    dp = DomainParticipant(domain)
    qos = ros_qos()
    readers: dict[str, DataReader] = {}
    for name, type_name in topics:
        topic = Topic(dp, dds_topic(name), TYPES[type_name], qos=qos)
        readers[topic.name] = DataReader(dp, topic, qos=qos)
    pending = set(readers)
    deadline = time.monotonic() + timeout
    while pending:
        if time.monotonic() > deadline:
            print(f"ros_peer: timeout after {timeout}s, no sample on: {', '.join(sorted(pending))}",
                  file=sys.stderr)
            return 3
        for topic_name, reader in readers.items():
            for sample in reader.take(N=64):
                if isinstance(sample, InvalidSample):  # dispose/unregister notification, no data
                    continue
                line = {"topic": topic_name, "type": type(sample).__idl_typename__,
                        "value": asdict(sample)}
                print(json.dumps(line), flush=True)
                pending.discard(topic_name)
        time.sleep(0.05)
    return 0


def talk(domain: int, name: str, data: str, count: int, period: float) -> int:
    """Publish `data` as std_msgs/String on rt/<name> `count` times, `period` seconds apart."""
    dp = DomainParticipant(domain)
    qos = ros_qos()
    writer = DataWriter(dp, Topic(dp, dds_topic(name), String, qos=qos), qos=qos)
    for i in range(count):
        writer.write(String(data=data))
        if i + 1 < count:
            time.sleep(period)
    writer.wait_for_acks(duration(seconds=2))  # let reliable retransmits to matched readers finish
    return 0


def topic_arg(spec: str) -> tuple[str, str]:
    """Parse a `NAME:TYPE` listen argument."""
    name, sep, type_name = spec.rpartition(":")
    if not sep or not name or type_name not in TYPES:
        raise argparse.ArgumentTypeError(f"expected NAME:TYPE with TYPE in {sorted(TYPES)}, got {spec!r}")
    return name, type_name


def main(argv: list[str] | None = None) -> int:
    """Parse the command line and run the chosen mode."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="mode", required=True)
    lp = sub.add_parser("listen", help="print received samples as JSON lines")
    lp.add_argument("--domain", type=int, default=0)
    lp.add_argument("--timeout", type=float, default=30.0, help="seconds before giving up (exit 3)")
    lp.add_argument("--topic", type=topic_arg, action="append", required=True, metavar="NAME:TYPE",
                    help=f"repeatable; TYPE one of {', '.join(TYPES)}")
    tp = sub.add_parser("talk", help="publish a std_msgs/String")
    tp.add_argument("--domain", type=int, default=0)
    tp.add_argument("--topic", required=True, metavar="NAME")
    tp.add_argument("--data", required=True, metavar="TEXT")
    tp.add_argument("--count", type=int, default=20)
    tp.add_argument("--period", type=float, default=0.25, help="seconds between writes")
    args: Any = ap.parse_args(argv)
    if args.mode == "listen":
        return listen(args.domain, args.timeout, args.topic)
    return talk(args.domain, args.topic, args.data, args.count, args.period)


if __name__ == "__main__":
    sys.exit(main())
