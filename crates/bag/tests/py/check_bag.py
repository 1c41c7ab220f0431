"""Reads a cellsuite bag with two independent decoders and prints what they decoded as JSON lines.

Usage: check_bag.py BAG_DIR

1. The `mcap` reader with `mcap-ros2-support`'s decoder, file by file in metadata.yaml order, via
   the summary section (seeking reader, chunk and message indexes), every message decoded.
2. `rosbags`' AnyReader on the bag directory (metadata.yaml + mcap); every message decoded by a
   typestore built here from the bag's schemas with `get_types_from_msg`, and by AnyReader's own
   typestore too wherever it has the type (not service parts: see below).

Any failure raises (non-zero exit). Output lines: {"reader": ..., ...}.
"""

import dataclasses
import json
import sys
from pathlib import Path

import rosbags.highlevel.anyreader
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore, get_types_from_msg
from ruamel.yaml import YAML


def plain(v):
    """Decoded message to JSON-able values (field names as in the .msg)."""
    if isinstance(v, float) and (v != v or v in (float("inf"), float("-inf"))):
        # JSON has no NaN; null is how cell_msgs::json reads a NaN back (e.g. a HeatMap
        # without a threshold).
        return None
    if v is None or isinstance(v, (bool, int, float, str)):
        return v
    if isinstance(v, (bytes, bytearray)):
        return list(v)
    if hasattr(v, "tolist"):
        return plain(v.tolist())
    if isinstance(v, (list, tuple)):
        return [plain(x) for x in v]
    if dataclasses.is_dataclass(v):
        names = [f.name for f in dataclasses.fields(v)]
    elif hasattr(v, "__slots__"):
        names = list(v.__slots__)
    else:
        names = list(vars(v))
    # rosbags' classes also carry `__msgtype__` and the constants (upper case; ROS field names
    # are lower case).
    return {k: plain(getattr(v, k)) for k in names if not k.startswith("_") and not k.isupper()}


def types_from_msg(text, name):
    """`get_types_from_msg`, with a service part under its real name: rosbags 0.11 files
    `pkg/srv/Name_Request` under `pkg/srv/msg/Name_Request`."""
    types = get_types_from_msg(text, name)
    if name not in types and "/srv/" in name:
        pkg, _, rest = name.partition("/srv/")
        types[name] = types.pop(f"{pkg}/srv/msg/{rest}")
    return types


# AnyReader checks every connection's RIHS01 type hash (metadata.yaml's type_description_hash)
# against its own hash of the bag's definitions; misfiled, a service part has none (KeyError).
rosbags.highlevel.anyreader.get_types_from_msg = types_from_msg


def emit(**kw):
    print(json.dumps(kw, allow_nan=False), flush=True)


def main(bag: Path) -> None:
    meta = YAML(typ="safe").load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    schemas = {}
    for name in meta["relative_file_paths"]:
        with open(bag / name, "rb") as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            header = reader.get_header()
            summary = reader.get_summary()
            assert summary is not None, f"{name}: no summary"
            assert summary.statistics is not None, f"{name}: no statistics"
            emit(
                reader="mcap-file",
                file=name,
                profile=header.profile,
                library=header.library,
                message_count=summary.statistics.message_count,
                chunks=len(summary.chunk_indexes),
                message_indexes=all(ci.message_index_offsets for ci in summary.chunk_indexes),
                compression=sorted({ci.compression for ci in summary.chunk_indexes}),
                channels=[
                    {
                        "topic": c.topic,
                        "encoding": c.message_encoding,
                        "schema": summary.schemas[c.schema_id].name,
                        "schema_encoding": summary.schemas[c.schema_id].encoding,
                        "qos": c.metadata.get("offered_qos_profiles"),
                        "type_hash": c.metadata.get("topic_type_hash"),
                    }
                    for c in summary.channels.values()
                ],
            )
            for s in summary.schemas.values():
                schemas[s.name] = s.data.decode()
            for schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=True):
                emit(
                    reader="mcap",
                    topic=channel.topic,
                    type=schema.name,
                    log_time=message.log_time,
                    sequence=message.sequence,
                    value=plain(decoded),
                )

    # A typestore from the bag's own definitions, independent of AnyReader's.
    store = get_typestore(Stores.EMPTY)
    for name, text in schemas.items():
        store.register(types_from_msg(text, name))

    with AnyReader([bag]) as reader:
        emit(
            reader="rosbags-bag",
            message_count=reader.message_count,
            duration=reader.duration,
            start_time=reader.start_time,
            topics=[
                {
                    "topic": c.topic,
                    "type": c.msgtype,
                    "count": c.msgcount,
                    # rosbags reads metadata.yaml's type_description_hash into `digest`.
                    "type_hash": c.digest,
                    "qos": [
                        {
                            "reliability": q.reliability.name,
                            "durability": q.durability.name,
                            "history": q.history.name,
                            "depth": q.depth,
                        }
                        for q in c.ext.offered_qos_profiles
                    ],
                }
                for c in reader.connections
            ],
        )
        own_store_only = set()
        for conn, timestamp, raw in reader.messages():
            value = plain(store.deserialize_cdr(raw, conn.msgtype))
            if conn.msgtype in reader.typestore.fielddefs:
                again = plain(reader.deserialize(raw, conn.msgtype))
                assert value == again, f"{conn.topic}: AnyReader and schema typestore disagree"
            else:
                own_store_only.add(conn.msgtype)
            emit(reader="rosbags", topic=conn.topic, type=conn.msgtype, log_time=timestamp, value=value)
        emit(reader="rosbags-own-store-only", types=sorted(own_store_only))


if __name__ == "__main__":
    main(Path(sys.argv[1]))
