"""A DBC file describing proleg's CAN frames (``proleg dbc -o FILE``), built from
``proleg.protocol.can``'s layout with cantools' database objects, so any CAN tool can decode telemetry.

One message set per node: names get a ``_N<node>`` suffix when several nodes are described.
The segmented CMD/REPLY frames are described by their header (segment index, last flag) and
seven raw data bytes; their content is the protocol frame (see ``proleg.protocol.can``).
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Sequence
from pathlib import Path

from cantools.database.can import Database, Message, Node, Signal
from cantools.database.conversion import BaseConversion

from ..errors import LinkError
from .definition import PROTOCOL_VERSION, BY_NAME, Direction
from .can import SLOT_CMD, SLOT_REPLY, TELEMETRY_FRAMES, CanIds

HOST = "HOST"


_ASCII = {"→": "->", "°": " deg", "≤": "<=", "≥": ">=", "ψ": "psi", "—": "-", "–": "-"}


def _ascii(text: str | None) -> str | None:
    """DBC files are ASCII: spell out the few symbols the protocol's docs use."""
    if text is None:
        return None
    for k, v in _ASCII.items():
        text = text.replace(k, v)
    return text.encode("ascii", "replace").decode("ascii")


def _robot_node(node: int) -> str:
    return f"ROBOT_{node}"


def _signal(name: str, start: int, length: int, signed: bool, scale: float = 1.0, unit: str = "",
            comment: str | None = None, choices: dict[int, str] | None = None,
            receivers: list[str] | None = None) -> Signal:
    if signed:
        lo, hi = -(1 << (length - 1)), (1 << (length - 1)) - 1
    else:
        lo, hi = 0, (1 << length) - 1
    conv = BaseConversion.factory(scale=scale, offset=0, choices=choices, is_float=False)
    return Signal(name, start, length, "little_endian", signed, conversion=conv,
                  minimum=lo * scale, maximum=hi * scale, unit=unit or None, comment=_ascii(comment),
                  receivers=receivers or [])


def _segment_signals(receiver: str) -> list[Signal]:
    sigs = [
        _signal("segment_index", 0, 4, False, comment="segment number, 0 starts a frame", receivers=[receiver]),
        _signal("segment_bytes_minus_1", 4, 3, False, comment="valid data bytes - 1", receivers=[receiver]),
        _signal("segment_last", 7, 1, False, comment="1 on the last segment", receivers=[receiver]),
    ]
    sigs += [_signal(f"data_{k}", 8 * (k + 1), 8, False, receivers=[receiver]) for k in range(7)]
    return sigs


_FIELD_DOCS = {f.name: f.doc for f in BY_NAME["TELEMETRY"].fields}


def build_database(nodes: Sequence[int] = (0,), base: int = 0x100) -> Database:
    """The cantools database of proleg's frames for robots ``nodes`` on one bus."""
    if not nodes:
        raise LinkError("dbc: at least one node id is needed")
    repeated = sorted({n for n in nodes if list(nodes).count(n) > 1})
    if repeated:  # one BU_ node and one message set per robot: a repeat would name a node twice
        raise LinkError(f"dbc: node id {repeated[0]} given more than once (each robot on the bus once)")
    messages: list[Message] = []
    suffix = len(nodes) > 1
    for node in nodes:
        ids = CanIds(node=node, base=base)
        robot = _robot_node(node)
        tag = f"_N{node}" if suffix else ""
        messages.append(Message(ids.id(SLOT_CMD), f"CMD{tag}", 8, _segment_signals(robot), senders=[HOST],
                                comment="host->robot command, segmented protocol frame"))
        messages.append(Message(ids.id(SLOT_REPLY), f"REPLY{tag}", 8, _segment_signals(HOST), senders=[robot],
                                comment="robot->host reply/event, segmented protocol frame"))
        for frame in TELEMETRY_FRAMES:
            sigs = []
            for s in frame.signals:
                choices = {int(d): d.name for d in Direction} if s.field == "direction" else None
                sigs.append(_signal(s.name, s.start_bit, s.length, s.signed, s.scale, s.unit,
                                    comment=_FIELD_DOCS.get(s.field) or None, choices=choices, receivers=[HOST]))
            messages.append(Message(ids.id(frame.slot), f"{frame.name}{tag}", 8, sigs, senders=[robot],
                                    comment=f"TELEMETRY part (protocol {PROTOCOL_VERSION})"))
    db_nodes = [Node(HOST, comment="proleg host")] + [Node(_robot_node(n), comment=f"robot node {n}") for n in nodes]
    return Database(messages=messages, nodes=db_nodes, version=f"proleg-protocol-{PROTOCOL_VERSION}")


def dbc_text(nodes: Sequence[int] = (0,), base: int = 0x100) -> str:
    return build_database(nodes, base).as_dbc_string()


def write_dbc(path: str | Path, nodes: Sequence[int] = (0,), base: int = 0x100) -> Path:
    """Write the DBC atomically (temp file + rename); returns the path."""
    text = dbc_text(nodes, base)
    out = Path(path)
    directory = out.parent if str(out.parent) else Path(".")
    if not directory.is_dir():
        raise LinkError(f"dbc: directory {directory} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=directory)
    try:
        with os.fdopen(fd, "w", encoding="ascii", newline="\n") as f:
            f.write(text)
        os.replace(tmp, out)
    except OSError as e:
        Path(tmp).unlink(missing_ok=True)
        raise LinkError(f"dbc: cannot write {out}: {e.strerror or e}") from None
    return out
