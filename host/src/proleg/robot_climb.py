"""``[control] max_climb_deg``, the climb guard's limits (docs/calibration.md, "Too steep to
climb"): the value (``ClimbLimit``), how a robot file gives it (``climb_limit``), and what
robots and builds may carry it (``climb_guard_refusal``, ``check_climb_limit``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

from .names import counted
from .robot_fields import Fields


class ClimbLimit(NamedTuple):
    """``[control] max_climb_deg``: the steepest climb (°) START accepts walking +x and -x. The
    file gives one number for both, or ``{ "+x" = …, "-x" = … }`` where each way is a number
    for all its gaits or a list: the first built-in gaits of that way their own limits (gait 0
    first, in the firmware's order: ``proleg build`` lists it), every other gait of that way
    and a loaded gait stated that way the smallest of the list. ``plus_x``/``minus_x`` are
    each way's limit for a gait without its own."""

    plus_x: float
    minus_x: float
    plus_x_gaits: tuple[float, ...] = ()  # () = plus_x for every +x gait
    minus_x_gaits: tuple[float, ...] = ()

    @classmethod
    def of(cls, plus_x: float | Sequence[float], minus_x: float | Sequence[float]) -> ClimbLimit:
        """From each way's number or per-gait list. The list is kept as short as says the
        same: a trailing entry equal to its smallest goes while the smallest is still listed
        before it (the gaits past the list take the smallest), and a list that is then one
        entry is that number."""
        def split(v: float | Sequence[float]) -> tuple[float, tuple[float, ...]]:
            if isinstance(v, (int, float)):
                return float(v), ()
            per = [float(x) for x in v]
            low = min(per)
            while len(per) > 1 and per[-1] == low and low in per[:-1]:
                per.pop()
            return low, (() if len(per) == 1 else tuple(per))

        (px, pg), (mx, mg) = split(plus_x), split(minus_x)
        return cls(px, mx, pg, mg)

    def gaits_toward(self, direction: str) -> tuple[float, ...]:
        """That way's per-gait limits; () when one number holds all its gaits."""
        return self.plus_x_gaits if direction == "+x" else self.minus_x_gaits

    def toward(self, direction: str, gait: int | None = None) -> float:
        """The limit walking ``direction``: built-in gait ``gait``'s (its own where the list
        has one), or (None) a loaded gait's."""
        per = self.gaits_toward(direction)
        if gait is not None and 0 <= gait < len(per):
            return per[gait]
        return self.plus_x if direction == "+x" else self.minus_x

    def _way(self, direction: str) -> float | list[float]:
        per = self.gaits_toward(direction)
        return list(per) if per else self.toward(direction)

    def to_json(self) -> float | dict[str, float | list[float]]:
        """One number when both ways are the same number, as a robot file would say it."""
        plus, minus = self._way("+x"), self._way("-x")
        return plus if plus == minus and not isinstance(plus, list) else {"+x": plus, "-x": minus}

    def __str__(self) -> str:
        def text(v: float | list[float]) -> str:
            return f"[{', '.join(f'{x:g}' for x in v)}]" if isinstance(v, list) else f"{v:g}"

        j = self.to_json()
        if not isinstance(j, dict):
            return text(j)
        return f'{{ "+x" = {text(j["+x"])}, "-x" = {text(j["-x"])} }}'


def climb_guard_refusal(n_limbs: int, library: Any) -> str:
    """Why a robot cannot carry the climb guard ("" if it can). The guard reads the slope along
    x from the first and last limbs' ends (a chain of limbs from +x to -x) and knows a built-in
    gait's direction only as +x / -x: not a robot with a [gaits] library (headings and turns in
    the plane) or fewer than two limbs."""
    if n_limbs < 2:
        return (f"the climb guard needs at least two limbs (it reads the slope from the first and last ends), "
                f"this robot has {n_limbs}")
    if library is not None:
        return ("not with a [gaits] library (its gaits walk headings in the plane and turn; the guard knows only "
                "+x and -x along a chain of limbs)")
    return ""


#: max_climb_deg's range. Below 0.5° the slope the firmware measures at rest (σ ≈ 0.1°: two
#: ends' readings, each low-passed to 0.13°, level.h) would refuse START on flat ground now and
#: then; it levels on no ground beyond 20° (level.h LEVEL_MAX_CDEG, refused as too tilted), so
#: a limit of 20° or more could never refuse a slope it measures.
MIN_CLIMB_DEG = 0.5
MAX_CLIMB_DEG = 19.5


def climb_limit(f: Fields) -> ClimbLimit | None:
    """``max_climb_deg``: a number for both directions or a table of both, each a number or a
    list of the first gaits' own (checked against the gaits when the firmware's gaits are
    known: ``check_climb_limit``)."""
    if not f.has("max_climb_deg"):
        return None
    value = f.table["max_climb_deg"]
    if isinstance(value, dict):
        ways = Fields(f.path, f"{f.where}.max_climb_deg", value, {"+x", "-x"})
        return ClimbLimit.of(*(_climb_way(ways, d) for d in ("+x", "-x")))
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        f.fail("max_climb_deg", 'a number, or a table { "+x" = …, "-x" = … }', value)
    limit = f.number("max_climb_deg", None, MIN_CLIMB_DEG, MAX_CLIMB_DEG)
    return ClimbLimit(limit, limit)


def _climb_way(ways: Fields, direction: str) -> float | tuple[float, ...]:
    """One way's limit: a number, or a list of one per gait of that way."""
    value = ways.table.get(direction)
    if not isinstance(value, list):
        return ways.number(direction, None, MIN_CLIMB_DEG, MAX_CLIMB_DEG)
    if not value:
        ways.fail(direction, "a number, or a list of one number per gait walking that way", value)
    keys = [f"[{i}]" for i in range(len(value))]
    items = Fields(ways.path, f"{ways.where}.{direction}", dict(zip(keys, value)), set(keys), sep="")
    return tuple(items.number(k, None, MIN_CLIMB_DEG, MAX_CLIMB_DEG) for k in keys)


def check_climb_limit(limit: ClimbLimit | None, gaits: dict[str, Sequence[Any]]) -> str | None:
    """Why ``limit``'s per-gait lists name more gaits than the firmware carries (``gaits``:
    direction → its built-in gaits), or None."""
    if limit is None:
        return None
    for d in ("+x", "-x"):
        per, have = limit.gaits_toward(d), len(gaits.get(d, ()))
        if len(per) > have:
            return (f"control.max_climb_deg.{d}: {counted(len(per), 'limit')}, but the firmware carries "
                    f"{counted(have, 'gait')} walking {d} (one limit per gait, gait 0 first; "
                    "`proleg build` lists them)")
    return None
