"""The simulated robot body (plant): SMA drive → temperature → contraction → ψ → friction state
→ centre-of-mass displacement (SPEC §5).

Chain per step, for a PWM duty held constant over the step:

1. each SMA coil: exact exponential step of the lumped thermal model, then the Liang–Rogers
   hysteretic austenite fraction α (``proleg.sim.sma``);
2. contraction_j = α_j × max_strain_j × stroke_j (stroke_j = 1 fresh, < 1 after stroke loss);
3. body bending, linear in the contractions: each end's target contact angle
   ψ°_i = ψ_rest_i + Σ_j G[i][j] · contraction_j / max_strain_j, i.e. G[i][j] is how far
   actuator j at full nominal contraction tilts end i. The coils overlap, so each coil moves
   "its" end most and the other end less: with the default G = [[60, 27], [27, 60]]° and
   ψ* = 20°, one coil alone crosses its own end's ψ* at α ≈ 0.33 and the far end's at
   α ≈ 0.74, so an R1 robot driven by its left coil only goes 00 → 10 → 11 and back
   11 → 10 → 00, as in the paper's loss-of-actuation experiment;
4. ψ_i follows ψ°_i with a first-order mechanical lag (τ_m = 30 ms, the soft body's
   response); dψ/dt is the lag's derivative, for the gyro model;
5. friction level of limb i, counted as the firmware's classifier counts it (psi.h) from the
   true ψ: up past ψ*_i,k + h_i/2, down below ψ*_i,k − h_i/2 (h_i the limb's
   ``hysteresis_deg``; 0: the critical angles reached). The matrix describes the firmware's
   state changes, so a held limb sagging past ψ* inside its band changes nothing, and a
   multi-level limb passing a level on its way to another books each level it passes
   (0 → 1, 1 → 2), as the firmware's measured state passes it. The debounce is not modelled;
6. robot state index (mixed radix, first limb most significant); when it changes, the change
   and any further change within ``simultaneous_s`` (30 ms) form one transition a → b, and
   displacement += T_true[a][b] · step_mm + N(0, noise_mm²). Where T_true forbids a → b but
   allows each change of the window in turn (two limbs crossing a few ms apart: 110 → 120 →
   220 under a one-level matrix), each is booked, as the firmware saw them. A transition that
   T_true forbids (NaN) but that physically happened earns 0 and is counted in
   ``unexpected_transitions``, unless the next one is forbidden too, T_true allows the two as one (a → b → c, a → c
   allowed) and every limb's level in b lies between a's and c's: that was a pass, the limbs
   of one step crossing apart (full strokes' rise and fall leads cross one limb first on
   purpose, up to 3.5 s before the others), booked as a → c when c is reached within
   ``PASS_S`` (5 s) of the first change.

Not modelled: the quasi-static friction alternative of SPEC §5 (rewards come only from the
ground-truth matrix), latent heat, the coil's stress dependence of the transformation
temperatures, non-uniform coil temperature.

Faults: ``kill_actuator(ch)`` (no heating on that channel), ``inject_drift(ch, rate, mode)``:
"power" — effective heating power × exp(−rate · on-time), on-time = ∫ duty dt since the
injection (a coil whose response weakens as it ages or whose contact resistance rises);
"temperature" — As, Af, Ms, Mf shift up by rate °C per second of on-time (functional
fatigue); "stroke" — the recoverable stroke × exp(−rate · on-time). ``step`` gives an
immediate part of the same effect, so a test need not age the coil for minutes.
"""

from __future__ import annotations

import math
import random
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..errors import SimError
from ..names import counted
from ..states import limb_levels, place_values
from .plant_params import (  # noqa: F401 (re-exported: the plant's parameters live beside it)
    CROSS_GAIN_DEG,
    DIRECT_GAIN_DEG,
    LimbParams,
    PlanarMotion,
    PlantParams,
    planar_motion_from_robot,
    plant_params_from_robot,
    true_rewards_from_robot,
)
from .sma import Hysteresis, checked_drift, drifted

#: The longest pass (a -> b -> c booked as a -> c): full strokes' leads cross first and the
#: others follow within CTL_SAG_WAIT_MS + CTL_CLIMB_MAX_MS (3.5 s, core/ctl.h); a state held
#: longer happened.
PASS_S = 5.0

