"""Measure a robot's transition reward matrix on the physical plant (no firmware needed).

``measure_matrix`` drives the plant with the idealised drive (``drive.IdealDrive``: perfect
sensing, each limb's coil heated at ``duty`` until its end is ``margin_deg`` past its target
level's critical angle, then held there), its duties put through the firmware's safety
envelope (``envelope.Envelope``: the duty ceiling, the on-time limit, the mean-duty window and
the state timeout, as the robot's firmware is built with them). For every allowed transition
a → b it goes to a, settles, records the centre of mass, drives to b, settles again and records
the displacement; ``repeats`` times. A transition the drive cannot reach within ``timeout_s``,
or only past the envelope (it would latch a fault), gets no sample (its entry is NaN and its
count 0); the envelope's faults are kept in ``MeasuredMatrix.latched``, and the coils rest
until the on-time debt is paid before the next one, as an operator clears the fault. ``measure_matrix_range`` measures it at several hold margins,
``measure_history_range`` in several orders (each entry starts where the one before left the
body, so an entry depends on what came before it: docs/plant.md).

``kinematic_signs`` does the same with the coils' contractions moved directly at a fixed rate
(no thermal model): the sign pattern a friction assignment predicts, used to infer D1/D2.
"""

from __future__ import annotations

import random
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .conditions import Conditions
from .drive import (  # noqa: F401 (re-exported: the idealised drive was part of this module)
    CLIMB_GAIN_DEG,
    CLIMB_MAX_S,
    CLIMB_STOP_DPS,
    CLIMB_STOP_S,
    FALL_SHARE,
    FALL_WAIT_S,
    HOVER_S,
    LAG_S,
    MARGIN_DEG,
    PROGRESS_DEG,
    SHARE_SYNC,
    EnvelopeWalk,
    IdealDrive,
    _run_to,
    run_sequence,
    walk_within_envelope,
)
from .envelope import Envelope, EnvelopeLatched
from .plant import PhysicalParams, PhysicalPlant


@dataclass
class MeasuredMatrix:
    states: list[str]
    matrix_mm: np.ndarray      # mean displacement per transition, NaN where not measured
    std_mm: np.ndarray
    samples: np.ndarray        # int counts
    duration_s: np.ndarray     # mean time to reach the target state
    mechanisms: tuple[str, ...]
    mechanism_source: str
    #: each coil's hottest (°C) while measuring, by actuator name: a supply that cooks a coil
    #: cooks it here too
    coil_peak_c: dict[str, float] = field(default_factory=dict)
    #: (from, to) → the fault the safety envelope latched on that transition's way (its last
    #: try): the firmware, keeping to the same envelope, would stop there too
    latched: dict[tuple[int, int], str] = field(default_factory=dict)

    def to_json(self) -> dict:
        return {"states": self.states, "matrix": json_matrix(self.matrix_mm), "units": "mm",
                "std": json_matrix(self.std_mm), "samples": self.samples.tolist(),
                "duration_s": json_matrix(self.duration_s), "mechanisms": list(self.mechanisms),
                "mechanism_source": self.mechanism_source,
                "coil_peak_c": {k: round(v, 1) for k, v in self.coil_peak_c.items()},
                "latched": {f"{self.states[a]}->{self.states[b]}": code for (a, b), code in sorted(self.latched.items())}}


def json_matrix(m: np.ndarray) -> list:
    """A matrix for JSON: rounded to 0.1 µm, null where there is no (finite) value."""
    return [[None if not np.isfinite(x) else round(float(x), 4) for x in row] for row in m]


