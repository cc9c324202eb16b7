"""The physical plant's SMA coils: duty in, contraction out (steps 1–3 of ``plant``).

``Coils(params, conditions, actuators, …)`` holds every coil's electrical, thermal and
material state; ``step(dt_s, duties)`` advances them with each channel's duty held constant
and says whether a contraction moved. Per step: the supply's voltage at the coils (each
coil's V_s·√power, sagged behind R_source by its own on-phase current and the others' mean),
each coil's thermal node (``thermal``) and Liang–Rogers hysteresis (``proleg.sim.sma``) with latent heat, the body node they all
warm, fatigue (stroke loss, transformation-temperature shift) with transformation cycles,
injected drift, and the contraction ``c[j]`` = α_j × stroke_j through a first-order
mechanical lag (``PhysicalParams.mech_tau_s``). Nothing here knows the body's shape or its
contacts: ``PhysicalPlant`` turns ``c`` into motion.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

from ...errors import SimError
from ...names import counted
from ...physics.params import PhysicalParams, coil_geometries
from ..sma import Hysteresis, checked_drift, drifted, heating_branch
from .conditions import Conditions


class Coils:
    """The robot's coils in actuator order; ``channel[j]`` is coil j's PWM channel. Lists
    are per coil and updated in place (``temp`` may be held and read after each step)."""

    def __init__(self, p: PhysicalParams, cond: Conditions, acts: Sequence[Any], anames: Sequence[str],
                 by_limb: Sequence[int], lnames: Sequence[str], robot: Any = None) -> None:
        self.physics = p
        na = len(acts)
        self._na = na
        self.amb = cond.get("ambient_c")
        mism = cond.get("coil_mismatch")
        conv = cond.get("convection")
        self.R, self.C, self.hA, self.G, self.lat = [], [], [], [], []
        geos = coil_geometries(p, robot, na)  # each coil's wire and alloy
        for j in range(na):
            scale = 1.0 + (mism if j == 0 else -mism if j == na - 1 and na > 1 else 0.0)
            g = geos[j]
            self.R.append(g.resistance_ohm * scale)
            self.C.append(g.heat_capacity_j_k * scale)
            self.lat.append(g.latent_j * scale)
            self.hA.append(g.convection_w_k(80.0, self.amb, conv) * scale)
            self.G.append(g.coil_to_body_w_k)
        # the body node is the robot's mass: all that mass_g changes (every force scales with it)
        self.Cb = dataclasses.replace(p.body_thermal, mass_kg=cond.get("mass_g") * 1e-3).heat_capacity_j_k()
        self.hAb = p.body_thermal.convection_w_k(conv)
        # each coil's own supply (a robot file's supply_v list), all behind one source resistance
        self.supply = [cond.for_index("supply_v", j, anames, by_limb, lnames) * math.sqrt(cond.get("power"))
                       for j in range(na)]
        self.rsrc = cond.get("supply_ohm")
        self.pscale = [cond.for_index("power_scale", j, anames, by_limb, lnames) for j in range(na)]
        self.channel = [a.channel for a in acts]
        self.n_channels = max(self.channel) + 1
        self.temp = [self.amb] * na
        self.peak = [self.amb] * na  # each coil's hottest since the plant was made
        self.tbody = self.amb
        self.hyst = [Hysteresis(g.as_c, g.af_c, g.ms_c, g.mf_c, self.amb) for g in geos]
        self.alive = [True] * na
        self.pfactor = [1.0] * na
        self.drift: list[tuple[str, float, float] | None] = [None] * na
        self.drift_on = [0.0] * na
        self.drift_shift = [0.0] * na
        self.drift_stroke = [1.0] * na
        self.ontime = [0.0] * na
        self.speedup = cond.get("fatigue_speedup")
        self.cycles = [cond.get("fatigue_cycles")] * na
        self.fat_stroke = [1.0] * na
        self.fat_shift = [0.0] * na
        self.fat_at = [0.0] * na
        for j in range(na):
            self._update_fatigue(j)
        # Each coil starts as the air left it, warmed from below As (where it was made and kept) to
        # ambient_c: past As part of the way through its transformation, past Af all of it. Every
        # coil used to start in martensite whatever the air: at 100 °C (Af 82 °C) the first touch of
        # heat transformed it at once, its latent heat took it 9 °C under the air it sat in, and the
        # body it bent moved R1 by 6 mm with no limb raised.
        for h in self.hyst:
            h.alpha = h.alpha_r = heating_branch(self.amb, h.as_c + h.shift_c, h.af_c + h.shift_c)
        # contraction, fraction of the fresh stroke (after the lag): at rest where the air holds it
        self.c = [h.alpha * s for h, s in zip(self.hyst, self.stroke())]
        self._dt_cache: tuple[float, list[float], float] = (-1.0, [], 0.0)

    def _update_fatigue(self, j: int) -> None:
        law = self.physics.fatigue
        n = self.cycles[j]
        self.fat_at[j] = n
        self.fat_stroke[j] = law.stroke(n)
        self.fat_shift[j] = law.shift(n)
        self.hyst[j].shift_c = self.fat_shift[j] + self.drift_shift[j]

    def step(self, dt_s: float, duties: Sequence[float]) -> tuple[bool, bool]:
        """Advance by ``dt_s`` seconds with each channel's duty held constant. Returns
        (changed: some contraction moved, moving: one is still on its way to its target)."""
        if dt_s != self._dt_cache[0]:
            if not dt_s > 0:
                raise SimError(f"step: dt_s must be > 0, got {dt_s!r}")
            k = [math.exp(-dt_s * (h + g) / c) for h, g, c in zip(self.hA, self.G, self.C)]
            self._dt_cache = (dt_s, k, math.exp(-dt_s / self.physics.mech_tau_s))
        _, decay, mdecay = self._dt_cache
        if len(duties) < self.n_channels:
            raise SimError(f"step: {counted(len(duties), 'duty')} given, the plant drives channels 0..{self.n_channels - 1}")
        na = self._na
        channel, alive = self.channel, self.alive
        ds = []
        for j in range(na):
            d = duties[channel[j]]
            if not 0.0 <= d <= 1.0:
                raise SimError(f"step: duty {d!r} on channel {channel[j]} is outside 0..1")
            ds.append(d if alive[j] else 0.0)
        vs = self.supply
        if self.rsrc > 0.0:
            # A coil heats only in its PWM on-phase, when it draws its full current through the
            # source, the others their mean (V² / (V + R_source·I), I that current at the supply's
            # V). All the coils' mean currents alone (d·V/R) sagged a coil at duty d < 1 too little:
            # R1 behind 50 Ω settled at 53.8 °C at duty 0.6 and 51.7 °C at duty 1, hotter at less
            # duty, and behind 20 Ω 18 °C above steady_temperature_c (the warnings' figure).
            rs, R = self.rsrc, self.R
            mean = sum(d * v / r for d, v, r in zip(ds, vs, R))
            vs = [v * v / (v + rs * (mean + (1.0 - d) * v / r)) for d, v, r in zip(ds, vs, R)]
        amb, tb = self.amb, self.tbody
        # the per-coil lists, looked up once a step (this runs every 2 ms of a measurement)
        R, pscale, pfactor, hA, G, C, lat = self.R, self.pscale, self.pfactor, self.hA, self.G, self.C, self.lat
        temp, peak, hyst, cs, cycles, fat_at = self.temp, self.peak, self.hyst, self.c, self.cycles, self.fat_at
        fat_stroke, drift_stroke, drift, ontime, speedup = (self.fat_stroke, self.drift_stroke, self.drift,
                                                             self.ontime, self.speedup)
        to_body = 0.0
        changed = False
        moving = False
        for j in range(na):
            d = ds[j]
            if d > 0.0:
                ontime[j] += d * dt_s
                if drift[j] is not None:
                    self._apply_drift(j, d * dt_s)
            v = vs[j]
            power = d * v * v / R[j] * pscale[j] * pfactor[j]
            h, g = hA[j], G[j]
            t_eq = (power + h * amb + g * tb) / (h + g)
            t = t_eq + (temp[j] - t_eq) * decay[j]
            hy = hyst[j]
            a0 = hy.alpha
            if (a0 == 0.0 and t < hy.as_c + hy.shift_c and hy.temp < hy.as_c + hy.shift_c) or (
                    a0 == 1.0 and t > hy.ms_c + hy.shift_c and hy.temp > hy.ms_c + hy.shift_c):
                a1 = a0   # outside the transformation band on a saturated branch: nothing moves
            else:
                a1 = hy.update(t)
            if a1 != a0:
                t -= lat[j] * (a1 - a0) / C[j]
                hy.temp = t
                cycles[j] += abs(a1 - a0) * 0.5 * speedup
                if abs(cycles[j] - fat_at[j]) > 0.01:   # fatigue e-folds over 10³+ cycles
                    self._update_fatigue(j)
            temp[j] = t
            if t > peak[j]:
                peak[j] = t
            to_body += g * (t - tb)
            target = a1 * fat_stroke[j] * drift_stroke[j]
            c = cs[j]
            if c != target:
                c = target + (c - target) * mdecay
                if abs(c - target) < 1e-7:
                    c = target
                else:
                    moving = True
                cs[j] = c
                changed = True
        self.tbody = tb + dt_s * (to_body - self.hAb * (tb - amb)) / self.Cb
        return changed, moving

    def _apply_drift(self, j: int, on: float) -> None:
        mode = self.drift[j][0]
        self.drift_on[j] += on
        now = drifted(self.drift[j], self.drift_on[j])
        if mode == "power":
            self.pfactor[j] = now
        elif mode == "stroke":
            self.drift_stroke[j] = now
        else:
            self.drift_shift[j] = now
            self.hyst[j].shift_c = self.fat_shift[j] + self.drift_shift[j]

    # -- faults ---------------------------------------------------------------------------------
    def of_channel(self, channel: int) -> int:
        """The coil driven by ``channel``; a SimError when none is."""
        try:
            return self.channel.index(channel)
        except ValueError:
            raise SimError(f"no actuator on channel {channel} (channels: {self.channel})") from None

    def kill(self, channel: int) -> None:
        """The coil on ``channel`` no longer heats (broken wire, dead MOSFET)."""
        self.alive[self.of_channel(channel)] = False

    def inject_drift(self, channel: int, rate: float, mode: str = "power", step: float = 0.0) -> None:
        """See ``PhysicalPlant.inject_drift``."""
        j = self.of_channel(channel)
        self.drift[j] = checked_drift(mode, rate, step)
        self.drift_on[j] = 0.0
        self._apply_drift(j, 0.0)

    # -- what the coils can reach -----------------------------------------------------------------
    def steady_temperature_c(self, duty: float) -> list[float]:
        """See ``PhysicalPlant.steady_coil_temperature_c``."""
        out = []
        for j in range(self._na):
            r, v = self.R[j], self.supply[j]
            vv = v * r / (r + self.rsrc) if self.rsrc > 0.0 else v
            power = duty * vv * vv / r * self.pscale[j] * self.pfactor[j] * (1.0 if self.alive[j] else 0.0)
            out.append(self.amb + power / (self.hA[j] + self.G[j]))
        return out

    def transformation_c(self) -> list[tuple[float, float]]:
        """Each coil's (As, Af) now, fatigue and drift shifts included."""
        return [(h.as_c + h.shift_c, h.af_c + h.shift_c) for h in self.hyst]

    def reverse_transformation_c(self) -> list[tuple[float, float]]:
        """Each coil's (Ms, Mf) now, fatigue and drift shifts included."""
        return [(h.ms_c + h.shift_c, h.mf_c + h.shift_c) for h in self.hyst]

    def stroke(self) -> list[float]:
        """Each coil's stroke now, a fraction of its fresh stroke (fatigue and drift)."""
        return [a * b for a, b in zip(self.fat_stroke, self.drift_stroke)]
