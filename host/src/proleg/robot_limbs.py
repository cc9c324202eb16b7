"""The robot file's ``[[limb]]`` and ``[[actuator]]`` tables: each limb's levels, critical
angles ψ*, hysteresis, actuator, IMU placement, friction and stroke (``Limb``, ``ImuSpec``),
each actuator's name and channel (``Actuator``), read and checked by ``_limbs`` and
``_actuators`` (called by ``proleg.robot.robot_from_dict``), and the checks of the limbs
against the ``[control]`` table: strokes and their leads (``_check_strokes``,
``stroke_leads``) and levels too close to hold (``hold_crossings``, warning lines, not errors).
Re-exported by ``proleg.robot``."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import RobotFileError
from .names import counted, identifier
from .robot_fields import Fields, toml_text
from .robot_plant import limb_friction
from .robot_settings import Control

#: The alphabet of robot, limb, actuator and board names (the one place it is spelled), and
#: its words in their messages: a first character, then any more.
NAME_FIRST, NAME_REST = "[a-z0-9]", "[a-z0-9-]"
NAME_ALPHABET = "lowercase letters, digits and '-' (not first)"


def name_re(max_chars: int) -> re.Pattern[str]:
    """Names of 1 to ``max_chars`` characters of the names' alphabet; use ``fullmatch`` ("$"
    would let a final "\n" through)."""
    return re.compile(f"{NAME_FIRST}{NAME_REST}{{0,{max_chars - 1}}}")


NAME_RE = name_re(15)  # limbs and actuators: the firmware's names are 15 characters


def too_long(name: str) -> str:
    """`` (N characters)`` for a name of the right characters but too many of them, else "": a
    lab's 64-character robot name was told "1 to 63 characters, got '…'", left to count."""
    return f" ({len(name)} characters)" if re.fullmatch(f"{NAME_FIRST}{NAME_REST}*", name) else ""

MAX_LIMBS = 8
MAX_ACTUATORS = 8


@dataclass(frozen=True)
class ImuSpec:
    """Where a limb's IMU sits, as the robot file says (every part optional; the build
    fills in the rest, see proleg.firmware.placement): the board's I2C bus by name, the
    TCA9548A/PCA9548A multiplexer's address (0x70..0x77) and channel (0..7) when the IMU
    sits behind one, and the IMU's 7-bit address (0x68 or 0x69 for an MPU-6050)."""

    bus: str | None = None
    mux: int | None = None
    channel: int | None = None
    address: int | None = None


#: A multiplexer's 7-bit addresses (TCA9548A/PCA9548A: A2..A0 select 0x70..0x77) and channels.
MUX_ADDRESSES = range(0x70, 0x78)
MUX_CHANNELS = 8


#: The highest ``[[limb]] stroke_deg``: the firmware's hold band above it stays below 89° (psi.c).
STROKE_MAX_DEG = 85.0


@dataclass(frozen=True)
class Limb:
    name: str
    levels: int
    psi_star_deg: tuple[float, ...]
    hysteresis_deg: float
    actuator: str
    imu: ImuSpec | None = None  # None: placed automatically by the build
    #: friction mechanism: "D1"/"D2" or one material per level, a name or a pad's (μs, μk)
    #: (None: the plant infers it)
    friction: str | tuple[str | tuple[float, float], ...] | None = None
    #: how far the controller raises the limb when its top level is wanted (°): heated until ψ
    #: reaches it and held there, instead of just past the top critical angle (None)
    stroke_deg: float | None = None


@dataclass(frozen=True)
class Actuator:
    name: str
    channel: int
    channel_given: bool = True  # False: no channel key, the default (its position among the [[actuator]]s)


def _array_of_tables(path: Path, value: Any, key: str) -> list[dict]:
    if not isinstance(value, list) or not value or not all(isinstance(t, dict) for t in value):
        raise RobotFileError(f"{path}: {key}: expected one or more [[{key}]] tables")
    return value


def _entry(kind: str, i: int, table: Any) -> str:
    """How an error names the ``i``-th (0-based) ``[[kind]]`` table: by its name when it has
    one, e.g. ``limb 'left'``, else by its place counted from 1, ``limb #2``."""
    name = table.get("name") if isinstance(table, dict) else None
    return f"{kind} {name!r}" if isinstance(name, str) and name else f"{kind} #{i + 1}"