@dataclass(frozen=True)
class Transition:
    t_s: float          # time of the first limb change of this transition
    src: int
    dst: int
    reward_mm: float
    #: when reward_mm was added to displacement_mm: simultaneous_s after t_s (a pass: after
    #: its last leg's first change, up to PASS_S later); a pose read before it has not moved yet
    t_booked_s: float | None = None

    def __iter__(self):  # unpacks as (t, from, to, reward_mm)
        return iter((self.t_s, self.src, self.dst, self.reward_mm))


#: The planar pose's noise comes from its own generator (seed mixed with this), so a plant
#: without planar statistics draws exactly the numbers it always drew.
_POSE_SEED = 0x5E2


class Plant:
    """The simulated robot body. ``step(dt_s, duties)`` advances it; read the rest as properties.

    ``planar`` (optional): the robot file's planar statistics; then each transition also moves
    a planar pose (x, y in mm, θ in degrees, start frame) by its body-frame (Δx, Δy, Δθ) —
    Δx the true reward as for ``displacement_mm``, Δy and Δθ the means — each with Gaussian
    noise of the file's variance (seeded), composed in SE(2): ``pose``, ``poses``. Δx's
    variance noise is then in ``displacement_mm`` too. Without ``planar``, ``pose`` is None and
    nothing else changes.

    ``true_rewards``: n×n matrix (n = number of robot states), row = from, column = to, in the
    robot file's units (scaled by ``params.step_mm``), NaN = forbidden. None → all zero.
    ``duties``: one PWM duty in [0, 1] per board channel (index = actuator channel).
    """

    def __init__(
        self,
        params: PlantParams | None = None,
        true_rewards: np.ndarray | None = None,
        levels: Sequence[int] | None = None,
        seed: int = 0,
        planar: PlanarMotion | None = None,
    ) -> None:
        params = params or PlantParams()
        msg = params.check()
        if msg:
            raise SimError(f"plant parameters: {msg}")
        if levels is None:
            levels = params.levels
        levels = tuple(int(k) for k in levels)
        if levels != params.levels:
            raise SimError(f"levels {levels} do not match the limbs' critical angles (levels {params.levels})")
        self.params = params
        self.levels = levels
        n = math.prod(levels)
        if true_rewards is None:
            true_rewards = np.zeros((n, n))
        tr = np.asarray(true_rewards, dtype=np.float64)
        if tr.shape != (n, n):
            raise SimError(f"true_rewards is {tr.shape}, expected ({n}, {n}) for levels {levels}")
        # reward in mm per (from, to), None where forbidden
        self._reward = [[None if math.isnan(x) else float(x) * params.step_mm for x in row] for row in tr.tolist()]
        self._rng = random.Random(seed)
        self._noise = float(params.noise_mm)
        self._window = float(params.simultaneous_s)

        acts = params.actuators
        self._na = len(acts)
        self._nl = len(params.limbs)
        self._channel = [a.channel for a in acts]
        self._n_channels = max(self._channel) + 1
        self._power = [a.full_power_w for a in acts]          # W at duty 1
        self._hA = [a.conductance_w_per_k for a in acts]
        self._tau = [a.tau_s for a in acts]
        self._strain = [a.max_strain for a in acts]
        self._amb = float(params.ambient_c)
        self._temp = [self._amb] * self._na
        self._peak = [self._amb] * self._na  # each coil's hottest since the plant was made
        self._hyst = [Hysteresis(a.as_c, a.af_c, a.ms_c, a.mf_c, self._amb) for a in acts]
        self._alive = [True] * self._na
        self._pfactor = [1.0] * self._na                      # heating power factor (drift)
        self._stroke = [1.0] * self._na                       # recoverable stroke factor (drift)
        self._drift: list[tuple[str, float, float] | None] = [None] * self._na  # (mode, rate, step)
        self._ontime = [0.0] * self._na                       # ∫ duty dt since drift injection
        self._ontime_total = [0.0] * self._na

        self._g = params.coupling()
        self._rest = [float(limb.psi_rest_deg) for limb in params.limbs]
        self._thresholds = [tuple(float(p) for p in limb.psi_star_deg) for limb in params.limbs]
        self._half_band = [float(limb.hysteresis_deg) / 2.0 for limb in params.limbs]
        self._limb_level = [0] * self._nl  # each limb's level with its bands' hysteresis (_classify)
        self._mult = place_values(levels)
        self._mtau = float(params.mech_tau_s)
        self._psi = self._targets()
        self._dpsi = [0.0] * self._nl
        self._t = 0.0
        self._dt_cache = (-1.0, [], 0.0)
        self._state = self._classify()
        self._committed = self._state
        self._pending_since: float | None = None
        self._path: list[int] = []  # the states seen since _pending_since, from _committed on
        self._displacement = 0.0
        self._transitions: list[Transition] = []
        self._unexpected = 0
        self._planar = None
        self._poses: list[tuple[float, float, float, float]] = []
        if planar is not None:
            fields = {k: np.asarray(getattr(planar, k), dtype=np.float64) for k in
                      ("dy", "dtheta_deg", "var_dx", "var_dy", "var_dtheta_deg")}
            bad = [k for k, v in fields.items() if v.shape != (n, n) or not np.all(np.isfinite(v))]
            if bad or min(float(fields[k].min()) for k in ("var_dx", "var_dy", "var_dtheta_deg")) < 0:
                raise SimError(f"planar statistics: {bad[0] if bad else 'a variance'} must be a finite ({n}, {n}) "
                               "matrix (variances >= 0)")
            self._planar = {k: v.tolist() for k, v in fields.items()}
            self._pose_rng = random.Random(seed * 1_000_003 + _POSE_SEED)
            self._poses.append((0.0, 0.0, 0.0, 0.0))

    # -- stepping -----------------------------------------------------------------------------
    def _targets(self) -> list[float]:
        contraction = [h.alpha * s for h, s in zip(self._hyst, self._stroke)]
        return [r + sum(g * c for g, c in zip(row, contraction)) for r, row in zip(self._rest, self._g)]

    def _classify(self) -> int:
        """The state index of ψ now, each limb's level counted as the firmware's classifier
        counts it (psi.h): up past a threshold at ψ* + h/2, down below ψ* − h/2, from the level
        it had (the first call: the upper edges ψ has reached). Without bands (h = 0), the
        thresholds ψ* reached (``proleg.states.classify``)."""
        idx = 0
        for i, (p, ths, half, m) in enumerate(zip(self._psi, self._thresholds, self._half_band, self._mult)):
            lvl = self._limb_level[i]
            while lvl < len(ths) and p >= ths[lvl] + half:
                lvl += 1
            while lvl > 0 and p < ths[lvl - 1] - half:
                lvl -= 1
            self._limb_level[i] = lvl
            idx += lvl * m
        return idx

    def step(self, dt_s: float, duties: Sequence[float]) -> None:
        """Advance by ``dt_s`` seconds with each channel's duty held constant."""
        if dt_s != self._dt_cache[0]:
            if not dt_s > 0:
                raise SimError(f"step: dt_s must be > 0, got {dt_s!r}")
            self._dt_cache = (dt_s, [math.exp(-dt_s / tau) for tau in self._tau], math.exp(-dt_s / self._mtau))
        _, decay, mdecay = self._dt_cache
        if len(duties) < self._n_channels:
            raise SimError(f"step: {counted(len(duties), 'duty')} given, the plant drives channels 0..{self._n_channels - 1}")
        temp = self._temp
        amb = self._amb
        contraction = []
        for j in range(self._na):
            d = duties[self._channel[j]]
            if not 0.0 <= d <= 1.0:
                raise SimError(f"step: duty {d!r} on channel {self._channel[j]} is outside 0..1")
            if not self._alive[j]:
                d = 0.0
            drift = self._drift[j]
            if drift is not None and d > 0.0:
                self._apply_drift(j, d * dt_s)
            if d > 0.0:
                self._ontime_total[j] += d * dt_s
            t_eq = amb + d * self._power[j] * self._pfactor[j] / self._hA[j]
            t1 = t_eq + (temp[j] - t_eq) * decay[j]
            temp[j] = t1
            if t1 > self._peak[j]:
                self._peak[j] = t1
            contraction.append(self._hyst[j].update(t1) * self._stroke[j])
        psi = self._psi
        dpsi = self._dpsi
        inv_tau = 1.0 / self._mtau
        for i in range(self._nl):
            target = self._rest[i]
            for g, c in zip(self._g[i], contraction):
                target += g * c
            p = target + (psi[i] - target) * mdecay
            psi[i] = p
            dpsi[i] = (target - p) * inv_tau
        self._t += dt_s
        # friction state and transitions
        state = self._classify()
        if state != self._state:
            self._state = state
            if self._pending_since is None:
                self._pending_since = self._t
                self._path = [self._committed]
            self._path.append(state)
        if self._pending_since is not None and self._t - self._pending_since >= self._window - 1e-12:
            self._commit()

    def _commit(self) -> None:
        a, b = self._committed, self._state
        t0 = self._pending_since
        self._pending_since = None
        path, self._path = self._path, []
        if a == b:
            return  # changed and changed back within the window: no transition
        if self._reward[a][b] is None and len(path) > 2 and all(
                self._reward[x][y] is not None for x, y in zip(path, path[1:])):
            # changes the window joins into one the matrix forbids, each of them allowed (two
            # limbs crossing a few ms apart, 110 -> 120 -> 220): the firmware saw each, in turn
            for x, y in zip(path, path[1:]):
                self._record(t0, x, y, self._reward[x][y])
            return
        last = self._transitions[-1] if self._transitions else None
        if (self._reward[a][b] is None and last is not None and last.dst == a and self._reward[last.src][a] is None
                and last.src != b and self._reward[last.src][b] is not None and self._between(last.src, a, b)
                and self._t - last.t_s <= PASS_S):
            # a pass: both legs forbidden, the whole allowed, every limb on its way (a staggered
            # step): one transition
            self._transitions.pop()
            self._unexpected -= 1
            self._committed = last.src
            self._record(last.t_s, last.src, b, self._reward[last.src][b])
            return
        self._record(t0, a, b, self._reward[a][b])

    def _between(self, a: int, via: int, c: int) -> bool:
        """Every limb's level in ``via`` lies between its levels in ``a`` and ``c``: the limbs of
        a → c crossing apart, none past where the step takes it (not a proleg lifted past its
        second edge and back: that is what the step did on this body, as it happened)."""
        la, lv, lc = (limb_levels(x, self.levels) for x in (a, via, c))
        return all(min(x, z) <= y <= max(x, z) for x, y, z in zip(la, lv, lc))

    def _record(self, t0: float, a: int, b: int, r: float | None) -> None:
        """Transition a → b from ``t0``: ``r`` mm (None: one T_true forbids, 0 mm, unexpected)."""
        if r is None:
            self._unexpected += 1
            r = 0.0
        elif self._noise > 0.0:
            r += self._rng.gauss(0.0, self._noise)
        if self._planar is not None and self._reward[a][b] is not None:
            r = self._move_pose(a, b, r)
        self._committed = b
        self._displacement += r
        self._transitions.append(Transition(t0, a, b, r, self._t))

    def _move_pose(self, a: int, b: int, dx: float) -> float:
        """Compose one transition's noisy body-frame step into the pose; returns the Δx used."""
        p, rng, k = self._planar, self._pose_rng, self.params.step_mm
        assert p is not None
        dx += rng.gauss(0.0, math.sqrt(p["var_dx"][a][b]) * k) if p["var_dx"][a][b] > 0 else 0.0
        dy = p["dy"][a][b] * k + (rng.gauss(0.0, math.sqrt(p["var_dy"][a][b]) * k) if p["var_dy"][a][b] > 0 else 0.0)
        dth = p["dtheta_deg"][a][b] + (
            rng.gauss(0.0, math.sqrt(p["var_dtheta_deg"][a][b])) if p["var_dtheta_deg"][a][b] > 0 else 0.0)
        _, x, y, th = self._poses[-1]
        c, s = math.cos(math.radians(th)), math.sin(math.radians(th))
        self._poses.append((self._t, x + c * dx - s * dy, y + s * dx + c * dy, th + dth))
        return dx

    def _apply_drift(self, j: int, on: float) -> None:
        mode = self._drift[j][0]
        self._ontime[j] += on
        now = drifted(self._drift[j], self._ontime[j])
        if mode == "power":
            self._pfactor[j] = now
        elif mode == "stroke":
            self._stroke[j] = now
        else:  # temperature
            self._hyst[j].shift_c = now

    # -- faults -------------------------------------------------------------------------------
    def _actuator_of(self, channel: int) -> int:
        try:
            return self._channel.index(channel)
        except ValueError:
            raise SimError(f"no actuator on channel {channel} (channels: {self._channel})") from None

    def kill_actuator(self, channel: int) -> None:
        """The coil on ``channel`` no longer heats (broken wire, dead MOSFET)."""
        self._alive[self._actuator_of(channel)] = False

    def inject_drift(self, channel: int, rate: float, mode: str = "power", step: float = 0.0) -> None:
        """From now on the coil on ``channel`` drifts (see the module doc for the modes).

        ``rate``: per second of on-time (∫ duty dt): 1/s for "power" and "stroke", °C/s for
        "temperature". ``step``: an immediate part, a fraction in [0, 1) for "power"/"stroke"
        (0.3 → 30 % weaker at once), °C for "temperature".
        """
        j = self._actuator_of(channel)
        self._drift[j] = checked_drift(mode, rate, step)
        self._ontime[j] = 0.0
        self._apply_drift(j, 0.0)

    # -- observation --------------------------------------------------------------------------
    @property
    def time_s(self) -> float:
        return self._t

    @property
    def psi_deg(self) -> np.ndarray:
        return np.array(self._psi)

    @property
    def dpsi_dps(self) -> np.ndarray:
        return np.array(self._dpsi)

    def limb_truth(self, i: int) -> tuple[float, float]:
        """(ψ_i in degrees, dψ_i/dt in °/s) as plain floats (cheap; for the IMU model)."""
        return self._psi[i], self._dpsi[i]

    @property
    def temperature_c(self) -> np.ndarray:
        return np.array(self._temp)

    def reset_peak(self) -> None:
        """Start each coil's hottest afresh from its temperature now (a run measured from here)."""
        self._peak[:] = self._temp

    @property
    def peak_temperature_c(self) -> list[float]:
        """Each coil's hottest (°C, coil order) since the plant was made or ``reset_peak``."""
        return list(self._peak)

    @property
    def austenite(self) -> np.ndarray:
        return np.array([h.alpha for h in self._hyst])

    @property
    def contraction(self) -> np.ndarray:
        """Per actuator, strain relative to the installed length."""
        return np.array([h.alpha * s * e for h, s, e in zip(self._hyst, self._stroke, self._strain)])

    @property
    def power_factor(self) -> np.ndarray:
        return np.array([pf if alive else 0.0 for pf, alive in zip(self._pfactor, self._alive)])

    @property
    def on_time_s(self) -> np.ndarray:
        """Per actuator, ∫ duty dt since the start."""
        return np.array(self._ontime_total)

    @property
    def true_state(self) -> int:
        """Current friction state index (from ψ now; transitions are committed after the window)."""
        return self._state

    @property
    def limb_levels(self) -> tuple[int, ...]:
        return limb_levels(self._state, self.levels)

    @property
    def displacement_mm(self) -> float:
        return self._displacement

    @property
    def pose(self) -> tuple[float, float, float] | None:
        """(x mm, y mm, θ degrees) in the start frame; None without planar statistics."""
        return None if self._planar is None else self._poses[-1][1:]

    @property
    def poses(self) -> list[tuple[float, float, float, float]]:
        """(t s, x mm, y mm, θ degrees) at the start and after each transition ([] when not planar)."""
        return list(self._poses)

    @property
    def transitions(self) -> list[Transition]:
        return list(self._transitions)

    @property
    def unexpected_transitions(self) -> int:
        return self._unexpected


def default_plant(true_rewards: np.ndarray | None = None, seed: int = 0, **overrides: Any) -> Plant:
    """A plant with the default R1-class parameters (``overrides`` replace PlantParams fields)."""
    return Plant(replace(PlantParams(), **overrides), true_rewards, seed=seed)