def measure_matrix(robot: Any, conditions: Conditions | None = None, *, repeats: int = 2,
                   duty: float | None = None, margin_deg: float = MARGIN_DEG, settle_s: float = 2.5,
                   timeout_s: float = 12.0, dt_s: float = 0.002, seed: int = 0,
                   params: PhysicalParams | None = None, mechanisms: Sequence[Any] | None = None,
                   on_step: Callable[[int, int, int], None] | None = None, order: str = "rows",
                   order_seed: int = 0, envelope: bool = True) -> MeasuredMatrix:
    """The reward matrix of ``robot`` measured on the physical plant (mm, row = from).
    ``on_step(tried, sampled, total)`` after each transition tried: how many were tried, how
    many of those gave a sample, of ``total`` (the allowed transitions × ``repeats``).
    ``order``: the order the transitions are made in, each repeat alike (``ORDERS``).
    ``envelope``: keep to the firmware's safety envelope (off: the bare idealised drive, which
    heats a step until it is made and held, however hot: the one-actuator R1 reached 183 °C)."""
    plant = PhysicalPlant(robot, conditions, seed=seed, params=params, mechanisms=mechanisms)
    drive = IdealDrive(robot, plant, margin_deg)
    duty = robot.control.drive_duty if duty is None else duty
    _, allowed = robot.transitions.dense()
    n = len(allowed)
    sums = [[[] for _ in range(n)] for _ in range(n)]
    times = [[[] for _ in range(n)] for _ in range(n)]
    steps = _ordered([(a, b) for a in range(n) for b in range(n) if a != b and allowed[a][b]], order, order_seed)
    gate = Envelope(robot, max(a.channel for a in plant.params.actuators) + 1, dt_s) if envelope else None
    latched: dict[tuple[int, int], str] = {}
    tried = sampled = 0
    for _ in range(repeats):
        for a, b in steps:
            took = None
            try:
                if _run_to(plant, drive, a, duty, dt_s, timeout_s, settle_s, gate) is not None:
                    x0 = plant.displacement_mm
                    took = _run_to(plant, drive, b, duty, dt_s, timeout_s, settle_s, gate)
                latched.pop((a, b), None)  # what its last try did: this one latched nothing
            except EnvelopeLatched as e:
                assert gate is not None
                latched[a, b] = e.code
                _rest(plant, gate, dt_s)
                drive.boosted.clear()  # the operator's CLEAR and START begin the firmware's next run unboosted
            if took is not None:
                sums[a][b].append(plant.displacement_mm - x0)
                times[a][b].append(took)
                sampled += 1
            tried += 1
            if on_step is not None:
                on_step(tried, sampled, len(steps) * repeats)
    mean = np.full((n, n), np.nan)
    std = np.full((n, n), np.nan)
    dur = np.full((n, n), np.nan)
    count = np.zeros((n, n), dtype=int)
    for a in range(n):
        for b in range(n):
            if sums[a][b]:
                mean[a, b] = float(np.mean(sums[a][b]))
                std[a, b] = float(np.std(sums[a][b]))
                dur[a, b] = float(np.mean(times[a][b]))
                count[a, b] = len(sums[a][b])
    labels = robot.transitions.labels() if hasattr(robot.transitions, "labels") else [str(i) for i in range(n)]
    peaks = {a.name: t for a, t in zip(robot.actuators, plant.peak_temperature_c)}
    return MeasuredMatrix(list(labels), mean, std, count, dur, tuple(plant.mechanisms), plant.mechanism_source, peaks,
                          {k: v for k, v in latched.items() if not count[k]})


def _rest(plant: PhysicalPlant, gate: Envelope, dt_s: float) -> None:
    """After a latched fault: every coil off until the envelope's on-time debt is paid (at least
    ``REST_S``), then the fault cleared (``Envelope.acknowledge``), as an operator would."""
    off = [0.0] * len(gate.debt)
    waited = 0.0
    while waited < REST_S or any(gate.debt):
        plant.step(dt_s, gate.gate(off))
        waited += dt_s
    gate.acknowledge()


#: the least rest after a latched fault: the coils cool towards the air first
REST_S = 3.0


#: The orders ``measure_matrix`` makes the transitions in: row by row (the default), the same
#: reversed, and a random permutation (``order_seed``). ``measure_history_range`` uses all three.
ORDERS = ("rows", "reversed", "shuffled")


