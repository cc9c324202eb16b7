"""Which gaits the firmware carries, and the selection that chose them.

``firmware_gaits`` returns the optimal gaits of both directions, every tie (at most
MAX_FIRMWARE_GAITS per direction, the best-ranked), as a
``FirmwareGaits`` mapping (``{"+x": (Gait, ...), "-x": (...)}``) that also names its
``GaitSelection`` (objective, directions, max_transitions, rank), so the rendered gait
table and proleg-build.json can say which inputs chose them.

A robot with a gait library (``[gaits] library`` in the robot file, or ``library=``: issue
17) also carries the library's gaits: each entry's gait is found in the table when it is
already there (an optimal tie of +x or −x), else appended to the +x gaits after the ties.
``FirmwareGaits.library`` says where each one is (direction, index), so a host starts the
gait for a heading with START (``proleg run --heading``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from ..robot import Robot
from ..robot_transitions import HOW_TO_MEASURE

#: The rank of tied optimal gaits in the table: gait 0 is the one START runs by default.
RANK = "fewest opposing steps first, then search order"
DIRECTIONS = ("+x", "-x")
#: Tied optimal gaits the firmware carries per direction at most (the best-ranked ones).
MAX_FIRMWARE_GAITS = 32

def default_max_transitions(robot: Robot, objective: str) -> int | None:
    """max_transitions when none is given (``gait.optimal.whole_body_bound``): None up to 16
    states; for the total objective on larger robots 2 · Σ(levels − 1), a whole-body wave."""
    from ..gait.optimal import whole_body_bound

    return whole_body_bound(robot.levels, objective)


@dataclass(frozen=True)
class GaitSelection:
    objective: str
    max_transitions: int | None  # None = unbounded
    directions: tuple[str, ...] = DIRECTIONS
    rank: str = RANK

    def describe(self) -> str:
        """One line for generated headers."""
        mt = "unbounded" if self.max_transitions is None else str(self.max_transitions)
        return (
            f"objective {self.objective}, max_transitions {mt}, directions {' '.join(self.directions)}, "
            f"every optimal tie ranked {self.rank}"
        )

    def as_json(self) -> dict[str, Any]:
        return {
            "objective": self.objective,
            "max_transitions": self.max_transitions,
            "directions": list(self.directions),
            "rank": self.rank,
        }


@dataclass(frozen=True)
class LibraryGait:
    """One library entry in the firmware's table: START ``direction`` gait ``index`` runs it."""

    heading: Any  # proleg.gait.library.Heading
    direction: str
    index: int
    gait: Any  # proleg.gait.Gait (its reward is the planar score)
    value: float
    below_zero: bool
    net: Any  # proleg.gait.compose.Pose: Δx, Δy, Δθ° of one pass in the start frame
    appended: bool = False  # a gait of its own in the table (not one of the optimal ties)

    def as_json(self, labels) -> dict[str, Any]:
        return {
            "heading": self.heading.name, "heading_deg": self.heading.heading_deg, "rotate": self.heading.rotate,
            "direction": self.direction, "gait": self.index, "states": [labels(s) for s in self.gait.states],
            "value": self.value, "below_zero": self.below_zero,
            "net_motion": {"dx": self.net.x, "dy": self.net.y, "dtheta_deg": self.net.theta_deg},
        }

    def describe(self, labels) -> str:
        what = f"heading {self.heading.name} deg" if self.heading.rotate is None else self.heading.name
        return (f"{what}: {self.direction} gait {self.index} ({' '.join(labels(s) for s in self.gait.states)}), "
                f"per pass dx {self.net.x:+.4g} dy {self.net.y:+.4g} dtheta {self.net.theta_deg:+.3g} deg"
                + (" (nothing scores above zero: the best)" if self.below_zero else ""))


