"""Conditions of a simulated run: supply, air, wear, sensors and world (``key=value``).

Every key, its unit and range is in ``KEYS`` (the physical keys of the robot file's
``[plant]`` schema, ``proleg.robot_plant.PLANT_KEYS``; ``conditions_from_section`` turns a
robot file's ``[plant]`` values into ``Conditions``). Per-limb and per-actuator keys take
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
from ...robot_plant import PHYSICAL_KEYS, PLANT_KEYS, PlantKey
from ...typed import typed_float


@dataclass(frozen=True)
class Key:
    unit: str
    lo: float
    hi: float
    default: float
    per: str | None  # None: one value; "limb" / "actuator": per name
    doc: str
    spec: PlantKey

    def accepts(self, v: float) -> bool:
        return self.spec.accepts(v)

    def range_text(self) -> str:
        return self.spec.range_text()


def _key(spec: PlantKey) -> Key:
    default = spec.default_for("physical")
    assert default is not None
    return Key(spec.unit, spec.lo, spec.hi, default, spec.per or None, spec.doc, spec)


# The one schema lives with the robot file's [plant] table (proleg.robot_plant): the same keys,
# units and ranges for the robot file and for ``--condition``.
KEYS: dict[str, Key] = {name: _key(PLANT_KEYS[name]) for name in PHYSICAL_KEYS}


@dataclass(frozen=True)
class Conditions:
    """One value per scalar key; per-name keys map a name ("" = all) to a value."""

    values: Mapping[str, float] = field(default_factory=dict)
    named: Mapping[str, Mapping[str, float]] = field(default_factory=dict)

    def get(self, key: str) -> float:
        """A key's one value; for a per-limb or per-actuator key the value given for all of
        them (``for_index`` reads one item's)."""
        if KEYS[key].per:
            return float(self.named.get(key, {}).get("", KEYS[key].default))
        return float(self.values.get(key, KEYS[key].default))

    def for_index(self, key: str, index: int, names: Sequence[str], by_limb: Sequence[int] = (),
                  limbs: Sequence[str] = ()) -> float:
        """Value of a per-limb/actuator key for item ``index`` of ``names``; for an actuator
        key, ``limbs`` and ``by_limb`` (each limb's actuator index) let a limb's name name its
        actuator."""
        per = self.named.get(key, {})
        v = per.get("", KEYS[key].default)
        for name, x in per.items():
            if name and _resolve(key, name, names, by_limb, limbs) == index:
                v = x
        return float(v)

    def check_names(self, limbs: Sequence[str], actuators: Sequence[str], by_limb: Sequence[int] = ()) -> None:
        for key, per in self.named.items():
            per_limb = KEYS[key].per == "limb"
            for name in per:
                if name:
                    _resolve(key, name, limbs if per_limb else actuators, () if per_limb else by_limb,
                             limbs if not per_limb else ())

    def with_(self, *items: str) -> "Conditions":
        """These conditions with ``key=value`` strings applied on top."""
        return parse_conditions(items, self)


def coil_of_limb(robot: Any) -> list[int]:
    """Each limb's actuator index (the ``by_limb`` a per-actuator key resolves names with)."""
    acts = [a.name for a in robot.actuators]
    return [acts.index(lb.actuator) for lb in robot.limbs]


def actuator_index(robot: Any, name: str) -> int:
    """The actuator ``name`` means on ``robot`` as a per-actuator condition reads it: its own
    name or index, a limb's name (that limb's coil), or rear/front (the first/last limb's)."""
    return _resolve("power_scale", name, [a.name for a in robot.actuators], coil_of_limb(robot),
                    [lb.name for lb in robot.limbs])


#: The first and the last limb (or their actuators), where no limb or actuator has that name.
ALIASES = {"rear": 0, "front": -1}


class NoSuchName(SimError):
    """``resolve_name``: ``name`` names nothing (the caller says what it expected)."""


def resolve_name(name: str, names: Sequence[str], by_limb: Sequence[int] = (), limbs: Sequence[str] = (), *,
                 index: bool = True) -> int:
    """Index in ``names`` (limbs, or actuators) that ``name`` means: the one way ``--condition``
    and ``--inject`` read a limb's or an actuator's name. ``name`` is taken with the spaces at
    its ends stripped and may hold any other character (``front@pad``, ``leg+2``); it is a name
    of ``names``, then (actuators, with ``by_limb``: each limb's actuator) a limb's name, meaning
    that limb's actuator, then a name with its spaces at the ends not counting (a limb named
    " a" is "a"), then rear/front (the first/last limb, or its actuator) where nothing has that
    name, then (``index``) an index. ``NoSuchName`` when it names nothing, a ``SimError`` when
    it names two alike."""
    name = name.strip()
    if name in names:
        return list(names).index(name)
    if by_limb and limbs and name in limbs:
        return by_limb[list(limbs).index(name)]
    # a limb named " a" (a robot file may give one) is "a": `proleg check` refused its own draw
    # imu_bias_deg= a:1.1 ("no limb 'a'"), and --inject imu-silent:a refused what --condition took
    for pool, at in ((names, None), (limbs if by_limb else (), by_limb)):
        bare = [n.strip() for n in pool]
        if bare.count(name) > 1:
            raise SimError(f"{name!r} names {', '.join(repr(n) for n in pool if n.strip() == name)} alike (spaces "
                           "at a name's ends do not count): give the index instead")
        if name in bare:
            return bare.index(name) if at is None else at[bare.index(name)]
    if name in ALIASES:
        ends = by_limb or range(len(names))
        return ends[ALIASES[name]]
    if index and name.isdigit() and int(name) < len(names):
        return int(name)
    raise NoSuchName(f"nothing is named {name!r}")


def _resolve(key: str, name: str, names: Sequence[str], by_limb: Sequence[int] = (),
             limbs: Sequence[str] = ()) -> int:
    """Index in ``names`` that ``name`` means for ``key`` (``resolve_name``). For an actuator key
    with ``by_limb`` (each limb's actuator) a limb's name, and rear/front, mean that limb's
    actuator, so that ``imu_bias_deg=front:3`` and ``power_scale=front:0.8`` name the same end
    of the robot."""
    try:
        return resolve_name(name, names, by_limb, limbs)
    except NoSuchName:
        pass
    except SimError as e:
        raise SimError(f"condition {key}: {e}") from None
    what = KEYS[key].per
    also = [a for a in ALIASES if a not in names and a not in limbs]
    named = [*names, *(f"{lb} (its limb)" for lb in limbs if lb not in names)] if by_limb else list(names)
    raise SimError(f"condition {key}: no {what} {name.strip()!r} (expected one of: {', '.join([*named, *also])}, "
                   f"or 0..{len(names) - 1})")


def _number(key: str, text: str) -> float:
    spec = KEYS[key]
    try:
        v = typed_float(text)
    except ValueError:
        raise SimError(f"condition {key}: expected a number{_in_unit(spec.unit)}, got {text!r}") from None
    if not math.isfinite(v):
        raise SimError(f"condition {key}: expected a finite number in {spec.range_text()}, got {text!r}")
    if not spec.accepts(v):
        # as given: {v:g} refused power=2.0000001 as "2 is outside [0.2, 2]"
        raise SimError(f"condition {key}: {text.strip()} is outside {spec.range_text()}")
    return v


def _in_unit(unit: str) -> str:
    """What a value of ``unit`` is, after "expected a number": "in ×" read oddly."""
    if unit == "×":
        return " (a factor, ×)"
    return f" (in {unit})" if unit else ""


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
        given: dict[tuple[str, str], str] = {}
        for item in items:
            key, eq, val = item.partition("=")
            if not eq:
                raise SimError(f"condition {item!r}: expected key=value (keys: {', '.join(KEYS)})")
            pairs.append((key.strip(), val.strip()))
            _once(given, key.strip(), val.strip(), item)
    fresh: dict[str, set[str]] = {}  # per key, the names these items set (not ``base``)
    for key, val in pairs:
        if key in PLANT_KEYS and key not in KEYS:  # length_mm, working_strain, the coils' wire, as_c..mf_c
            raise SimError(f"condition {key!r}: a key of the robot file's [plant] table only (the robot's body, "
                           f"coils or table plant: docs/robot-file.md), not a run condition (one of: {', '.join(KEYS)})")
        if key not in KEYS:
            raise SimError(f"condition {key!r}: unknown key (expected one of: {', '.join(KEYS)})")
        spec = KEYS[key]
        if spec.per is None:
            if ":" in val:
                raise SimError(f"condition {key}: takes one number, not NAME:value")
            values[key] = _number(key, val)
        else:
            name, colon, num = val.rpartition(":")
            if colon and not name.strip():  # ":3" read as every item: a name left out by mistake
                article = "an" if spec.per[0] in "aeiou" else "a"
                raise SimError(f"condition {key}: expected NAME:value with {article} {spec.per} name or index before "
                               f"':', or a bare value for every {spec.per}, got {val!r}")
            per = named.setdefault(key, {})
            if not colon:
                # a bare value goes on top of every item ``base`` names: a robot file's
                # imu_bias_deg = [1, -1] kept both limbs at ±1° under --condition imu_bias_deg=15
                for n in [n for n in per if n and n not in fresh.get(key, set())]:
                    del per[n]
            per[name.strip() if colon else ""] = _number(key, num if colon else val)
            fresh.setdefault(key, set()).add(name.strip() if colon else "")
    return replace(base, values=values, named=named)


def _once(given: dict[tuple[str, str], str], key: str, val: str, item: str) -> None:
    """A key (for a per-limb or per-actuator key: a key and a name) given twice is a SimError
    naming both: which one was meant cannot be told, so the last is not silently taken."""
    name = val.rpartition(":")[0].strip() if key in KEYS and KEYS[key].per else ""
    if (key, name) in given:
        which = f"{key} for {name!r}" if name else key
        raise SimError(f"condition {which}: given twice ({given[key, name]!r} and {item!r}); give it once")
    given[key, name] = item


def check_given_once(items: Iterable[str], limbs: Sequence[str], actuators: Sequence[str],
                     by_limb: Sequence[int] = ()) -> None:
    """``_once`` on a known robot: two ``key=NAME:value`` strings whose names mean the same limb
    or actuator (``0`` and ``tail``, ``front`` and ``head``, a limb and its coil) are the same
    SimError as one name given twice, not the last silently taken."""
    seen: dict[tuple[str, int], str] = {}
    for item in items:
        key, _, val = item.partition("=")
        key = key.strip()
        name = val.rpartition(":")[0].strip()
        if key not in KEYS or not KEYS[key].per or not name:
            continue
        per_limb = KEYS[key].per == "limb"
        names = limbs if per_limb else actuators
        index = _resolve(key, name, names, () if per_limb else by_limb, () if per_limb else limbs)
        if (key, index) in seen:
            raise SimError(f"condition {key}: {seen[key, index]!r} and {item!r} both name {KEYS[key].per} "
                           f"{names[index]!r}; give it once")
        seen[key, index] = item


def by_item_name(cond: Conditions, limbs: Sequence[str], actuators: Sequence[str],
                 by_limb: Sequence[int] = ()) -> Conditions:
    """``cond`` with one per-limb or per-actuator value for each limb or actuator, the last given
    (as the plant reads them: ``Conditions.for_index``), under the name it was given by. A robot
    file's ``overlap_mm = 20`` (listed as ``sma-right:20``) under ``--condition overlap_mm=right:14``
    kept both, so ``effective_conditions`` named the coil twice, and given back as
    ``--condition`` they were refused ("both name actuator 'sma-right'")."""
    named: dict[str, dict[str, float]] = {}
    for key, per in cond.named.items():
        per_limb = KEYS[key].per == "limb"
        names = limbs if per_limb else actuators
        last: dict[int, str] = {}   # item -> the name its value was last given by
        for name in per:
            if name:
                last[_resolve(key, name, names, () if per_limb else by_limb, () if per_limb else limbs)] = name
        kept = set(last.values())
        named[key] = {name: v for name, v in per.items() if not name or name in kept}
    return replace(cond, named=named)


def describe_keys() -> str:
    """One line per key: name, unit, range, default, what it does."""
    out = []
    for k, s in KEYS.items():
        per = f" (per {s.per}: NAME:value)" if s.per else ""
        out.append(f"{k:<20} {s.range_text():<18} default {s.default:g}{per}  {s.doc}")
    return "\n".join(out)




def conditions_from_section(section: Any, actuators: Sequence[str], limbs: Sequence[str]) -> Conditions:
    """The physical keys a robot file's checked ``[plant]`` table gives, as ``Conditions``
    (``section``: ``proleg.robot_plant.PlantSection``). A per-actuator ``supply_v`` list is each
    coil's own supply (``supply_v=NAME:value``), one number every coil's. It used to become the
    highest voltage and a ``power_scale`` of (V_j / V_max)² per coil, so a ``--condition
    power_scale=1`` (a crimp) put R1's 3 V coil on 7.4 V, and ``effective_conditions`` named a
    ``power_scale`` below 0.2 that ``--condition`` refused."""
    values: dict[str, float] = {}
    named: dict[str, dict[str, float]] = {}
    given = dict(getattr(section, "physical", {}) or {})
    for key, v in given.items():
        per = KEYS[key].per
        if per is None:
            values[key] = float(v)  # type: ignore[arg-type]
            continue
        if key == "supply_v" and not isinstance(v, tuple):
            named[key] = {"": float(v)}  # one supply: ``Conditions.get("supply_v")``
            continue
        names = actuators if per == "actuator" else limbs
        vals = v if isinstance(v, tuple) else (float(v),) * len(names)
        named[key] = {name: float(x) for name, x in zip(names, vals)}
    return Conditions(values=values, named=named)
