"""What a recording holds, in physical units with named fields — shared by every format.

``RecordingMeta``: who was recorded (robot, board, firmware ids, limb and actuator names, ψ*,
the wall-clock start time in ISO 8601 UTC). ``event_row`` puts an EVENT in words the way the
console does (``proleg.console.names.event_text``, one implementation for both). ``telemetry_row`` turns one TELEMETRY frame into
a flat row: ``t_host_s`` (host receipt time on the link's clock), ``t_s`` (firmware time),
the integer fields as integers, ``psi_<limb>_deg`` per limb, ``duty_<actuator>_pct`` per
channel and the link's ground truth (``displacement_mm`` on the simulated robot). Every
format (CSV, JSON Lines, MCAP) writes these same names; docs/data.md lists them.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from datetime import datetime, timezone
from typing import Any

from ..names import identifier
from ..robot import info_name
from ..states import label
from ..protocol.definition import ErrorCode, EventKind

#: TELEMETRY's integer fields, as recorded (no scaling)
INTEGER_FIELDS = ("seq", "measured", "target", "gait", "direction", "step", "flags")
#: the columns of the events table (EVENT messages, replies, fault injections)
EVENT_COLUMNS = ("t_host_s", "t_s", "msg", "kind", "code", "detail", "text")


def _strings(d: dict[str, Any], key: str) -> tuple[str, ...]:
    v = d.get(key, ())
    if not isinstance(v, (list, tuple)) or not all(isinstance(x, str) for x in v):
        raise ValueError(f"{key}: expected a list of names, got {v!r:.40}")
    return tuple(v)


def _stars(v: Any) -> tuple[tuple[float, ...], ...]:
    """ψ* per limb: a list of lists of numbers."""
    ok = isinstance(v, (list, tuple)) and all(
        isinstance(s, (list, tuple)) and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in s)
        for s in v)
    if not ok:
        raise ValueError(f"psi_star_deg: expected a list of lists of degrees per limb, got {v!r:.40}")
    return tuple(tuple(float(x) for x in s) for s in v)


def utc_now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds").replace("+00:00", "Z")


@dataclass(frozen=True)
class RecordingMeta:
    """A recording's metadata (the CSV sidecar ``.meta.json``, JSONL's first line, MCAP metadata)."""

    limb_names: tuple[str, ...]
    channel_names: tuple[str, ...]
    robot: str = ""
    board: str = ""
    start_utc: str = field(default_factory=utc_now)
    psi_star_deg: tuple[tuple[float, ...], ...] = ()
    truth: tuple[str, ...] = ()  # ground-truth columns the link provides (displacement_mm)
    info: dict[str, str] = field(default_factory=dict)  # firmware build id, gait hash, link, rates...
    #: actuator names in the firmware's actuator order (the robot file's), for events that name one
    actuator_names: tuple[str, ...] = ()

    def state_label(self, index: int) -> str:
        """State ``index`` by its label (one digit per limb, levels from ``psi_star_deg``), as
        the console names it; the bare index when the metadata has no ψ* or it is out of range."""
        if not self.psi_star_deg or len(self.psi_star_deg) != len(self.limb_names):
            return str(index)
        try:
            return label(index, tuple(len(s) + 1 for s in self.psi_star_deg))
        except ValueError:
            return str(index)

    def n_states(self) -> int:
        """The number of states ``psi_star_deg`` gives (0: unknown)."""
        if not self.psi_star_deg or len(self.psi_star_deg) != len(self.limb_names):
            return 0
        return math.prod(len(s) + 1 for s in self.psi_star_deg)

    def columns(self) -> list[str]:
        """The telemetry columns, in order."""
        return (["t_host_s", "t_s", *INTEGER_FIELDS]
                + [f"psi_{identifier(n)}_deg" for n in self.limb_names]
                + [f"duty_{identifier(n)}_pct" for n in self.channel_names]
                + list(self.truth))

    def as_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["psi_star_deg"] = [list(v) for v in self.psi_star_deg]
        d["columns"] = self.columns()
        d["units"] = {"t_host_s": "s (host clock)", "t_s": "s (firmware clock)", "psi_*_deg": "degree",
                      "duty_*_pct": "percent", "displacement_mm": "mm",
                      "temp_*_c": "degree Celsius (simulated coil)"}
        return d

    @classmethod
    def from_dict(cls, d: Any) -> RecordingMeta:
        """From ``as_dict``'s output; ``ValueError`` names the first field of the wrong type."""
        if not isinstance(d, dict):
            raise ValueError(f"expected a JSON object, got {type(d).__name__}")
        info = d.get("info", {})
        if not isinstance(info, dict):
            raise ValueError(f"info: expected an object, got {info!r:.40}")
        return cls(
            limb_names=_strings(d, "limb_names"), channel_names=_strings(d, "channel_names"),
            robot=str(d.get("robot", "")), board=str(d.get("board", "")), start_utc=str(d.get("start_utc", "")),
            psi_star_deg=_stars(d.get("psi_star_deg", ())), truth=_strings(d, "truth"),
            info={str(k): str(v) for k, v in info.items()}, actuator_names=_strings(d, "actuator_names"),
        )

    @classmethod
    def for_robot(cls, *, info: Any = None, robot: Any = None, link: Any = None, **kw: Any) -> RecordingMeta:
        """Metadata from a connected robot's INFO (``RobotInfo``), its robot file (``Robot``,
        for limb and actuator names and ψ*) and the link (its description, its ground truth)."""
        limbs = info.limbs if info is not None else len(robot.limbs)
        # TELEMETRY's duties come one per actuator in the firmware's actuator order (the robot
        # file's: core/telemetry.c), whatever channels those actuators drive
        channels = info.actuators if info is not None else len(robot.actuators)
        limb_names = [f"limb{i + 1}" for i in range(limbs)]  # counted from 1, as messages show them
        channel_names = [f"ch{j}" for j in range(channels)]
        stars: tuple[tuple[float, ...], ...] = ()
        actuator_names: tuple[str, ...] = ()
        if robot is not None and len(robot.limbs) == limbs:
            limb_names = [limb.name for limb in robot.limbs]
            stars = tuple(tuple(limb.psi_star_deg) for limb in robot.limbs)
            actuator_names = tuple(a.name for a in robot.actuators)
            if len(actuator_names) == channels:
                channel_names = list(actuator_names)
        extra = dict(info.header()) if info is not None else {}
        for k in ("robot", "board", "limbs", "channels"):
            extra.pop(k, None)
        if link is not None:
            extra["link"] = link.description
        return cls(
            limb_names=tuple(limb_names), channel_names=tuple(channel_names),
            # the robot file's full name when it is the board's (INFO carries 15 characters)
            robot=robot.name if robot is not None and (info is None or info_name(robot.name) == info.robot_name)
            else info.robot_name,
            board=info.board if info is not None else kw.pop("board", ""),
            psi_star_deg=stars, info=extra, actuator_names=actuator_names,
            # the link's order: displacement_mm, then the coils as the duty columns are
            truth=kw.pop("truth", tuple(link.truth()) if link is not None else ()), **kw,
        )