def _ordered(steps: list[tuple[int, int]], order: str, seed: int) -> list[tuple[int, int]]:
    if order == "rows":
        return steps
    if order == "reversed":
        return steps[::-1]
    if order == "shuffled":
        shuffled = list(steps)
        random.Random(seed).shuffle(shuffled)
        return shuffled
    raise ValueError(f"measure_matrix: order must be one of {', '.join(ORDERS)}, got {order!r}")


def _low_high(measured: Sequence[MeasuredMatrix]) -> tuple[np.ndarray, np.ndarray]:
    stack = np.array([m.matrix_mm for m in measured])
    return np.fmin.reduce(stack, axis=0), np.fmax.reduce(stack, axis=0)


#: Hold margins (° past the critical angle) that ``measure_matrix_range`` spans: a drive may hold a
#: raised limb anywhere from half to twice the idealised drive's 4°, and the firmware's raised limbs
#: pass through all of it in a gait (they overshoot to about ψ* + 13° before they settle on their
#: hold edge, ψ* + h/2 + ``control.hold_margin_deg``).
HOLD_RANGE_DEG = (MARGIN_DEG / 2, MARGIN_DEG, 2 * MARGIN_DEG)


@dataclass
class MatrixRange:
    """The matrix measured at several hold margins: per entry, the lowest and highest mean
    over the margins at which it was measured (NaN where none reached it)."""

    margins_deg: tuple[float, ...]
    measured: tuple[MeasuredMatrix, ...]
    low_mm: np.ndarray
    high_mm: np.ndarray

    def at(self, margin_deg: float) -> MeasuredMatrix:
        """The matrix measured at ``margin_deg`` (one of ``margins_deg``)."""
        return self.measured[self.margins_deg.index(margin_deg)]

    def cycle_range(self, states: Sequence[int]) -> tuple[float, float]:
        """(lowest, highest) displacement along ``states``, each step at its own extreme: within a
        gait, each step's held limbs may sit anywhere in the range, independently of the others."""
        steps = list(zip(states, states[1:]))
        return (float(sum(self.low_mm[a, b] for a, b in steps)),
                float(sum(self.high_mm[a, b] for a, b in steps)))

    def to_json(self) -> dict:
        return {"hold_margins_deg": list(self.margins_deg), "low": json_matrix(self.low_mm),
                "high": json_matrix(self.high_mm)}


def measure_matrix_range(robot: Any, margins_deg: Sequence[float] = HOLD_RANGE_DEG, *, jobs: int = 1,
                         **kwargs: Any) -> MatrixRange:
    """``measure_matrix`` once per hold margin, and each entry's range over them.

    How far past ψ* the held limbs are changes the body's shape and the load on each contact,
    and with it which end slides: R1's 11 → 00 measures −0.90 mm at 2°, +0.01 at 4° and −0.07
    at 8°. The range says how much the matrix depends on the hold; it is not a bound on what
    a drive that holds within it walks (a gait's steps interact: docs/plant.md).

    The margins are measured on plants of their own, so ``jobs`` > 1 measures up to that many
    at once in worker processes, with the same numbers as one after another (each matrix is
    one chain of transitions on one body, each starting where the last ended: it is not split)."""
    if not margins_deg:
        raise ValueError("measure_matrix_range: no hold margins given")
    if jobs < 1:
        raise ValueError(f"measure_matrix_range: jobs must be at least 1, got {jobs!r}")
    measured = _measure_variants(robot, [{"margin_deg": m} for m in margins_deg], jobs, "at a hold margin", kwargs)
    return MatrixRange(tuple(float(m) for m in margins_deg), tuple(measured), *_low_high(measured))


