"""A DBC file describing proleg's CAN frames (``proleg dbc -o FILE``), built from
``proleg.protocol.can``'s layout with cantools' database objects, so any CAN tool can decode telemetry.

One message set per node: names get a ``_N<node>`` suffix when several nodes are described.
The segmented CMD/REPLY frames are described by their header (segment index, last flag) and
seven raw data bytes; their content is the protocol frame (see ``proleg.protocol.can``).

Signals are physical: ψ in degrees, duty in %, times in ms, each with its unit; TELEMETRY's
flags are one 1-bit signal per flag (``flag_running``...); direction, EVENT kinds, fault codes
and stop reasons carry value tables. EVENT is multiplexed by ``kind``: ``fault_code`` /
``fault_detail`` for FAULT, ``stop_reason`` / ``cycles`` for GAIT_STOPPED and so on. Given a
robot (``robot=``), ψ and duty signals are named for its limbs and actuators
(``psi_front_left``, ``duty_sma_left``).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from cantools.database.can import Database, Message, Node, Signal
from cantools.database.conversion import BaseConversion

from ..errors import UsageError
from ..names import identifier
from ..outputs import write_text_atomic
from .definition import DIR_UNSTATED, PROTOCOL_VERSION, BY_NAME, Direction, EventKind, FaultCode, Flag, StopReason
from .can import EVENT_FRAME, SLOT_CMD, SLOT_REPLY, TELEMETRY_FRAMES, CanIds

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
            receivers: list[str] | None = None, **extra: Any) -> Signal:
    if signed:
        lo, hi = -(1 << (length - 1)), (1 << (length - 1)) - 1
    else:
        lo, hi = 0, (1 << length) - 1
    conv = BaseConversion.factory(scale=scale, offset=0, choices=choices, is_float=False)
    return Signal(name, start, length, "little_endian", signed, conversion=conv,
                  minimum=lo * scale, maximum=hi * scale, unit=unit or None, comment=_ascii(comment),
                  receivers=receivers or [], **extra)


def _segment_signals(receiver: str) -> list[Signal]:
    sigs = [
        _signal("segment_index", 0, 4, False, comment="segment number, 0 starts a frame", receivers=[receiver]),
        _signal("segment_bytes_minus_1", 4, 3, False, comment="valid data bytes - 1", receivers=[receiver]),
        _signal("segment_last", 7, 1, False, comment="1 on the last segment", receivers=[receiver]),
    ]
    sigs += [_signal(f"data_{k}", 8 * (k + 1), 8, False, receivers=[receiver]) for k in range(7)]
    return sigs


_FIELD_DOCS = {f.name: f.doc for f in BY_NAME["TELEMETRY"].fields}


def _choices(enum: type) -> dict[int, str]:
    return {int(v): v.name for v in enum}


def _directions() -> dict[int, str]:
    """Direction, and DIR_UNSTATED: a loaded gait started without its way stated."""
    return {**_choices(Direction), DIR_UNSTATED: "UNSTATED"}


def _telemetry_signals(frame: Any, limbs: Sequence[str], actuators: Sequence[str]) -> list[Signal]:
    sigs = []
    named = {f"psi_{identifier(n)}" for n in limbs} | {f"duty_{identifier(a)}" for a in actuators}
    for s in frame.signals:
        if s.field == "flags":
            sigs += [_signal(f"flag_{f.name.lower()}", s.start_bit + f.bit_length() - 1, 1, False,
                             comment=f"TELEMETRY.flags bit {f.bit_length() - 1}", receivers=[HOST])
                     for f in Flag if f.name]
            continue
        name = s.name
        if s.field == "psi" and s.index is not None and s.index < len(limbs):
            name = f"psi_{identifier(limbs[s.index])}"
        elif s.field == "duty" and s.index is not None and s.index < len(actuators):
            name = f"duty_{identifier(actuators[s.index])}"
        elif name in named:  # named like a limb or actuator (a limb "5": psi_slot5; "count": psi_count_field)
            base = f"{s.field}_slot{s.index}" if s.index is not None else f"{name}_field"
            name, k = base, 1
            while name in named:  # ... and a limb called "slot5" too: psi_slot5_2
                k += 1
                name = f"{base}_{k}"
        choices = _directions() if s.field == "direction" else None
        sigs.append(_signal(name, s.start_bit, s.length, s.signed, s.scale, s.unit,
                            comment=_FIELD_DOCS.get(s.field) or None, choices=choices, receivers=[HOST]))
    return sigs


def _event_signals() -> list[Signal]:
    """EVENT, multiplexed by ``kind``: the meaning of code/detail per kind gets its own signals."""
    t, k, c, d = EVENT_FRAME.signals
    r = [HOST]
    sigs = [
        _signal("time_ms", t.start_bit, t.length, False, 1.0, "ms", comment="firmware time of the event", receivers=r),
        _signal("kind", k.start_bit, k.length, False, choices=_choices(EventKind), receivers=r, is_multiplexer=True),
    ]

    def muxed(name: str, sig: Any, kinds: Sequence[EventKind], choices: dict[int, str] | None = None,
              comment: str | None = None) -> Signal:
        return _signal(name, sig.start_bit, sig.length, False, choices=choices, comment=comment, receivers=r,
                       multiplexer_ids=[int(x) for x in kinds], multiplexer_signal="kind")

    sigs += [
        muxed("fault_code", c, [EventKind.FAULT], _choices(FaultCode)),
        muxed("fault_detail", d, [EventKind.FAULT], comment="limb index (actuator index for SMA_ON_LIMIT)"),
        muxed("stop_reason", c, [EventKind.GAIT_STOPPED], _choices(StopReason)),
        muxed("cycles", d, [EventKind.GAIT_STOPPED], comment="completed gait cycles (saturating)"),
        muxed("gait", c, [EventKind.GAIT_STARTED], comment="gait index, 255 = the loaded user gait"),
        muxed("direction", d, [EventKind.GAIT_STARTED], _directions()),
        muxed("step", c, [EventKind.STATE_REACHED], comment="gait step index"),
        muxed("state", d, [EventKind.STATE_REACHED], comment="state index (limb levels, first limb most significant)"),
        muxed("code", c, [EventKind.BOOT, EventKind.ESTOP, EventKind.FAULT_CLEARED, EventKind.GAIT_LOADED]),
        muxed("detail", d, [EventKind.BOOT, EventKind.ESTOP, EventKind.FAULT_CLEARED, EventKind.GAIT_LOADED]),
        muxed("suspect_actuator", c, [EventKind.SUSPECT], comment="actuator index, 255 = none"),
        muxed("failed_transition", d, [EventKind.SUSPECT],
              comment="from-state * n_states + to-state, 65535 = not representable"),
        muxed("lost_actuator", c, [EventKind.FALLBACK], comment="actuator index the firmware's fallback gave up"),
        muxed("fallback_steps", d, [EventKind.FALLBACK], comment="steps of the fallback gait it runs"),
    ]
    return sigs


def build_database(nodes: Sequence[int] = (0,), base: int = 0x100, robot: Any = None) -> Database:
    """The cantools database of proleg's frames for robots ``nodes`` on one bus; ``robot``
    names the ψ and duty signals after its limbs and actuators."""
    if not nodes:
        raise UsageError("dbc: at least one node id is needed")
    limbs = [limb.name for limb in robot.limbs] if robot is not None else []
    actuators = [a.name for a in robot.actuators] if robot is not None else []
    repeated = sorted({n for n in nodes if list(nodes).count(n) > 1})
    if repeated:  # one BU_ node and one message set per robot: a repeat would name a node twice
        raise UsageError(f"dbc: node id {repeated[0]} given more than once (each robot on the bus once)")
    messages: list[Message] = []
    suffix = len(nodes) > 1
    for node in nodes:
        ids = CanIds(node=node, base=base)
        robot_node = _robot_node(node)
        tag = f"_N{node}" if suffix else ""
        messages.append(Message(ids.id(SLOT_CMD), f"CMD{tag}", 8, _segment_signals(robot_node), senders=[HOST],
                                comment="host->robot command, segmented protocol frame"))
        messages.append(Message(ids.id(SLOT_REPLY), f"REPLY{tag}", 8, _segment_signals(HOST), senders=[robot_node],
                                comment="robot->host reply, segmented protocol frame"))
        for frame in TELEMETRY_FRAMES:
            messages.append(Message(ids.id(frame.slot), f"{frame.name}{tag}", 8,
                                    _telemetry_signals(frame, limbs, actuators), senders=[robot_node],
                                    comment=f"TELEMETRY part (protocol {PROTOCOL_VERSION})"))
        messages.append(Message(ids.id(EVENT_FRAME.slot), f"EVENT{tag}", 8, _event_signals(), senders=[robot_node],
                                comment="EVENT: boot, state reached, fault, gait started/stopped, E-stop..."))
    db_nodes = [Node(HOST, comment="proleg host")] + [Node(_robot_node(n), comment=f"robot node {n}") for n in nodes]
    return Database(messages=messages, nodes=db_nodes, version=f"proleg-protocol-{PROTOCOL_VERSION}")


def dbc_text(nodes: Sequence[int] = (0,), base: int = 0x100, robot: Any = None) -> str:
    return build_database(nodes, base, robot).as_dbc_string()


def write_dbc(path: str | Path, nodes: Sequence[int] = (0,), base: int = 0x100, robot: Any = None) -> Path:
    """Write the DBC atomically (temp file + rename); returns the path."""
    return write_text_atomic(path, dbc_text(nodes, base, robot), "dbc", encoding="ascii")
