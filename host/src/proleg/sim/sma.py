"""One shape-memory-alloy coil: lumped thermal model and Liang–Rogers hysteresis.

Thermal model (one node per coil)::

    C dT/dt = k · duty · V² / R − hA · (T − T_amb)

with k the effective power factor (1 fresh; drift lowers it). For a duty held constant over
a step dt the solution is exact: T(dt) = T_eq + (T − T_eq)·exp(−dt/τ), τ = C/hA, so any dt is
stable. Latent heat of transformation is ignored (it only stretches the transformation band
a little at these heating rates).

Phase model: austenite fraction α ∈ [0, 1] (0 = martensite, coil long; 1 = austenite, coil
contracted). Liang & Rogers (1990) cosine branches:

    heating (M→A), major branch  h(T) = ½ (1 − cos(π (T − As)/(Af − As)))   As ≤ T ≤ Af
    cooling (A→M), major branch  c(T) = ½ (1 − cos(π (T − Mf)/(Ms − Mf)))   Mf ≤ T ≤ Ms

(0 below / 1 above the band for h, 1 above Ms / 0 below Mf for c). Partial transformations:
when the temperature reverses, the fraction α_r at the reversal point is kept and the new
branch is scaled so that it starts at α_r and ends at the branch's end point (α=1 at Af on
heating, α=0 at Mf on cooling)::

    heating from (T_r, α_r):  h0 = max(h(T_r), α_r)
                              α = α_r + (1 − α_r) · max(0, h(T) − h0) / (1 − h0)
    cooling from (T_r, α_r):  c0 = min(c(T_r), α_r)
                              α = α_r · min(1, c(T) / c0)

When α_r lies on the "outside" of the major branch (the usual case: heated part-way, then
cooled above Ms), h0 = α_r and the branch reduces to α = max(α_r, h(T)), which is the
return-point memory of real SMA minor loops: the coil does not transform again until it is
back at the temperature where it stopped. When the branch has moved under the material
(e.g. transformation temperatures drifted), the scaled form keeps α continuous. α never
decreases while heating nor increases while cooling, and stays in [0, 1].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import SimError

_PI = math.pi


@dataclass(frozen=True)
class SmaParams:
    """One SMA coil and its drive. Defaults: a Toki BioMetal Helix BMX100-class coil.

    Numbers (BMX100: 0.1 mm NiTi wire wound into a 0.4 mm coil; the paper's robot threads
    two such coils through channels above the mid-line of an 80 mm body):

    * resistance: NiTi resistivity ≈ 0.8–1.0 µΩ·m → ≈ 110–130 Ω per metre of 0.1 mm wire;
      a ≈ 30 mm close-wound coil of 0.3 mm mean diameter holds ≈ 0.28 m of wire → ≈ 36 Ω.
    * supply 5 V (USB / boost from a LiPo); at 100 % duty 139 mA, 0.69 W.
    * heat capacity: 0.28 m of wire = 2.2 mm³ × 6.45 g/cm³ ≈ 14 mg × 0.32 J/(g·K)
      (Dynalloy's figure for NiTi) ≈ 4.6 mJ/K.
    * hA: bare thin wire in still air has h ≈ 100 W/(m²·K) over its 89 mm² surface; inside
      the body's channel roughly half of that → 4.6 mW/K, so τ = C/hA = 1.0 s (within the
      0.5–3 s of thin coils). Steady state at duty 0.6: T_amb + 90 K ≈ 115 °C.
    * transformation temperatures: BioMetal's ≈ 70 °C class alloy has, for a uniformly hot
      wire, As ≈ 68 / Af ≈ 78 °C on heating and Ms ≈ 52 / Mf ≈ 42 °C on cooling. A coil
      threaded through the body is not uniformly hot (its crimped ends and the parts touching
      the body lag), so the lumped model uses the same midpoints (73 °C heating, 47 °C
      cooling) with a band widened to 18 K: As 64 / Af 82, Ms 56 / Mf 38 °C. The narrow
      10 K band makes ψ sweep 60° in ≈ 0.2 s, faster than a ψ-feedback loop with a 30 ms
      body lag and a few ms of debounce can hold a state.
    * max_strain: contraction of the coil at full transformation relative to its installed
      (pre-stretched) length. Helix coils give large strokes; 0.3 is a modest working value.
      ψ is computed from the fraction of this nominal stroke (see ``PlantParams``), so the
      number only scales the reported contraction and the stroke-loss drift.
    """

    name: str = "sma"
    channel: int = 0
    resistance_ohm: float = 36.0
    supply_v: float = 5.0
    heat_capacity_j_per_k: float = 4.6e-3
    conductance_w_per_k: float = 4.6e-3
    as_c: float = 64.0
    af_c: float = 82.0
    ms_c: float = 56.0
    mf_c: float = 38.0
    max_strain: float = 0.3

    @property
    def tau_s(self) -> float:
        return self.heat_capacity_j_per_k / self.conductance_w_per_k

    @property
    def full_power_w(self) -> float:
        return self.supply_v * self.supply_v / self.resistance_ohm

    def check(self) -> str | None:
        """What is wrong with these numbers, or None."""
        for field in ("resistance_ohm", "supply_v", "heat_capacity_j_per_k", "conductance_w_per_k", "max_strain"):
            v = getattr(self, field)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                return f"{field} must be a positive number, got {v!r}"
        if not self.mf_c < self.ms_c:
            return f"mf_c ({self.mf_c}) must be below ms_c ({self.ms_c})"
        if not self.as_c < self.af_c:
            return f"as_c ({self.as_c}) must be below af_c ({self.af_c})"
        if not self.ms_c <= self.af_c:
            return f"ms_c ({self.ms_c}) must not exceed af_c ({self.af_c})"
        if not self.mf_c <= self.as_c:
            return f"mf_c ({self.mf_c}) must not exceed as_c ({self.as_c})"
        return None


def heating_branch(t: float, as_c: float, af_c: float) -> float:
    """Austenite fraction on the major heating branch at temperature ``t``."""
    if t <= as_c:
        return 0.0
    if t >= af_c:
        return 1.0
    return 0.5 - 0.5 * math.cos(_PI * (t - as_c) / (af_c - as_c))


def cooling_branch(t: float, ms_c: float, mf_c: float) -> float:
    """Austenite fraction on the major cooling branch at temperature ``t``."""
    if t >= ms_c:
        return 1.0
    if t <= mf_c:
        return 0.0
    return 0.5 - 0.5 * math.cos(_PI * (t - mf_c) / (ms_c - mf_c))


class Hysteresis:
    """Austenite fraction of one coil as its temperature moves (reversal-point bookkeeping).

    ``update(t)`` moves the coil to temperature ``t`` and returns the new fraction. The
    transformation temperatures may be changed between updates (``shift_c``), as the
    temperature-drift fault does.
    """

    __slots__ = ("as_c", "af_c", "ms_c", "mf_c", "shift_c", "alpha", "temp", "direction", "alpha_r", "anchor")

    def __init__(self, as_c: float, af_c: float, ms_c: float, mf_c: float, temp: float, alpha: float = 0.0):
        self.as_c, self.af_c, self.ms_c, self.mf_c = as_c, af_c, ms_c, mf_c
        self.shift_c = 0.0
        self.alpha = alpha
        self.temp = temp
        self.direction = 0      # +1 heating, -1 cooling, 0 not yet moved
        self.alpha_r = alpha    # fraction at the last reversal
        self.anchor = 0.0       # h0 (heating) or c0 (cooling) of the current branch

    def update(self, t: float) -> float:
        t0 = self.temp
        self.temp = t
        if t > t0:
            s = self.shift_c
            if self.direction != 1:
                self.direction = 1
                self.alpha_r = a_r = self.alpha
                self.anchor = max(heating_branch(t0, self.as_c + s, self.af_c + s), a_r)
            a_r = self.alpha_r
            h0 = self.anchor
            h = heating_branch(t, self.as_c + s, self.af_c + s)
            if h0 < 1.0:
                a = a_r + (1.0 - a_r) * (h - h0) / (1.0 - h0) if h > h0 else a_r
            else:
                a = h if h > a_r else a_r
            if a > self.alpha:
                self.alpha = a if a < 1.0 else 1.0
        elif t < t0:
            s = self.shift_c
            if self.direction != -1:
                self.direction = -1
                self.alpha_r = a_r = self.alpha
                self.anchor = min(cooling_branch(t0, self.ms_c + s, self.mf_c + s), a_r)
            a_r = self.alpha_r
            c0 = self.anchor
            c = cooling_branch(t, self.ms_c + s, self.mf_c + s)
            if c0 > 0.0:
                a = a_r * c / c0 if c < c0 else a_r
            else:
                a = c if c < a_r else a_r
            if a < self.alpha:
                self.alpha = a if a > 0.0 else 0.0
        return self.alpha


#: How a coil drifts with its on-time (∫ duty dt), as both plants' ``inject_drift`` takes it:
#: its heating ("power") or its stroke fades, or its transformation temperatures rise.
DRIFT_MODES = ("power", "temperature", "stroke")


def checked_drift(mode: str, rate: float, step: float) -> tuple[str, float, float]:
    """A drift's ``(mode, rate, step)``, else a SimError saying which is wrong: ``rate`` per
    second of on-time (1/s for "power" and "stroke", °C/s for "temperature"), ≥ 0; ``step`` an
    immediate part, a fraction in [0, 1) for "power" and "stroke", °C for "temperature"."""
    if mode not in DRIFT_MODES:
        raise SimError(f"inject_drift: mode must be 'power', 'temperature' or 'stroke', got {mode!r}")
    if not (math.isfinite(rate) and rate >= 0):
        raise SimError(f"inject_drift: rate must be ≥ 0, got {rate!r}")
    if mode != "temperature" and not 0.0 <= step < 1.0:
        raise SimError(f"inject_drift: step must be in [0, 1) for mode {mode!r}, got {step!r}")
    if not math.isfinite(step):  # a NaN shift made every later ψ NaN, silently
        raise SimError(f"inject_drift: step must be a finite number of °C for mode 'temperature', got {step!r}")
    return mode, float(rate), float(step)


def drifted(drift: tuple[str, float, float], on_s: float) -> float:
    """What ``drift`` (``checked_drift``) has made of its coil after ``on_s`` of on-time: for
    "power" and "stroke" the factor left, (1 − step)·exp(−rate·on_s); for "temperature" the
    shift in °C, step + rate·on_s."""
    mode, rate, step = drift
    x = on_s * rate
    return step + x if mode == "temperature" else (1.0 - step) * math.exp(-x)