@dataclass
class HistoryRange:
    """The matrix measured with its transitions made in several orders (``ORDERS``): per entry,
    the lowest and highest mean over the orders (NaN where none reached it). Each entry starts
    where the transition before it left the body (its coils' heat, how far each limb is held),
    so the range is how much an entry depends on what came before it; the samples of one order
    (``std``) do not show that."""

    orders: tuple[str, ...]
    measured: tuple[MeasuredMatrix, ...]
    low_mm: np.ndarray
    high_mm: np.ndarray

    def at(self, order: str) -> MeasuredMatrix:
        return self.measured[self.orders.index(order)]

    def to_json(self) -> dict:
        return {"orders": list(self.orders), "low": json_matrix(self.low_mm), "high": json_matrix(self.high_mm)}


def pooled(measured: Sequence[MeasuredMatrix]) -> MeasuredMatrix:
    """One matrix from several measurements of it: per entry the mean and spread of all their
    samples together (the spread over ``HistoryRange``'s orders is its history's, which one
    order's samples do not show), the samples summed, the durations their samples' mean."""
    first = measured[0]
    n = np.array([m.samples for m in measured], dtype=float)
    total = n.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        def mean_of(values: np.ndarray) -> np.ndarray:
            return np.where(total > 0, np.nansum(np.where(n > 0, values * n, 0.0), axis=0) / total, np.nan)
        mean = mean_of(np.array([m.matrix_mm for m in measured]))
        second = mean_of(np.array([m.std_mm ** 2 + m.matrix_mm ** 2 for m in measured]))
        std = np.sqrt(np.maximum(second - mean ** 2, 0.0))
        duration = mean_of(np.array([m.duration_s for m in measured]))
    latched = {k: v for m in measured for k, v in m.latched.items() if not total[k]}
    return MeasuredMatrix(first.states, mean, std, total.astype(int), duration, first.mechanisms,
                          first.mechanism_source, hottest(measured), latched)


def hottest(measured: Sequence[MeasuredMatrix | None]) -> dict[str, float]:
    """Each coil's hottest over several measurements (``MeasuredMatrix.coil_peak_c``; a None
    among them is one not made)."""
    out: dict[str, float] = {}
    for m in measured:
        for name, t in (m.coil_peak_c.items() if m is not None else ()):
            out[name] = max(t, out.get(name, t))
    return out


def measure_history_range(robot: Any, orders: Sequence[str] = ORDERS, *, jobs: int = 1,
                          **kwargs: Any) -> HistoryRange:
    """``measure_matrix`` once per order of ``orders`` (the first is the one ``measure_matrix``
    makes by default), and each entry's range over them. Measured in reverse, R1's steps into
    and out of 11 moved by up to 1.24 mm and three changed sign, its one-limb steps by less than
    0.2 mm (docs/plant.md). ``jobs`` > 1: the orders on plants of their own in worker processes,
    with the same numbers as one after another."""
    if not orders:
        raise ValueError("measure_history_range: no orders given")
    for o in orders:
        _ordered([], o, 0)  # an unknown order: ValueError before anything is measured
    measured = _measure_variants(robot, [{"order": o} for o in orders], jobs, "in an order", kwargs)
    return HistoryRange(tuple(orders), tuple(measured), *_low_high(measured))


def _measure_variants(robot: Any, variants: Sequence[dict[str, Any]], jobs: int, what: str,
                      kwargs: dict[str, Any]) -> list[MeasuredMatrix]:
    """``measure_matrix`` once per variant (its keyword arguments on top of ``kwargs``), one after
    another or, with ``jobs`` > 1, in worker processes; ``kwargs``' ``on_step`` hears the counts
    summed over the variants either way."""
    if jobs < 1:
        raise ValueError(f"measuring the matrix {what}: jobs must be at least 1, got {jobs!r}")
    on_step = kwargs.pop("on_step", None)
    if min(jobs, len(variants)) > 1:
        return _measure_at_once(robot, variants, jobs, on_step, kwargs, what)
    measured: list[MeasuredMatrix] = []
    for v in variants:
        step = _counting_on(on_step, measured, len(variants))
        measured.append(measure_matrix(robot, on_step=step, **{**kwargs, **v}))
    return measured