def _actuators(path: Path, value: Any) -> tuple[Actuator, ...]:
    tables = _array_of_tables(path, value, "actuator")
    if len(tables) > MAX_ACTUATORS:
        raise RobotFileError(f"{path}: actuator: at most {MAX_ACTUATORS} actuators, got {len(tables)}")
    out: list[Actuator] = []
    for i, t in enumerate(tables):
        f = Fields(path, _entry("actuator", i, t), t, {"name", "channel"}, sep=": ")
        name = f.string("name")
        if not NAME_RE.fullmatch(name):
            f.fail("name", f"{NAME_ALPHABET}, 1 to 15 characters", name, too_long(name))
        if any(a.name == name for a in out):
            f.fail("name", "a name no other actuator has", name)
        channel = f.integer("channel", i, 0, MAX_ACTUATORS - 1)
        other = next((a for a in out if a.channel == channel), None)
        if other is not None:  # the one that has it, and a default said as one: "got 1" named no line of the file
            written = f"channel = {channel}" if other.channel_given else f"channel {channel}, by default"
            if "channel" in t:
                f.fail("channel", f"a channel no other actuator uses (actuator {other.name!r} has {written})", channel)
            f.fail("channel", f"a channel no other actuator uses: without one it takes its place among the [[actuator]]s "
                              f"counted from 0, {channel}, which actuator {other.name!r} has ({written}): give it a "
                              "channel of its own")
        out.append(Actuator(name, channel, "channel" in t))
    return tuple(out)


def _limbs(path: Path, value: Any, actuator_names: set[str]) -> tuple[Limb, ...]:
    tables = _array_of_tables(path, value, "limb")
    if len(tables) > MAX_LIMBS:
        raise RobotFileError(f"{path}: limb: at most {MAX_LIMBS} limbs, got {len(tables)}")
    out: list[Limb] = []
    for i, t in enumerate(tables):
        f = Fields(path, _entry("limb", i, t), t, {"name", "levels", "psi_star_deg", "hysteresis_deg", "actuator", "imu", "friction",
                                                   "stroke_deg"},
                    sep=": ")
        name = f.string("name")
        if not name or not name.isprintable():  # empty: psi_ in the DBC; a newline splits printed lines
            f.fail("name", "a name of printable characters, at least one", name)
        if any(limb.name == name for limb in out):
            f.fail("name", "a name no other limb has (duplicate limb)", name)
        if (twin := next((limb.name for limb in out if identifier(limb.name) == identifier(name)), None)) is not None:
            f.fail("name", f"a name that stays apart from limb {twin!r} as an identifier (both are "
                           f"{identifier(name)!r} in recordings and CAN signals)", name)
        levels = f.integer("levels", 2, 2, 10)
        psi = t.get("psi_star_deg")
        if isinstance(psi, (int, float)) and not isinstance(psi, bool):
            psi = [psi]
        if (
            not isinstance(psi, list)
            or len(psi) != levels - 1
            or not all(isinstance(p, (int, float)) and not isinstance(p, bool) for p in psi)
        ):
            if isinstance(psi, list) and len(psi) > 1 and "levels" not in t and len(psi) + 1 <= 10:
                # the limb's levels were left to the default: the angles say how many were meant
                raise RobotFileError(f"{path}: {f.where}: psi_star_deg: expected a list of 1 critical angle in "
                                     f"degrees (levels - 1, and levels is 2 when not given), got {toml_text(psi)}: "
                                     f"for {counted(len(psi), 'angle')} say levels = {len(psi) + 1}")
            f.fail("psi_star_deg", f"a list of {levels - 1} critical angle(s) in degrees (levels - 1)", psi)
        psi_t = tuple(float(p) for p in psi)
        if not all(-90.0 < p < 90.0 for p in psi_t):
            f.fail("psi_star_deg", "angles strictly between -90 and 90 degrees", psi)
        if any(b <= a for a, b in zip(psi_t, psi_t[1:])):
            f.fail("psi_star_deg", "strictly increasing angles", psi)
        hyst = f.number("hysteresis_deg", 2.0, 0.0, 20.0)
        gaps = [b - a for a, b in zip(psi_t, psi_t[1:])]
        if gaps and hyst >= min(gaps):
            f.fail("hysteresis_deg", f"less than the smallest gap between critical angles ({min(gaps)})", hyst)
        if psi_t[0] - hyst / 2 <= -90.0 or psi_t[-1] + hyst / 2 >= 90.0:  # the firmware's band edges
            f.fail("psi_star_deg", f"angles whose bands psi* ± hysteresis_deg/2 ({hyst:g}/2) lie strictly inside "
                   f"(-90, 90) degrees", psi)
        actuator = f.string("actuator")
        if actuator not in actuator_names:
            f.fail("actuator", f"the name of an [[actuator]] ({', '.join(sorted(actuator_names))})", actuator)
        imu = _imu_spec(path, f"{f.where}: imu", t["imu"]) if "imu" in t else None
        friction = limb_friction(path, f.where, t["friction"], levels) if "friction" in t else None
        stroke = f.number("stroke_deg", 0.0, -math.inf, math.inf) if f.has("stroke_deg") else None  # range: _check_strokes
        out.append(Limb(name, levels, psi_t, hyst, actuator, imu, friction, stroke))
    declared = [limb.friction is not None for limb in out]
    if any(declared) and not all(declared):
        missing = next(limb.name for limb in out if limb.friction is None)
        raise RobotFileError(f"{path}: limb {missing!r}: friction: expected on every limb or on none "
                             f"(the others give it; without it the simulator infers every limb's mechanism)")
    return tuple(out)


