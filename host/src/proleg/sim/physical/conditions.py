"""Conditions of a simulated run: supply, air, wear, sensors and world (``key=value``).

Every key, its unit and range is in ``KEYS``. Per-limb and per-actuator keys take
``NAME:value`` (a limb or actuator name, its index, ``rear``/``front`` for the first/last
limb or actuator) or a bare value for all of them; repeat the key for several names
(``imu_bias_deg=left:3``, ``imu_bias_deg=right:-2``). ``parse_conditions`` turns strings such
as ``power=0.8`` into a ``Conditions``; an unknown key, a malformed value or a value outside
its range raises ``SimError`` with one line naming the key and what was expected.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from ...errors import SimError


@dataclass(frozen=True)
class Key:
    unit: str
    lo: float
    hi: float
    default: float
    per: str | None  # None: one value; "limb" / "actuator": per name
    doc: str


KEYS: dict[str, Key] = {
    "power": Key("×", 0.2, 2.0, 1.0, None, "heating power factor at the coils (supply voltage² / nominal)"),
    "supply_v": Key("V", 2.0, 12.0, 7.4, None, "supply voltage across a coil at duty 1 (2S LiPo)"),
    "supply_ohm": Key("Ω", 0.0, 50.0, 0.0, None, "source resistance shared by all coils (supply sag under load)"),
    "ambient_c": Key("°C", -10.0, 50.0, 25.0, None, "air and ground temperature"),
    "convection": Key("×", 0.2, 5.0, 1.0, None, "convective heat transfer factor (draught > 1, enclosure < 1)"),
    "fatigue_cycles": Key("cycles", 0.0, 1e6, 0.0, None, "transformation cycles the coils have already made"),
    "fatigue_speedup": Key("×", 1.0, 1e5, 1.0, None, "each cycle made during the run counts this many times"),
    "coil_mismatch": Key("fraction", 0.0, 0.5, 0.0, None,
                         "wire-length mismatch: first coil +m, last coil −m (resistance and mass)"),
    "power_scale": Key("×", 0.2, 2.0, 1.0, "actuator", "heating power factor of one coil (contact resistance)"),
    "overlap_mm": Key("mm", 0.0, 30.0, 8.0, "actuator", "how far a coil reaches past its half of the body (coupling)"),
    "imu_offset_deg": Key("°", -20.0, 20.0, 0.0, "limb", "IMU mounting tilt on the limb"),
    "imu_bias_deg": Key("°", -20.0, 20.0, 0.0, "limb", "IMU accelerometer bias, as an angle"),
    "imu_noise_deg": Key("° rms", 0.0, 5.0, 0.0, None, "white noise on every IMU angle sample"),
    "incline_deg": Key("°", -12.0, 12.0, 0.0, None, "ground slope, rising towards +x"),
    "psi_star_shift_deg": Key("°", -15.0, 15.0, 0.0, "limb", "true critical angle − configured ψ*"),
    "friction": Key("×", 0.2, 3.0, 1.0, None, "scale of every friction coefficient (ground)"),
    "mass_g": Key("g", 1.0, 20.0, 3.3, None, "robot mass"),
}


@dataclass(frozen=True)
class Conditions:
    """One value per scalar key; per-name keys map a name ("" = all) to a value."""

    values: Mapping[str, float] = field(default_factory=dict)
    named: Mapping[str, Mapping[str, float]] = field(default_factory=dict)

    def get(self, key: str) -> float:
        return float(self.values.get(key, KEYS[key].default))

    def for_index(self, key: str, index: int, names: Sequence[str]) -> float:
        """Value of a per-limb/actuator key for item ``index`` of ``names``."""
        per = self.named.get(key, {})
        v = per.get("", KEYS[key].default)
        for name, x in per.items():
            if name and _resolve(key, name, names) == index:
                v = x
        return float(v)

    def check_names(self, limbs: Sequence[str], actuators: Sequence[str]) -> None:
        for key, per in self.named.items():
            names = limbs if KEYS[key].per == "limb" else actuators
            for name in per:
                if name:
                    _resolve(key, name, names)

    def with_(self, *items: str) -> "Conditions":
        """These conditions with ``key=value`` strings applied on top."""
        return parse_conditions(items, self)


def _resolve(key: str, name: str, names: Sequence[str]) -> int:
    if name in names:
        return list(names).index(name)
    if name == "rear":
        return 0
    if name == "front":
        return len(names) - 1
    if name.isdigit() and int(name) < len(names):
        return int(name)
    what = KEYS[key].per
    raise SimError(f"condition {key}: no {what} {name!r} (expected one of: {', '.join(names)}, rear, front, or 0..{len(names) - 1})")


def _number(key: str, text: str) -> float:
    spec = KEYS[key]
    try:
        v = float(text)
    except ValueError:
        raise SimError(f"condition {key}: expected a number in {spec.unit}, got {text!r}") from None
    if not math.isfinite(v) or not spec.lo <= v <= spec.hi:
        raise SimError(f"condition {key}: {v:g} is outside {spec.lo:g}..{spec.hi:g} {spec.unit}")
    return v


def parse_conditions(items: Iterable[str] | Mapping[str, Any], base: Conditions | None = None) -> Conditions:
    """Parse ``key=value`` strings (or a mapping, e.g. a robot file's ``[plant]`` table)."""
    base = base or Conditions()
    values = dict(base.values)
    named = {k: dict(v) for k, v in base.named.items()}
    pairs: list[tuple[str, str]] = []
    if isinstance(items, Mapping):
        for k, v in items.items():
            if isinstance(v, Mapping):
                pairs += [(k, f"{n}:{x}") for n, x in v.items()]
            else:
                pairs.append((k, str(v)))
    else:
        for item in items:
            key, eq, val = item.partition("=")
            if not eq:
                raise SimError(f"condition {item!r}: expected key=value (keys: {', '.join(KEYS)})")
            pairs.append((key.strip(), val.strip()))
    for key, val in pairs:
        if key not in KEYS:
            raise SimError(f"condition {key!r}: unknown key (expected one of: {', '.join(KEYS)})")
        spec = KEYS[key]
        if spec.per is None:
            if ":" in val:
                raise SimError(f"condition {key}: takes one number, not NAME:value")
            values[key] = _number(key, val)
        else:
            name, colon, num = val.rpartition(":")
            named.setdefault(key, {})[name.strip() if colon else ""] = _number(key, num if colon else val)
    return replace(base, values=values, named=named)


def describe_keys() -> str:
    """One line per key: name, unit, range, default, what it does."""
    out = []
    for k, s in KEYS.items():
        per = f" (per {s.per}: NAME:value)" if s.per else ""
        out.append(f"{k:<20} {s.unit:<9} {s.lo:g}..{s.hi:g} (default {s.default:g}){per}  {s.doc}")
    return "\n".join(out)


