"""Quasi-static anchor/slip mechanics of a crawler on dry-friction contacts.

The body's gaps between neighbouring contacts are set by its shape (``body``). When they
change by Δg over a step, the contacts move by v_i = δ + o_i, with o_0 = 0, o_i = Σ_{k<i} Δg_k
and δ the one unknown rigid translation. Quasi-statically (no inertia: a 3 g body, mm/s
speeds), δ makes the forces balance: every sliding contact exerts its full friction
−μ_k N_i sign(v_i), every stuck contact any force within ±μ_s N_i, and together they balance
the weight's component along an inclined ground. This is the minimum over δ of the convex
dissipation Σ_i c_i |δ + o_i| + W δ (c_i = μ N_i; W = m g sin β), a weighted median; the
rate-independent crawler of Gidoni, Noselli & DeSimone (2014, 2016) and the anchor/slip
picture of Wagner & Lauga (2013) in its rigid-link limit. A contact that was stuck in the
previous step offers its static coefficient, a sliding one its kinetic coefficient
(stick-slip). When the friction of the two groups of contacts is exactly equal (e.g. two
identical ends), every δ between their breakpoints balances; the symmetric choice (the
middle) is taken. If the weight along the slope exceeds every contact's friction together,
the contacts slide as far as the shape change moves them, and no further: a body at rest does
not move, even on a ground steeper than its contacts hold (it would accelerate downhill, which no
quasi-static model describes; ``climb.slope_warnings`` says so when a run's ground is that steep).

The friction coefficient of a contact follows its material: the level of its mechanism at
the contact angle ψ (level k: ψ*_k ≤ ψ < ψ*_{k+1}), blended linearly over ``band_deg`` on the
soft material's side of each true critical angle (``mu_at``).
"""

from __future__ import annotations

from collections.abc import Sequence


def mu_at(psi: float, thresholds: Sequence[float], mus: Sequence[float], band: float) -> float:
    """Friction coefficient at contact angle ``psi`` for a mechanism with per-level ``mus``.

    A soft (sticky) pad grips with its contact area, which it builds up over ``band`` degrees
    once it touches: between two levels the coefficient changes linearly over the ``band``
    degrees on the stickier level's side of the critical angle (a soft pad at level 0 peels
    off over [ψ* − band, ψ*]; a soft tip at level 1 beds in over [ψ*, ψ* + band])."""
    k = 0
    n = len(thresholds)
    while k < n and psi >= thresholds[k]:
        k += 1
    mu = mus[k]
    if k > 0:  # this level is the stickier one: it beds in above the threshold
        th, lo = thresholds[k - 1], mus[k - 1]
        if mu > lo and psi < th + band:
            mu = lo + (mu - lo) * (psi - th) / band
    if k < n:
        th, hi = thresholds[k], mus[k + 1]
        if mu > hi and psi > th - band:
            mu = hi + (mu - hi) * (th - psi) / band
    return mu


def solve_translation(offsets: Sequence[float], caps: Sequence[float], push: float) -> float:
    """δ minimising Σ caps_i |δ + offsets_i| + push·δ (caps ≥ 0). Weighted median."""
    pts = sorted(zip((-o for o in offsets), caps))
    total = sum(caps)
    if push >= total:
        return pts[0][0]
    if -push >= total:
        return pts[-1][0]
    # slope of D left of every breakpoint: −total + push; it rises by 2·cap at each breakpoint
    slope = -total + push
    for idx, (p, c) in enumerate(pts):
        new = slope + 2.0 * c
        if new > 1e-12:
            return p
        if new >= -1e-12:  # flat from p to the next breakpoint: take the middle
            nxt = pts[idx + 1][0] if idx + 1 < len(pts) else p
            return (p + nxt) / 2.0
        slope = new
    return pts[-1][0]


def solve_two(dg: float, c0: float, c1: float, push: float) -> float:
    """``solve_translation((0, dg), (c0, c1), push)`` in closed form (two contacts, the hot path)."""
    lo, clo, hi = (-dg, c1, 0.0) if dg > 0 else (0.0, c0, -dg)
    total = c0 + c1
    if push >= total:
        return lo
    if -push >= total:
        return hi
    slope = -total + push + 2.0 * clo     # the dissipation's slope just right of the lower breakpoint
    if slope > 1e-12:
        return lo
    if slope >= -1e-12:
        return (lo + hi) / 2.0
    return hi