def _measure_at_once(robot: Any, variants: Sequence[dict[str, Any]], jobs: int,
                     on_step: Callable[[int, int, int], None] | None,
                     kwargs: dict[str, Any], what: str) -> list[MeasuredMatrix]:
    """``measure_matrix`` for each variant in up to ``jobs`` worker processes, in the order
    given. Each worker sends its ``on_step`` counts back through a queue; ``on_step`` hears the
    sums over the variants, as it does from the variants one after another."""
    import multiprocessing
    import queue as queue_mod
    from concurrent.futures.process import BrokenProcessPool

    from ...interrupts import end_workers, lost_worker, worker_pool

    with multiprocessing.get_context("fork").Manager() as manager:
        counts = manager.Queue()
        pool = worker_pool(min(jobs, len(variants)))
        try:
            pending = [pool.submit(_measure_variant, robot, v, i, counts, kwargs) for i, v in enumerate(variants)]
            tried, sampled, total = [0] * len(pending), [0] * len(pending), [0] * len(pending)
            while True:
                try:
                    i, t, s, n = counts.get(timeout=0.2)
                except queue_mod.Empty:
                    if all(p.done() for p in pending):  # a worker that died is done too (BrokenProcessPool)
                        break
                    continue
                tried[i], sampled[i], total[i] = t, s, n
                if on_step is not None:
                    on_step(sum(tried), sum(sampled), max(total) * len(pending))
            try:
                measured = [p.result() for p in pending]   # a worker's error is raised here
            except BrokenProcessPool:
                raise lost_worker(f"measuring the matrix {what}") from None
        finally:
            end_workers(pool)
    return measured


def _measure_variant(robot: Any, variant: dict[str, Any], index: int, counts: Any,
                     kwargs: dict[str, Any]) -> MeasuredMatrix:
    """One worker's variant for ``_measure_at_once``: its counts go to ``counts`` tagged ``index``."""
    return measure_matrix(robot, on_step=lambda t, s, n: counts.put((index, t, s, n)), **{**kwargs, **variant})


def _counting_on(on_step: Callable[[int, int, int], None] | None, measured: Sequence[MeasuredMatrix],
                 n_margins: int) -> Callable[[int, int, int], None] | None:
    """``on_step`` for the next of ``n_margins`` measurements (margins or orders): its counts go
    on from the matrices already ``measured``, out of all the measurements' transitions."""
    if on_step is None:
        return None
    done, sampled_before = len(measured), sum(int(x.samples.sum()) for x in measured)
    return lambda tried, sampled, total: on_step(done * total + tried, sampled_before + sampled, total * n_margins)


#: The physical conditions that shape the body rather than the run (``body.body_geometry``):
#: a kinematic sweep takes them from the robot file's ``[plant]``, and no others.
BODY_CONDITIONS = ("overlap_mm",)


def body_conditions(robot: Any) -> Conditions:
    """Nominal conditions on the robot file's body: its ``[plant]`` values of
    ``BODY_CONDITIONS``, every other condition at its default. A sweep on ``Conditions()``
    posed the default overlap_mm, not the file's: a 200 mm three-limb body with
    ``overlap_mm = 0`` was refused by ``proleg sim`` as curling over itself (its middle coil
    taken to span 116 mm, not 100) while inferring its friction mechanisms."""
    from .conditions import conditions_from_section

    return body_of_run(conditions_from_section(getattr(robot, "plant", None), [a.name for a in robot.actuators],
                                               [lb.name for lb in robot.limbs]))


def body_of_run(conditions: Conditions) -> Conditions:
    """Of a run's conditions, only those that shape the body (``BODY_CONDITIONS``): the body
    the run's plant infers its friction mechanisms on."""
    return Conditions({k: v for k, v in conditions.values.items() if k in BODY_CONDITIONS},
                      {k: dict(v) for k, v in conditions.named.items() if k in BODY_CONDITIONS})


