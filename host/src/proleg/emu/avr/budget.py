"""The tick budget measured on the emulated MCU: how much of each control tick the
firmware's work takes (busy), how much of that the I2C bus was in use, how deep the
stack went, and how fast the emulation ran."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The budget every example robot must meet at its configured rate (issue 11, SPEC §3).
P99_LIMIT = 0.70
MAX_LIMIT = 0.90


@dataclass(frozen=True)
class TickBudget:
    tick_period_us: float  # configured
    ticks: int  # completed ticks measured
    busy_mean_us: float
    busy_p99_us: float
    busy_max_us: float
    period_mean_us: float  # measured, start to start (longer than configured when ticks overrun)
    overruns: int  # ticks whose work took longer than the configured period
    i2c_mean_us: float  # per tick, I2C bus owned (START..STOP) during the tick's work
    i2c_share: float  # of the busy time
    stack_peak_bytes: int  # RAMEND - lowest stack pointer
    stack_margin_bytes: int  # lowest stack pointer - end of static data (what is left)
    emulated_s: float
    wall_s: float
    cpu_s: float  # process CPU time (the wall time includes whatever else the machine runs)

    @property
    def p99_fraction(self) -> float:
        return self.busy_p99_us / self.tick_period_us

    @property
    def max_fraction(self) -> float:
        return self.busy_max_us / self.tick_period_us

    @property
    def emulation_speed(self) -> float:
        """Emulated seconds per wall-clock second."""
        return self.emulated_s / self.wall_s if self.wall_s > 0 else float("inf")

    @property
    def emulation_speed_cpu(self) -> float:
        """Emulated seconds per CPU second of this process."""
        return self.emulated_s / self.cpu_s if self.cpu_s > 0 else float("inf")

    def meets_target(self) -> bool:
        return self.p99_fraction <= P99_LIMIT and self.max_fraction <= MAX_LIMIT

    def as_dict(self) -> dict:
        return {
            "tick_period_us": round(self.tick_period_us, 3),
            "tick_busy_us": {
                "mean": round(self.busy_mean_us, 1),
                "p99": round(self.busy_p99_us, 1),
                "max": round(self.busy_max_us, 1),
            },
            "busy_p99_fraction": round(self.p99_fraction, 4),
            "busy_max_fraction": round(self.max_fraction, 4),
            "meets_target": self.meets_target(),
            "ticks": self.ticks,
            "period_mean_us": round(self.period_mean_us, 1),
            "overruns": self.overruns,
            "i2c_us": {"mean": round(self.i2c_mean_us, 1), "share_of_busy": round(self.i2c_share, 4)},
            "stack_peak_bytes": self.stack_peak_bytes,
            "stack_margin_bytes": self.stack_margin_bytes,
            "emulated_s": round(self.emulated_s, 3),
            "wall_s": round(self.wall_s, 3),
            "cpu_s": round(self.cpu_s, 3),
            "emulation_speed": round(self.emulation_speed, 3),
            "emulation_speed_cpu": round(self.emulation_speed_cpu, 3),
        }


def summarize(
    starts: np.ndarray,
    busy: np.ndarray,
    i2c: np.ndarray,
    *,
    freq_hz: int,
    tick_period_us: float,
    stack_peak_bytes: int,
    stack_margin_bytes: int,
    emulated_s: float,
    wall_s: float,
    cpu_s: float,
) -> TickBudget:
    """Summary of per-tick records (cycles) from the harness."""
    us = 1e6 / freq_hz
    b = busy.astype(np.float64) * us
    i = i2c.astype(np.float64) * us
    n = len(b)
    periods = np.diff(starts.astype(np.float64)) * us if n > 1 else np.array([tick_period_us])
    return TickBudget(
        tick_period_us=tick_period_us,
        ticks=n,
        busy_mean_us=float(b.mean()) if n else 0.0,
        busy_p99_us=float(np.percentile(b, 99)) if n else 0.0,
        busy_max_us=float(b.max()) if n else 0.0,
        period_mean_us=float(periods.mean()),
        overruns=int((b > tick_period_us).sum()),
        i2c_mean_us=float(i.mean()) if n else 0.0,
        i2c_share=float(i.sum() / b.sum()) if n and b.sum() > 0 else 0.0,
        stack_peak_bytes=stack_peak_bytes,
        stack_margin_bytes=stack_margin_bytes,
        emulated_s=emulated_s,
        wall_s=wall_s,
        cpu_s=cpu_s,
    )