class FirmwareGaits(dict):
    """``{direction: (Gait, ...)}`` plus the ``selection`` that produced it and the gait
    ``library`` (LibraryGait per entry that has a gait; empty without a library)."""

    def __init__(self, gaits: dict, selection: GaitSelection, library: tuple = (), library_spec: Any = None,
                 left_out: dict | None = None, unmeasured: bool = False):
        super().__init__(gaits)
        self.selection = selection
        self.library = tuple(library)
        self.library_spec = library_spec
        #: {direction: why}: a direction whose optimal gaits the hardware cannot make (``left_out_line``)
        self.left_out = dict(left_out or {})
        #: the robot's matrix is unmeasured (``Robot.unmeasured``): no gait moves it yet
        self.unmeasured = unmeasured

    def left_out_line(self, direction: str) -> str | None:
        """Why the firmware carries no gait of ``direction`` (its optimal gait 0 is one the
        hardware cannot make, or the matrix is unmeasured), or None when it was not left out."""
        if self.unmeasured and not self.get(direction):
            return (f"{direction}: the robot's matrix is unmeasured ([transitions] matrix = \"unmeasured\"), so no "
                    f"gait moves it yet and the firmware carries no {direction} gait (START {direction} is refused: "
                    f"NACK NO_GAIT). Learn the matrix {HOW_TO_MEASURE}, and build from that file; a gait of your "
                    f"own runs with proleg load-gait")
        why = self.left_out.get(direction)
        if why is None:
            return None
        return (f"{direction}: none of its optimal gaits can run on this robot (the best-ranked, {why}); the "
                f"firmware carries no {direction} gait (START {direction} is refused: NACK NO_GAIT). Mark the transitions into "
                f"those states \"x\" in the robot file, or learn its matrix (proleg learn marks the transitions "
                f"the hardware cannot make \"x\"); a gait of your own runs with proleg load-gait")


def no_such_gait(gait: int, robot_name: str, direction: str, per_direction: dict[str, int]) -> str:
    """The line refusing ``--gait gait`` of ``direction``, which the robot's firmware does not
    carry (``per_direction``: how many gaits it carries each way). When the other direction has
    gaits the line names them and ``--direction``: a robot that walks only one way (a ratchet)
    was told only that it has "no gait in +x", the default it had not asked for (and so it
    still was for a ``--gait`` past the other direction's)."""
    def shown(k: int) -> str:
        return "no gait" if not k else "gait 0 only" if k == 1 else f"gaits 0..{k - 1}"

    n = per_direction.get(direction, 0)
    line = f"--gait {gait}: {robot_name} has {shown(n)} in {direction}"
    other = next((d for d in DIRECTIONS if d != direction), None)
    m = per_direction.get(other, 0) if other else 0
    if m and (gait < m or not n):
        line += f" (it has {shown(m)} in {other}: --direction {other})"
    return line


def firmware_gaits(robot: Robot, objective: str = "total", max_transitions: int | None = None,
                   library: Any = None) -> FirmwareGaits:
    """The optimal gaits the firmware carries, all ties, for +x and -x (possibly none), and
    the gait library (``library``: a ``LibrarySpec``; default the robot file's ``[gaits]``).

    Ties whose steps each move limbs one way only come first (stable otherwise), so that
    gait 0, the one START and ``proleg sim`` run by default, is the easiest to make
    physically (``proleg.states.opposing_steps``). Gait 0 is then the first tie without an
    error (``gait_problems``), else the first the hardware can make at all: a tie the hardware
    cannot make (``CANNOT_MAKE``: a shared coil moving its limbs apart, a state a raised limb
    cannot reach on the simulated body, no way in from rest) is never gait 0 while another can
    be made (the build refused the robot, though a tie it could walk was there), and one the
    firmware would stop (a state the body cannot hold, a step longer than the state timeout, a
    coil past its on-time: "expect a fault") is not gait 0 while a tie it would walk exists.

    A direction whose gait 0 is still one the hardware cannot make (then every tie is one) is
    left out: its gaits are none, and ``left_out`` says why (``left_out_line``). The build
    warns and goes on, so that a robot whose guessed matrix leads there can still be learned,
    or walk a gait of its user's own (``proleg learn``, ``proleg load-gait``); the firmware
    refuses START of that direction (NACK NO_GAIT), and ``proleg sim`` and ``proleg run`` say why."""
    from ..gait import optimal_gaits
    from ..gait.feasibility import gait_problems
    from ..states import opposing_steps

    def errors(g) -> list:
        return [p for p in gait_problems(robot, g.states) if p.severity == "error"]

    def ordered(gaits):
        out = sorted(gaits, key=lambda g: len(opposing_steps(g.states, robot.levels)))
        if out and errors(out[0]):
            first = None
            for k, g in enumerate(out):  # one by one, to the first clean tie: ties may number thousands
                e = errors(g)
                if not e:
                    first = k
                    break
                if first is None and not cannot_make(e):
                    first = k
            if first is not None:
                out.insert(0, out.pop(first))
        return tuple(out)

    if max_transitions is None:
        max_transitions = default_max_transitions(robot, objective)
    gaits = {
        d: ordered(optimal_gaits(robot.transitions, objective, d, max_transitions).gaits)[:MAX_FIRMWARE_GAITS]
        for d in DIRECTIONS
    }
    left_out = {}
    for d in DIRECTIONS:
        unmade = cannot_make(gait_problems(robot, gaits[d][0].states)) if gaits[d] else []
        if unmade:  # ordered() put a tie the hardware can make first when there is one: there is none
            left_out[d] = unmade[0].message
            gaits[d] = ()
    spec = library if library is not None else getattr(robot, "library", None)
    placed: tuple = ()
    if spec is not None:
        placed = _place_library(robot, spec, gaits)
    return FirmwareGaits(gaits, GaitSelection(objective, max_transitions), placed, spec, left_out,
                         getattr(robot, "unmeasured", False))


