"""The physical plant: SMA coils → body shape → contact angles → anchor/slip mechanics.

Drop-in for ``proleg.sim.plant.Plant`` (``SimulatedRobot(robot, plant=PhysicalPlant(robot))``):
``step(dt_s, duties)``, ``limb_truth(i)``, ``displacement_mm``, ``transitions``,
``unexpected_transitions``, ``kill_actuator(ch)``, ``inject_drift(ch, rate, mode, step)``.
Unlike the table plant nothing here reads the robot's reward matrix to move: displacement is
the centre of mass of a body whose contacts stick or slide by force balance (``friction``).

Per step (duty held constant over the step), steps 1–3 in ``coils``:
1. supply: V at the coils = V_s·√power − R_source·ΣI (sag when both coils draw);
2. each coil: thermal node (``thermal``), Liang–Rogers hysteresis (``proleg.sim.sma``), latent
   heat, the body node; fatigue (stroke loss, transformation-temperature shift) accrues with
   transformation cycles;
3. contraction c_j = α_j × stroke_j, through a first-order mechanical lag (τ = 30 ms, the soft
   body's response); body shape → ψ per contact, gaps, loads, centre of mass (``body``);
4. contacts: friction coefficient from the mechanism's material at the true ψ (configured ψ*
   plus ``psi_star_shift_deg``), normal force from the loads, anchor/slip solve of the gap
   change (``friction``); the centre of mass moves with the contacts and the shape;
5. the robot's true friction state (for the transition log) from ψ and the true ψ*.

What the IMUs sense (``limb_truth``) is the end's tilt against gravity: ψ ± the ground incline
(the first limb's end faces up the slope, the last one down), plus mounting offset, bias and
noise. ``psi_deg`` is the true contact angle.
"""

from __future__ import annotations

import math
import random
from collections.abc import Sequence
from typing import Any

import numpy as np

from ...body import Shape, body_geometry, curl_key, curl_problem
from ...errors import SimError
from ...physics import materials as mat
from ...physics.params import ActView, LimbView, PhysicalParams, PlantView, Transition, robot_length_mm, robot_working_strain
from ...states import classify, limb_levels, place_values
from .coils import Coils
from .conditions import Conditions, coil_of_limb, conditions_from_section
from .friction import mu_at, solve_translation, solve_two
from .mechanism import limb_mechanisms

SHAPE_EPS = 3e-4   # contraction change (fraction of stroke) that triggers a shape update (≈ 0.013° of ψ)