def kinematic_signs(robot: Any, mechanisms: Sequence[str], *, margin_deg: float = MARGIN_DEG,
                    rate_per_s: float = 1.0, dt_s: float = 0.005) -> np.ndarray:
    """Displacement per allowed transition (mm) with the coils' contractions moved directly
    at ``rate_per_s`` (no thermal model, no lag): the pattern ``mechanisms`` predict."""
    return kinematic_signs_all(robot, [mechanisms], margin_deg=margin_deg, rate_per_s=rate_per_s, dt_s=dt_s)[0]


def kinematic_signs_all(robot: Any, assignments: Sequence[Sequence[str]], *, margin_deg: float = MARGIN_DEG,
                        rate_per_s: float = 1.0, dt_s: float = 0.005, body: Conditions | None = None) -> list[np.ndarray]:
    """``kinematic_signs`` for several D1/D2 assignments at the cost of about one.

    The sweep's poses do not depend on the friction mechanisms (the drive and the state read
    the shape only), so the body is swept once, recording per pose the contact angles, the
    gap changes, the loads and the centre of mass's offset; each assignment then replays only
    the anchor/slip solve (``PhysicalPlant._move`` itself, on a plant of its own)."""
    names = [tuple(a) for a in assignments]
    body = body if body is not None else body_conditions(robot)
    plant = PhysicalPlant(robot, body, mechanisms=names[0])
    drive = IdealDrive(robot, plant, margin_deg)
    _, allowed = robot.transitions.dense()
    n = len(allowed)
    c = [0.0] * drive.n_act
    step = rate_per_s * dt_s
    poses: list[tuple[list[float], list[float], list[float]]] = []   # (ψ, Δgaps, loads) per pose
    com_off: list[float] = []                                          # after each pose

    def pose() -> None:
        gaps_old = plant._gaps
        plant.pose(c)
        poses.append((list(plant._psi), [g1 - g0 for g0, g1 in zip(gaps_old, plant._gaps)], list(plant._load)))
        com_off.append(plant._com_off)

    def go(target: int) -> bool:
        for _ in range(int(4.0 / dt_s)):
            cmd = drive.command(plant.psi_deg.tolist(), target)
            for j, x in enumerate(cmd):
                c[j] = min(1.0, max(0.0, c[j] + x * step))
            pose()
            if plant.true_state == target and all(x != 1 for x in cmd) and all(
                    x == 0 or c[j] == 0.0 for j, x in enumerate(cmd)):
                pose()  # a pause: the body comes to rest
                return True
        return False

    spans: list[tuple[int, int, int, int]] = []   # (a, b, poses before a→b, poses after it)
    for a in range(n):
        for b in range(n):
            if a == b or not allowed[a][b]:
                continue
            if not go(a):
                continue
            k0 = len(poses)
            if go(b):
                spans.append((a, b, k0, len(poses)))

    x0 = _replay(robot, names, poses, body)                        # (assignments, poses + 1)
    outs = [np.zeros((n, n)) for _ in names]
    for a, b, k0, k1 in spans:
        for m, out in enumerate(outs):
            out[a, b] = (x0[m, k1] + com_off[k1 - 1]) - (x0[m, k0] + com_off[k0 - 1])
    return outs


def _replay(robot: Any, names: Sequence[tuple[str, ...]],
            poses: Sequence[tuple[list[float], list[float], list[float]]], body: Conditions) -> np.ndarray:
    """The body's rigid translation x0 after each recorded pose, for every assignment: one
    plant per assignment takes each pose's contact angles and loads and runs its own
    anchor/slip solve (``PhysicalPlant._move``) on the pose's gap changes, so the numbers are
    the plant's by construction. Returns (assignments, len(poses) + 1). Sets the plant's own
    fields: one package."""
    plants = [PhysicalPlant(robot, body, mechanisms=name) for name in names]
    x0 = np.zeros((len(names), len(poses) + 1))
    for m, p in enumerate(plants):
        x0[m, 0] = p._x0
        for t, (psi, dgaps, load) in enumerate(poses):
            p._psi, p._load = psi, load
            p._move(dgaps)
            x0[m, t + 1] = p._x0
    return x0