def telemetry_row(meta: RecordingMeta, host_s: float, f: dict[str, Any], truth: dict[str, float]) -> dict[str, Any]:
    """One TELEMETRY frame's fields in physical units under the recording's column names."""
    row: dict[str, Any] = {"t_host_s": round(host_s, 6), "t_s": f["time_ms"] / 1000}
    for k in INTEGER_FIELDS:
        row[k] = int(f[k])
    psi, duty = f["psi"], f["duty"]
    for i, n in enumerate(meta.limb_names):
        row[f"psi_{identifier(n)}_deg"] = psi[i] / 100 if i < len(psi) else None
    for j, n in enumerate(meta.channel_names):
        row[f"duty_{identifier(n)}_pct"] = duty[j] / 100 if j < len(duty) else None
    for k in meta.truth:
        row[k] = truth.get(k)
    return row


def event_row(host_s: float, name: str, f: dict[str, Any], meta: RecordingMeta | None = None) -> dict[str, Any]:
    """Any other message as one events-table row: ``kind``/``code``/``detail`` of an EVENT
    (kind by name), a NACK's error/detail, 0 otherwise; ``text`` says it in words, as the
    console does (``proleg.console.names.event_text``), naming the limb or actuator an event
    points at by the recording's ``meta`` names."""
    t_s = f["time_ms"] / 1000 if "time_ms" in f else None
    if name == "EVENT":
        from ..console.names import RobotNames, event_text

        if meta is None:
            names, state = RobotNames(), None
        else:
            names, state = RobotNames(meta.limb_names, meta.actuator_names, meta.n_states()), meta.state_label
        return {"t_host_s": round(host_s, 6), "t_s": t_s, "msg": name, "kind": _name(EventKind, f["kind"]),
                "code": int(f["code"]), "detail": int(f["detail"]), "text": event_text(f, names, state)}
    code = int(f.get("error", 0)) if name == "NACK" else 0
    detail = int(f.get("detail", 0)) if name == "NACK" else 0
    text = " ".join(f"{k}={v}" for k, v in f.items() if k != "time_ms")
    if name == "NACK":
        text = f"{_name(ErrorCode, code)} " + text
    return {"t_host_s": round(host_s, 6), "t_s": t_s, "msg": name, "kind": "", "code": code, "detail": detail,
            "text": text}


def injection_row(host_s: float, t_s: float | None, fault: str) -> dict[str, Any]:
    """A fault the simulator injected (``proleg sim --inject``), for plots' markers."""
    return {"t_host_s": round(host_s, 6), "t_s": t_s, "msg": "INJECT", "kind": "INJECT", "code": 0, "detail": 0,
            "text": fault}


def _name(enum: Any, value: int) -> str:
    try:
        return enum(value).name
    except ValueError:
        return str(value)


def dumps(obj: Any) -> str:
    return json.dumps(obj, separators=(",", ":"), allow_nan=False)