class PhysicalPlant:
    """A robot body that moves by friction mechanics. ``robot``: a loaded ``proleg.robot.Robot``
    (limbs, ψ*, actuators, channels; its matrix only to infer D1/D2 when the file does not
    say, and to count transitions it forbids). ``conditions``: ``Conditions`` (see
    ``conditions.KEYS``); left out, the robot file's ``[plant]`` values (``sim.closed_loop.
    plant_conditions`` puts more on top of them). ``mechanisms``: per limb "D1"/"D2" or per-level material names,
    overriding the robot file."""

    def __init__(self, robot: Any, conditions: Conditions | None = None, *, seed: int = 0,
                 params: PhysicalParams | None = None, mechanisms: Sequence[Any] | None = None) -> None:
        self.robot = robot
        self.physics = p = params or PhysicalParams()
        limbs = list(robot.limbs)
        acts = list(robot.actuators)
        lnames = [lb.name for lb in limbs]
        anames = [a.name for a in acts]
        self.conditions = cond = (conditions if conditions is not None else
                                  conditions_from_section(getattr(robot, "plant", None), anames, lnames))
        by_limb = coil_of_limb(robot)  # a limb's name names its coil too
        cond.check_names(lnames, anames, by_limb)
        self.levels = tuple(len(lb.psi_star_deg) + 1 for lb in limbs)
        self.params = PlantView(tuple(ActView(a.name, a.channel) for a in acts),
                              tuple(LimbView(lb.name, tuple(lb.psi_star_deg)) for lb in limbs))
        self._rng = random.Random(seed)
        nl, na = len(limbs), len(acts)
        if nl < 2:
            raise SimError(f"{getattr(robot, 'path', robot.name)}: the physical plant needs two limbs at least (a "
                           f"body crawls on two contacts), and {robot.name} has one: `proleg sim --plant table` "
                           "simulates it from its matrix; `proleg check`, --measure-matrix and --measure-climb "
                           "run on the physical plant only")
        self._nl, self._na = nl, na

        # -- friction mechanisms (robot file, override, or inferred from the matrix) ----------
        from .measure import body_of_run

        mech = limb_mechanisms(robot, mechanisms, body_of_run(cond))  # inferred on this run's body
        self.mechanisms = mech.names
        self.mechanism_source = mech.source
        fr = cond.get("friction")
        pads = [[mat.material(m, p.materials) for m in mats] for mats in mech.materials]
        self._mu_s = [[pad.mu_static * fr for pad in limb] for limb in pads]
        self._mu_k = [[pad.mu_kinetic * fr for pad in limb] for limb in pads]
        self._true_th = [tuple(t + cond.for_index("psi_star_shift_deg", i, lnames) for t in lb.psi_star_deg)
                         for i, lb in enumerate(limbs)]
        self._band = p.friction_band_deg

        # -- geometry -------------------------------------------------------------------------
        overlap = [cond.for_index("overlap_mm", j, anames, by_limb, lnames) for j in range(na)]
        length = p.length_mm if p.length_mm is not None else robot_length_mm(robot, nl)
        strain = p.working_strain if p.working_strain is not None else robot_working_strain(robot)
        geo = body_geometry(by_limb, na, length, overlap, p.coil_offset_mm, strain)
        curl = curl_problem(geo, anames)
        if curl:
            given = getattr(getattr(robot, "plant", None), "given", ())
            raise SimError(f"{getattr(robot, 'path', robot.name)}: plant.{curl_key(given)}: {curl}")
        self.geometry = geo
        self._shape = Shape(geo)

        # -- the coils: supply, thermal nodes, hysteresis, fatigue, drift (``coils``) -----------
        self._coils = coils = Coils(p, cond, acts, anames, by_limb, lnames, robot)
        self._temp = coils.temp   # the coils' own list, updated in place (report.claim reads it)

        # -- sensors and world --------------------------------------------------------------
        inc = cond.get("incline_deg")
        self._incline = math.radians(inc)
        self._sense_off = []
        for i in range(nl):
            side = inc if i == 0 else -inc if i == nl - 1 else 0.0
            self._sense_off.append(side + cond.for_index("imu_offset_deg", i, lnames)
                                   + cond.for_index("imu_bias_deg", i, lnames))
        self._noise = cond.get("imu_noise_deg")
        self._weight_n = cond.get("mass_g") * 1e-3 * mat.GRAVITY_M_S2
        self._normal_n = self._weight_n * math.cos(self._incline)
        self._push = self._weight_n * math.sin(self._incline)   # downhill force along −x

        # -- state ----------------------------------------------------------------------------
        self._set_shape(self._shape.evaluate(coils.c))
        self._x0 = 0.0                                          # ground position of contact 0
        self._stuck = [True] * nl
        self._resting = True
        self._com0 = self._com
        self._dpsi = [0.0] * nl
        self._t = 0.0
        self._t_eval = 0.0
        self._c_eval = list(coils.c)
        self._mult = place_values(self.levels)
        self._state = self._classify()
        self._committed = self._state
        self._pending: float | None = None
        self._last_commit_x = 0.0
        self._transitions: list[Transition] = []
        self._unexpected = 0
        tt = getattr(robot, "transitions", None)
        self._allowed = tt.dense()[1] if tt is not None else None

    # -- helpers ------------------------------------------------------------------------------
    def _set_shape(self, vals: list[float]) -> None:
        nl = self._nl
        self._psi = vals[:nl]
        self._gaps = vals[nl:2 * nl - 1]
        self._load = vals[2 * nl - 1:3 * nl - 1]
        self._com_off = vals[3 * nl - 1]
        self._com = getattr(self, "_x0", 0.0) + self._com_off

    def _classify(self) -> int:
        return classify(self._psi, self._true_th, self._mult)

    # -- stepping -------------------------------------------------------------------------------
    def step(self, dt_s: float, duties: Sequence[float]) -> None:
        """Advance by ``dt_s`` seconds with each channel's duty held constant."""
        changed, moving = self._coils.step(dt_s, duties)
        self._t += dt_s
        if changed:
            # Re-evaluate the shape once the contractions have moved by SHAPE_EPS since the
            # last evaluation (≈ 0.013° of ψ, below the IMU's resolution): the anchor/slip solve is rate-independent, so
            # one step over the accumulated change is the same motion as many small ones.
            c, ce = self._coils.c, self._c_eval
            if any(abs(a - b) > SHAPE_EPS for a, b in zip(c, ce)) or not moving:
                self._c_eval = list(c)
                psi_old, gaps_old = self._psi, self._gaps
                self._set_shape(self._shape.evaluate(c))
                if self._nl == 2:
                    self._move2(self._gaps[0] - gaps_old[0])
                else:
                    self._move([g1 - g0 for g0, g1 in zip(gaps_old, self._gaps)])
                inv = 1.0 / (self._t - self._t_eval)
                self._t_eval = self._t
                self._dpsi = [(a - b) * inv for a, b in zip(self._psi, psi_old)]
                state = self._classify()
                if state != self._state:
                    self._state = state
                    if self._pending is None:
                        self._pending = self._t
        elif not self._resting:
            self._stuck = [True] * self._nl   # the body came to rest: every contact is static again
            self._resting = True
            self._dpsi = [0.0] * self._nl
            self._t_eval = self._t
        else:
            self._t_eval = self._t
        if self._pending is not None and self._t - self._pending >= self.physics.simultaneous_s - 1e-12:
            self._commit()

    def _move(self, dgaps: list[float]) -> None:
        """Anchor/slip: how the contacts move when the gaps change by ``dgaps``."""
        offsets = [0.0]
        for dg in dgaps:
            offsets.append(offsets[-1] + dg)
        caps = []
        band = self._band
        for i in range(self._nl):
            mus = self._mu_s[i] if self._stuck[i] else self._mu_k[i]
            caps.append(mu_at(self._psi[i], self._true_th[i], mus, band) * self._load[i] * self._normal_n)
        if all(abs(o) < 1e-12 for o in offsets):
            self._stuck = [True] * self._nl
            self._resting = True
            return
        self._resting = False
        delta = solve_translation(offsets, caps, self._push)
        self._x0 += delta
        self._stuck = [abs(delta + o) < 1e-9 for o in offsets]
        self._com = self._x0 + self._com_off

    def _move2(self, dg: float) -> None:
        """``_move`` for two contacts: offsets (0, dg), a closed-form weighted median."""
        if abs(dg) < 1e-12:
            self._stuck = [True, True]
            self._resting = True
            return
        self._resting = False
        psi, th, band, st = self._psi, self._true_th, self._band, self._stuck
        n = self._normal_n
        c0 = mu_at(psi[0], th[0], self._mu_s[0] if st[0] else self._mu_k[0], band) * self._load[0] * n
        c1 = mu_at(psi[1], th[1], self._mu_s[1] if st[1] else self._mu_k[1], band) * self._load[1] * n
        delta = solve_two(dg, c0, c1, self._push)
        self._x0 += delta
        self._stuck = [abs(delta) < 1e-9, abs(delta + dg) < 1e-9]
        self._com = self._x0 + self._com_off

    def _commit(self) -> None:
        a, b = self._committed, self._state
        t0 = self._pending
        self._pending = None
        if a == b:
            return
        x = self._com - self._com0
        r = x - self._last_commit_x
        self._last_commit_x = x
        self._committed = b
        if self._allowed is not None and not self._allowed[a][b]:
            self._unexpected += 1
        self._transitions.append(Transition(t0, a, b, r))

    # -- faults ---------------------------------------------------------------------------------
    def kill_actuator(self, channel: int) -> None:
        """The coil on ``channel`` no longer heats (broken wire, dead MOSFET)."""
        self._coils.kill(channel)

    def inject_drift(self, channel: int, rate: float, mode: str = "power", step: float = 0.0) -> None:
        """From now on the coil on ``channel`` drifts with its on-time (∫ duty dt): "power"
        (heating × exp(−rate·t_on)), "stroke" (stroke × exp(−rate·t_on)), "temperature"
        (transformation temperatures + rate °C per s of on-time); ``step`` an immediate part."""
        self._coils.inject_drift(channel, rate, mode, step)

    # -- what the coils can reach -----------------------------------------------------------------
    def steady_coil_temperature_c(self, duty: float) -> list[float]:
        """Each coil's steady temperature at ``duty`` held forever, the body at ambient (its own
        heating neglected), one coil drawing (no sag from the others): what the supply can do."""
        return self._coils.steady_temperature_c(duty)

    def settled_bend(self, duty: float, targets: Sequence[float]) -> list[tuple[float, float, float | None]]:
        """Per limb, its own coil heated at ``duty`` until it settles (``steady_coil_temperature_c``;
        from cold, up the major heating branch) with every other coil cold: (ψ° it bends the limb
        to there; ψ° at the coil's full stroke now, fatigue included; the duty at which it would
        settle bending the limb to ``targets[i]``°, ``math.inf`` where no duty heats it at all,
        None where even the full stroke falls short or the limb is there at rest). A coil that
        settles between As and Af contracts only part of its stroke (R1 at power 0.35: 67 °C,
        6 %, its limbs at 3.6° against their 21° edge)."""
        from ..sma import heating_branch

        temps = self._coils.steady_temperature_c(duty)
        trans = self._coils.transformation_c()
        strokes = self._coils.stroke()
        amb = self.conditions.get("ambient_c")
        out: list[tuple[float, float, float | None]] = []
        for i, j in enumerate(coil_of_limb(self.robot)):
            as_c, af_c = trans[j]

            def bend(c: float, i: int = i, j: int = j) -> float:
                cs = [0.0] * self._na
                cs[j] = c
                return float(self._shape.evaluate(cs)[i])

            target = targets[i]
            settled = bend(heating_branch(temps[j], as_c, af_c) * strokes[j])
            full = bend(strokes[j])
            need: float | None = None
            if full >= target > bend(0.0) and strokes[j] > 0.0:
                lo, hi = 0.0, strokes[j]   # the contraction that bends it to the target (ψ rises with it)
                for _ in range(40):
                    mid = 0.5 * (lo + hi)
                    lo, hi = (mid, hi) if bend(mid) < target else (lo, mid)
                frac = min(1.0, hi / strokes[j])
                t_need = as_c + (af_c - as_c) * math.acos(1.0 - 2.0 * frac) / math.pi
                per_duty = (temps[j] - amb) / duty if duty > 0 else 0.0   # °C above the air per unit duty
                need = (t_need - amb) / per_duty if per_duty > 0 else math.inf
            out.append((settled, full, need))
        return out

    def warm_rest(self) -> tuple[list[float], list[float]]:
        """Where the body comes to rest once every coil has been heated through its
        transformation and then switched off, its temperature settled at the air's
        (``ambient_c``): (each coil's contraction, a fraction of its fresh stroke; each limb's
        ψ°). Below the coils' Mf both are 0; above it a coil transforms back only partly
        (above Ms not at all) and keeps its limbs bent (the body's own warmth neglected)."""
        from ..sma import cooling_branch

        amb = self.conditions.get("ambient_c")
        coils = self._coils
        c = [cooling_branch(amb, ms, mf) * s
             for (ms, mf), s in zip(coils.reverse_transformation_c(), coils.stroke())]
        return c, [float(p) for p in self._shape.evaluate(c)[:self._nl]]

    def standing_grip(self) -> tuple[float, float]:
        """How steep a ground the contacts' static friction holds the body on, as the tangent of
        its grade: (at rest, where the plant starts; with every contact on its least grippy pad,
        e.g. R1's 11 on its hard pads), each the contacts' μ_s weighted by their loads at rest.
        Steeper, a real robot slides downhill; this quasi-static plant moves the body only while
        its shape changes, so it holds it where it stands (``climb.slope_warnings``)."""
        load, band = self._load, self._band
        rest = sum(w * mu_at(p, th, mus, band) for w, p, th, mus in zip(load, self._psi, self._true_th, self._mu_s))
        return rest, sum(w * min(mus) for w, mus in zip(load, self._mu_s))

    @property
    def alive(self) -> tuple[bool, ...]:
        """Per actuator: False once ``kill_actuator`` was called on it."""
        return tuple(self._coils.alive)

    def transformation_c(self) -> list[tuple[float, float]]:
        """Each coil's (As, Af) now, fatigue and drift shifts included."""
        return self._coils.transformation_c()

    # -- observation ----------------------------------------------------------------------------
    def limb_truth(self, i: int) -> tuple[float, float]:
        """(angle the limb's IMU senses in degrees, its rate in °/s)."""
        a = self._psi[i] + self._sense_off[i]
        if self._noise > 0.0:
            a += self._rng.gauss(0.0, self._noise)
        return a, self._dpsi[i]

    @property
    def time_s(self) -> float:
        return self._t

    @property
    def psi_deg(self) -> np.ndarray:
        """True contact angles."""
        return np.array(self._psi)

    @property
    def dpsi_dps(self) -> np.ndarray:
        return np.array(self._dpsi)

    @property
    def psi_now(self) -> tuple[float, ...]:
        """``psi_deg`` as a tuple of floats: for a drive that reads it every step (an array
        made three times a step was a tenth of ``measure_matrix``'s time)."""
        return tuple(self._psi)

    @property
    def dpsi_now(self) -> tuple[float, ...]:
        """``dpsi_dps`` as a tuple of floats."""
        return tuple(self._dpsi)

    @property
    def true_psi_star_deg(self) -> list[tuple[float, ...]]:
        return list(self._true_th)

    @property
    def temperature_c(self) -> np.ndarray:
        return np.array(self._temp)

    def reset_peak(self) -> None:
        """Start each coil's hottest afresh from its temperature now (a run measured from here)."""
        self._coils.peak[:] = self._coils.temp

    @property
    def peak_temperature_c(self) -> list[float]:
        """Each coil's hottest (°C, coil order) since the plant was made or ``reset_peak``."""
        return list(self._coils.peak)

    @property
    def body_temperature_c(self) -> float:
        return self._coils.tbody

    @property
    def austenite(self) -> np.ndarray:
        return np.array([h.alpha for h in self._coils.hyst])

    @property
    def contraction(self) -> np.ndarray:
        """Per coil, fraction of its fresh stroke (after the mechanical lag)."""
        return np.array(self._coils.c)

    @property
    def stroke(self) -> np.ndarray:
        return np.array(self._coils.stroke())

    @property
    def cycles(self) -> np.ndarray:
        return np.array(self._coils.cycles)

    @property
    def resistance_ohm(self) -> np.ndarray:
        return np.array(self._coils.R)

    @property
    def on_time_s(self) -> np.ndarray:
        return np.array(self._coils.ontime)

    @property
    def contact_x_mm(self) -> np.ndarray:
        xs = [self._x0]
        for g in self._gaps:
            xs.append(xs[-1] + g)
        return np.array(xs)

    def pose(self, contractions: Sequence[float]) -> None:
        """Set the coils' contractions directly (bypassing the thermal model) and let the body
        move by friction mechanics: for kinematic sweeps (``measure.kinematic_signs_all``, which
        ``mechanism`` infers the friction mechanisms from)."""
        self._coils.c[:] = [float(c) for c in contractions]
        self._c_eval = list(self._coils.c)
        gaps_old = self._gaps
        psi_old = self._psi
        self._set_shape(self._shape.evaluate(self._coils.c))
        self._move([g1 - g0 for g0, g1 in zip(gaps_old, self._gaps)])
        self._dpsi = [0.0 for _ in psi_old]
        self._state = self._classify()

    @property
    def stuck(self) -> tuple[bool, ...]:
        return tuple(self._stuck)

    @property
    def true_state(self) -> int:
        return self._state

    @property
    def limb_levels(self) -> tuple[int, ...]:
        return limb_levels(self._state, self.levels)

    @property
    def displacement_mm(self) -> float:
        """Centre of mass along the ground (+x = from the first limb towards the last)."""
        return float(self._com - self._com0)

    @property
    def transitions(self) -> list[Transition]:
        return list(self._transitions)

    @property
    def unexpected_transitions(self) -> int:
        return self._unexpected