def _place_library(robot: Robot, spec: Any, gaits: dict) -> tuple:
    """Each library entry's gait: where it already is in ``gaits``, else appended to +x
    (``gaits`` is updated)."""
    from ..gait.compose import net_motion

    def key(g) -> tuple[int, ...]:
        return tuple(int(s) for s in g.states)

    out = []
    for entry in _entries(robot, spec):
        g = entry.gait
        if g is None:
            continue
        where = next(((d, i) for d in DIRECTIONS for i, h in enumerate(gaits[d]) if key(h) == key(g)), None)
        appended = where is None
        if where is None:
            gaits["+x"] = tuple(gaits["+x"]) + (g,)
            where = ("+x", len(gaits["+x"]) - 1)
        value = float(entry.result.value) if entry.result.value is not None else float("nan")
        out.append(LibraryGait(entry.heading, where[0], where[1], g, value, bool(entry.result.below_zero),
                               net_motion(robot.transitions, g.states), appended))
    return tuple(out)


#: Feasibility problems that mean the hardware cannot make the gait at all.
CANNOT_MAKE = ("shared-actuator", "unreachable", "no-entry")


def cannot_make(problems: Any) -> list[Any]:
    """Of a gait's ``gait_problems``, the errors for which the hardware cannot make it at all
    (``CANNOT_MAKE``); empty when it can."""
    return [p for p in problems if p.severity == "error" and p.kind in CANNOT_MAKE]


def gait_warnings(robot: Robot, gaits: dict) -> list[str]:
    """What the hardware may not do in the firmware's gaits (proleg.gait.feasibility):
    one line per problem, for ``proleg build`` to print, first a line per direction whose
    gaits ``firmware_gaits`` left out (``FirmwareGaits.left_out_line``). BuildError when gait 0
    of a direction (the one START runs by default) is still one the hardware cannot make (a
    shared actuator moving its limbs apart, a state a raised limb cannot reach, or no way in
    from rest over allowed transitions): a gait library's entry the user asked for, appended
    to a direction left empty.
    A coil on longer than safety.max_on_ms (on-time, never-cools) stays a warning: the
    firmware's hold is bang-bang on psi and sma.c enforces the on-time limit and the
    cool-down (the paper's one-actuator R1 walks 10 11 10 with its coil held)."""
    from ..errors import BuildError
    from ..gait.feasibility import gait_problems

    out = []
    left_out = getattr(gaits, "left_out_line", None)
    if left_out is not None:
        out += [line for d in gaits if (line := left_out(d)) is not None]
    for d, gs in gaits.items():
        for i, g in enumerate(gs):
            problems = gait_problems(robot, g.states)
            errors = cannot_make(problems)
            if i == 0 and errors:
                raise BuildError(
                    f"{robot.where}: gait 0 of {d}, the one START runs, cannot run on this robot: "
                    f"{errors[0].message} (choose another objective or --max-transitions, or fix the robot file)"
                )
            # printed after "proleg: warning: "; an error the build lets through (on-time) is one the
            # firmware's envelope will stop the gait for: said so, not called an error in a warning
            out += [f"gait {i} of {d}: {'' if p.severity == 'warning' else 'expect a fault: '}{p.message}"
                    for p in problems]
    return out