def _check_strokes(path: Path, control: Control, limbs: Sequence[Limb]) -> None:
    """Each ``stroke_deg`` lies at least 1° above where the limb is held without one (so that
    its hold band starts above that hold's, and rounds to a distinct edge) and at most
    STROKE_MAX_DEG; ``stroke_rise_lead`` / ``stroke_fall_lead`` name a limb that has one."""
    for lb in limbs:
        if lb.stroke_deg is None:
            continue
        lo = lb.psi_star_deg[-1] + lb.hysteresis_deg / 2 + control.hold_margin_deg + 1.0
        if lo > STROKE_MAX_DEG:  # "from 86 to 85 degrees" was a range with nothing in it
            raise RobotFileError(
                f"{path}: limb {lb.name!r}: stroke_deg: no stroke fits this limb: a stroke lies at least 1° above "
                f"where it is held without one ({lo - 1:g}°: psi* {lb.psi_star_deg[-1]:g} + hysteresis/2 + "
                f"control.hold_margin_deg) and at most {STROKE_MAX_DEG:g}°; lower its top psi_star_deg or "
                f"control.hold_margin_deg, or leave stroke_deg out, got {lb.stroke_deg:g}")
        if not lo <= lb.stroke_deg <= STROKE_MAX_DEG:
            # the firmware holds it between stroke_deg and 1° above (psi.c: edges within ±89°)
            raise RobotFileError(
                f"{path}: limb {lb.name!r}: stroke_deg: expected an angle from {lo:g} (1° above where it is held "
                f"without one: psi* + hysteresis/2 + control.hold_margin_deg) to {STROKE_MAX_DEG:g} degrees, "
                f"got {lb.stroke_deg:g}")
    with_stroke = [lb.name for lb in limbs if lb.stroke_deg is not None]
    for key in ("stroke_rise_lead", "stroke_fall_lead"):
        name = getattr(control, key)
        if name is not None and not with_stroke:
            raise RobotFileError(f"{path}: control.{key}: {name!r}, but no [[limb]] has a stroke_deg to lead with")
        if name is not None and name not in with_stroke:
            raise RobotFileError(f"{path}: control.{key}: expected the name of a limb with a stroke_deg "
                                 f"({', '.join(with_stroke)}), got {name!r}")


#: How far above its hold edge the firmware lets a held limb's coil heat (core/psi.h
#: PSI_HOLD_BAND_CDEG): the hold band is [hold edge, hold edge + 1°].
HOLD_BAND_DEG = 1.0


def hold_crossings(path: Path, limbs: Sequence[Limb], hold_margin_deg: float) -> list[str]:
    """One warning line per pair of neighbouring thresholds of a limb too close for the
    controller to hold the lower level: it holds level k with ψ between the hold edge
    ψ*_k + h/2 + ``hold_margin_deg`` and 1° above it (docs/control.md), and a hold band that
    reaches the next band's lower edge ψ*_{k+1} − h/2 takes the limb into level k+1. A warning,
    not an error: ``SET_PARAM`` may move the thresholds and the margin on the board."""
    out = []
    for lb in limbs:
        h = lb.hysteresis_deg
        need = h + hold_margin_deg + HOLD_BAND_DEG  # ψ*_{k+1} − ψ*_k must exceed this
        for k, (lo, hi) in enumerate(zip(lb.psi_star_deg, lb.psi_star_deg[1:]), start=1):
            if hi - lo > need:
                continue
            top = lo + h / 2 + hold_margin_deg + HOLD_BAND_DEG
            out.append(f"{path}: limb {lb.name!r}: psi_star_deg {lo:g}° and {hi:g}° are {hi - lo:g}° apart: holding "
                       f"level {k}, the controller heats it up to {top:g}° (psi* + hysteresis/2 + "
                       f"control.hold_margin_deg + {HOLD_BAND_DEG:g}°), which reaches level {k + 1}'s band "
                       f"(from {hi - h / 2:g}°), so level {k} cannot be held; space them more than {need:g}° "
                       f"apart (hysteresis_deg {h:g} + hold_margin_deg {hold_margin_deg:g} + {HOLD_BAND_DEG:g}), "
                       f"or lower hold_margin_deg or hysteresis_deg")
        out += _clamped_edges(path, lb, hold_margin_deg)
    return out