#: Steps a fallback gait may have at most (core/limbmap.c copies it into the loaded gait).
MAX_FALLBACK_STEPS = 16


def firmware_fallbacks(robot: Robot) -> dict[tuple[int, str], Any]:
    """Per (lost actuator index, direction): the fallback the firmware switches to by itself
    (proleg.limbloss.fallback), when it has a gait of at most MAX_FALLBACK_STEPS steps.
    Empty when ``[control] fallback = false`` or the robot has a single actuator."""
    from ..limbloss import fallback

    if not getattr(robot.control, "fallback", True) or len(robot.actuators) < 2:
        return {}
    out = {}
    for a in range(len(robot.actuators)):
        for d in DIRECTIONS:
            fb = fallback(robot, a, d)
            if fb.states is not None and len(fb.states) - 1 <= MAX_FALLBACK_STEPS:
                out[(a, d)] = fb
    return out


def fallback_lines(robot: Robot) -> list[str]:
    """What ``proleg build`` says about the fallbacks the firmware carries (or why none)."""
    if not getattr(robot.control, "fallback", True):
        return ["fallback gaits: off ([control] fallback = false)"]
    fbs = firmware_fallbacks(robot)
    if not fbs:  # say which of the reasons it is: an unmeasured robot was told it had one actuator only
        if len(robot.actuators) < 2:
            why = "one actuator only"
        elif getattr(robot, "unmeasured", False):
            why = "the matrix is unmeasured: no gait moves the robot yet, with or without a coil"
        else:
            why = "no single-actuator loss leaves a gait that moves it"
        return [f"fallback gaits: none ({why})"]
    out = []
    for (a, d), fb in sorted(fbs.items()):
        walk = " ".join(fb.table.label(s) for s in fb.states)
        if fb.mode == "remap":  # limbs moved to the coils that are left
            how = "remap: " + ", ".join(f"{limb.name}→{robot.actuators[x].name}"
                                        for limb, x in zip(robot.limbs, fb.actuator_map))
        else:  # the lost coil's limbs stay at level 0, the others keep their coils
            down = [limb.name for limb, x in zip(robot.limbs, fb.actuator_map) if x == a]
            how = f"{', '.join(down)} left down"
        out.append(f"fallback without {robot.actuators[a].name} ({d}): {walk} ({how})")
    return out


@dataclass(frozen=True)
class HeadingChoice:
    """How ``proleg run --heading/--rotate`` runs a heading: START ``direction`` gait
    ``index`` (a library gait in the firmware), or, with ``index`` None, LOAD_GAIT
    ``states`` (open, start not repeated) and START the user gait. ``message`` says which."""

    asked: str
    heading: Any  # proleg.gait.library.Heading that was run
    direction: str
    index: int | None
    states: tuple[int, ...]
    net: Any  # Pose of one pass
    message: str
    nearest: bool = False  # the library's nearest heading, not the one asked for
    still: bool = False  # the library's entry scores nothing above zero for it: said as a warning too

    @property
    def warned(self) -> bool:
        """Whether ``message`` is a warning: another heading, a gait that does not move that way,
        or a gait computed here to be loaded."""
        return self.nearest or self.still or self.index is None


def _entries(robot: Robot, spec: Any) -> list:
    """``spec.entries`` of the robot's table; its GaitError names the robot file, as proleg gait's
    does ("… needs [transitions].dy in the robot file" named none)."""
    from ..errors import GaitError

    try:
        return spec.entries(robot.transitions)
    except GaitError as e:
        raise GaitError(f"{robot.path}: {e}") from None


def choose_heading(robot: Robot, fw: FirmwareGaits, heading_deg: float | None = None, rotate: str | None = None,
                   *, exact: bool = False) -> HeadingChoice:
    """The firmware gait for a heading (degrees) or a rotation ("cw"/"ccw"): the library
    entry for it; for a heading the library does not hold, the nearest heading it holds
    (said in ``message``) — unless ``exact`` or the library has none, when the gait for that
    heading is computed with the library's question (or the plain heading question without
    a library) to be loaded with LOAD_GAIT. GaitError when no gait exists."""
    from ..errors import GaitError
    from ..gait.compose import net_motion
    from ..gait.library import Heading, library_spec, nearest_heading
    from .render import MAX_LOADED_STEPS

    label = robot.transitions.label
    if (heading_deg is None) == (rotate is None):
        raise GaitError("give a heading in degrees or a rotation (cw/ccw), not both")
    asked = f"heading {heading_deg:g}°" if heading_deg is not None else f"rotation {rotate}"
    entries = [(lg.heading, lg) for lg in fw.library]
    if rotate is not None:
        hit = next((lg for h, lg in entries if h.rotate == rotate), None)
    else:
        near = nearest_heading(entries, float(heading_deg))
        hit = near[1] if near is not None and (not exact or near[2] < 1e-9) else None
    if hit is not None:
        off = "" if rotate is not None else abs((hit.heading.heading_deg - heading_deg + 180) % 360 - 180)
        how = ("" if rotate is not None or off < 1e-9 else
               f" (the library's nearest heading, {hit.heading.name}°, {off:g}° off)")
        # the build says so of such an entry; run, which walks it, said nothing (planar: 270° walked +y)
        still = (" (nothing scores above zero for it: the library's best, which does not move that way)"
                 if hit.below_zero else "")
        return HeadingChoice(asked, hit.heading, hit.direction, hit.index, tuple(hit.gait.states[:-1]), hit.net,
                             f"{asked}{how}: {hit.direction} gait {hit.index} from the firmware's library, "
                             f"{' '.join(label(s) for s in hit.gait.states)}, per pass dx {hit.net.x:+.3g} "
                             f"dy {hit.net.y:+.3g} dtheta {hit.net.theta_deg:+.3g}°{still}",
                             nearest=bool(how), still=hit.below_zero)
    spec = fw.library_spec
    if spec is None:
        spec = library_spec("0")
    heading = Heading(f"{heading_deg:g}", heading_deg=float(heading_deg)) if rotate is None else \
        Heading(f"rot-{rotate}", rotate=rotate)
    entry = _entries(robot, replace(spec, headings=(heading,)))[0]
    if entry.gait is None:
        raise GaitError(f"{asked}: {robot.name} has no gait for it (no closed walk qualifies)")
    g = entry.gait
    table = next(((d, i) for d in DIRECTIONS for i, h in enumerate(fw.get(d) or ())
                  if tuple(int(s) for s in h.states) == tuple(int(s) for s in g.states)), None)
    if table is not None:  # the firmware carries it: START it by its index, with its way in from rest; loaded
        # as the user gait it has none, and from rest in a state it does not visit it was refused
        d, i = table
        net = net_motion(robot.transitions, g.states)
        why = "not in the firmware's library" if fw.library else "the firmware carries no gait library"
        return HeadingChoice(asked, heading, d, i, tuple(g.states[:-1]), net,
                             f"{asked}: {why}; computed {' '.join(label(s) for s in g.states)}, the firmware's {d} "
                             f"gait {i} (per pass dx {net.x:+.3g} dy {net.y:+.3g} dtheta {net.theta_deg:+.3g}°)")
    if len(g.states) - 1 > MAX_LOADED_STEPS:
        raise GaitError(f"{asked}: the gait for it has {len(g.states) - 1} steps, LOAD_GAIT takes at most "
                        f"{MAX_LOADED_STEPS}; put the heading in the robot file's [gaits] library")
    net = net_motion(robot.transitions, g.states)
    why = "not in the firmware's library" if fw.library else "the firmware carries no gait library"
    return HeadingChoice(asked, heading, "+x", None, tuple(g.states[:-1]), net,
                         f"{asked}: {why}; computed {' '.join(label(s) for s in g.states)} (per pass dx "
                         f"{net.x:+.3g} dy {net.y:+.3g} dtheta {net.theta_deg:+.3g}°), to be loaded with LOAD_GAIT")