#: The firmware's hold, hold-top and settle edges stop at ±this (core/psi.c set_angles).
EDGE_LIMIT_DEG = 89.0


def _clamped_edges(path: Path, lb: Limb, hold_margin_deg: float) -> list[str]:
    """A warning line for a limb whose hold top (without a stroke: ψ*_top + h/2 + margin + 1°)
    or settle edge (ψ*_1 − h/2 − margin) lies past ±``EDGE_LIMIT_DEG``: the firmware clamps
    them there, silently, so the margin the file sets is not the one held."""
    out = []
    h = lb.hysteresis_deg
    if lb.stroke_deg is None:
        edge = lb.psi_star_deg[-1] + h / 2 + hold_margin_deg
        if edge + HOLD_BAND_DEG > EDGE_LIMIT_DEG:
            out.append(f"{path}: limb {lb.name!r}: psi_star_deg {lb.psi_star_deg[-1]:g}°: the controller holds it "
                       f"raised between {edge:g}° and {edge + HOLD_BAND_DEG:g}° (psi* + hysteresis/2 + "
                       f"control.hold_margin_deg, and {HOLD_BAND_DEG:g}° above), but the firmware's angles stop at "
                       f"{EDGE_LIMIT_DEG:g}° and it holds the limb there instead, with less margin than the file "
                       f"says; lower psi_star_deg, control.hold_margin_deg or hysteresis_deg")
    settle = lb.psi_star_deg[0] - h / 2 - hold_margin_deg
    if settle < -EDGE_LIMIT_DEG:
        out.append(f"{path}: limb {lb.name!r}: psi_star_deg {lb.psi_star_deg[0]:g}°: lowered, it counts as settled "
                   f"only below {settle:g}° (psi* - hysteresis/2 - control.hold_margin_deg), but the firmware's "
                   f"angles stop at {-EDGE_LIMIT_DEG:g}° and it settles the limb there instead; raise "
                   f"psi_star_deg, or lower control.hold_margin_deg or hysteresis_deg")
    return out


def stroke_leads(limbs: Sequence[Any], control: Any) -> tuple[int, int | None] | None:
    """(rise lead, fall lead or None) as limb indices, or None when no limb has a stroke: the
    control keys; without ``stroke_rise_lead`` the limb with the largest stroke (the first such
    in the file), without ``stroke_fall_lead`` no fall lead (limbs fall as their coils cool)."""
    strokes = [getattr(lb, "stroke_deg", None) for lb in limbs]
    idx = [i for i, st in enumerate(strokes) if st is not None]
    if not idx:
        return None
    names = [lb.name for lb in limbs]
    rise, fall = getattr(control, "stroke_rise_lead", None), getattr(control, "stroke_fall_lead", None)
    return (names.index(rise) if rise else max(idx, key=lambda i: (strokes[i], -i)),
            names.index(fall) if fall else None)


def _i2c_address(f: Fields, key: str, lo: int, hi: int) -> int:
    """A 7-bit I2C address, said in hex as the file and the data sheets write it: ``mux = 0x69``
    was "expected an integer in 112..119, got 105"."""
    v = f.table.get(key)
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        got = f"0x{v:02x}" if isinstance(v, int) and not isinstance(v, bool) and v >= 0 else toml_text(v)
        raise RobotFileError(f"{f.path}: {f.where}{f.sep}{key}: expected an address in 0x{lo:02x}..0x{hi:02x} "
                             f"(a number, written like 0x{max(lo, 0x68):02x} without quotes), got {got}")
    return v


def _imu_spec(path: Path, where: str, value: Any) -> ImuSpec:
    """``imu = { bus = "I2C1", mux = 0x70, channel = 3, address = 0x68 }``, every part optional."""
    f = Fields(path, where, value, {"bus", "mux", "channel", "address"}, sep=".")
    bus = f.string("bus") if f.has("bus") else None
    mux = _i2c_address(f, "mux", MUX_ADDRESSES.start, MUX_ADDRESSES.stop - 1) if f.has("mux") else None
    channel = f.integer("channel", 0, 0, MUX_CHANNELS - 1) if f.has("channel") else None
    address = _i2c_address(f, "address", 0x08, 0x77) if f.has("address") else None
    if address is not None and address in MUX_ADDRESSES:
        raise RobotFileError(f"{path}: {where}.address: expected an IMU address outside the multiplexer range "
                             f"0x70..0x77, got 0x{address:02x}")
    return ImuSpec(bus, mux, channel, address)
