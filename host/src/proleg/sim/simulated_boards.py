"""Simulated boards by name: what ``proleg sim --board NAME`` and ``pytest hil_tests
--target NAME`` run a robot on.

=========  ==========================================================  ===============
name       what runs                                                    firmware board
=========  ==========================================================  ===============
host-sim   the generated C compiled for the host, stepped tick by tick  host-sim
avr-emu    the exact arduino-nano ``firmware.elf`` on simavr            arduino-nano
arm-emu    the exact bluepill ``firmware.elf`` on unicorn (STM32F103)   bluepill-f103
=========  ==========================================================  ===============

Every entry makes a ``proleg.sim.closed_loop.SimulatedRobot`` (the board in closed loop
with the robot's plant, the same fault injections); the emulated MCUs also measure the
control tick's busy time (``tick_budget``). Factories are imported only when asked for,
as python-can's interface registry does, so host-sim never loads an emulator.
"""

from __future__ import annotations

import importlib
import importlib.util
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import SimError

if TYPE_CHECKING:
    from ..robot import Robot
    from .closed_loop import SimulatedRobot


@dataclass(frozen=True)
class SimulatedBoard:
    name: str
    factory: str  # "module:callable", called as callable(robot, seed=seed) -> SimulatedRobot
    firmware_board: str  # boards/<firmware_board>.toml: what the firmware is built for and reports in INFO
    description: str
    emulated: bool  # an instruction-level MCU emulator (measures the tick budget)
    needs: str = ""  # what to install when something in ``requires`` is missing
    requires: tuple[str, ...] = ()  # commands on PATH, absolute file paths, "py:module" Python modules
    can_firmware_board: str = ""  # the firmware board whose host link is CAN ([link] transport = "can"); "": none

    def firmware_board_for(self, link: str) -> str:
        """The firmware board for a host link on ``link`` ("uart" or "can"); ``SimError`` if there is none."""
        if link == "uart":
            return self.firmware_board
        if link == "can" and self.can_firmware_board:
            return self.can_firmware_board
        raise SimError(f"simulated board {self.name} has no {link!r} host link (expected uart"
                       f"{' or can' if self.can_firmware_board else ''})")

    def missing(self) -> str | None:
        """What this board needs and this machine lacks, as one line; None if nothing."""
        absent = [r for r in self.requires if not _present(r)]
        if not absent:
            return None
        return f"board {self.name} needs {', '.join(r.removeprefix('py:') for r in absent)}: install {self.needs}"


def _present(requirement: str) -> bool:
    if requirement.startswith("py:"):
        return importlib.util.find_spec(requirement[3:]) is not None
    if requirement.startswith("/"):
        return Path(requirement).exists()
    return shutil.which(requirement) is not None


SIMULATED_BOARDS: dict[str, SimulatedBoard] = {
    b.name: b
    for b in (
        SimulatedBoard("host-sim", "proleg.sim.closed_loop:SimulatedRobot", "host-sim",
                       "the generated C compiled for the host, in virtual time", emulated=False,
                       can_firmware_board="host-sim-can"),
        SimulatedBoard("avr-emu", "proleg.emu.avr:AvrEmuRobot", "arduino-nano",
                       "the exact arduino-nano firmware.elf on simavr (ATmega328P, 16 MHz)", emulated=True,
                       needs="the Debian packages simavr, libsimavr-dev and gcc-avr (`make toolchains`)",
                       requires=("avr-gcc", "cc", "/usr/include/simavr/sim_avr.h")),
        SimulatedBoard("arm-emu", "proleg.emu.arm:ArmEmuRobot", "bluepill-f103",
                       "the exact bluepill firmware.elf on unicorn (STM32F103, 72 MHz)", emulated=True,
                       needs="the Python package unicorn (`make setup`) and gcc-arm-none-eabi (`make toolchains`)",
                       requires=("py:unicorn", "arm-none-eabi-gcc", "cc"), can_firmware_board="bluepill-can"),
    )
}


def simulated_board(name: str) -> SimulatedBoard:
    """The registry entry of ``name``; ``SimError`` naming the choices if there is none."""
    try:
        return SIMULATED_BOARDS[name]
    except KeyError:
        raise SimError(f"unknown simulated board {name!r} (expected one of: {', '.join(SIMULATED_BOARDS)})") from None


def simulated_robot(name: str, robot: Robot, *, seed: int = 1, **options: Any) -> SimulatedRobot:
    """``robot``'s firmware on the simulated board ``name``, in closed loop with its plant
    (the firmware is built, or taken from the build cache, first)."""
    entry = simulated_board(name)
    lacking = entry.missing()
    if lacking:
        raise SimError(lacking)
    module, _, attr = entry.factory.partition(":")
    factory: Any = getattr(importlib.import_module(module), attr)
    return factory(robot, seed=seed, **options)


def tick_budget(sim: SimulatedRobot) -> dict | None:
    """The busy time per control tick the emulated MCU measured since its last
    ``clear_ticks()`` (or reset): ``{"tick_period_us": P, "tick_busy_us": {"ticks", "mean",
    "p99", "max"}}`` in µs of emulated time (P a float on every board, ticks an int); None on a
    board that does not measure it."""
    measure = getattr(sim.board, "tick_budget", None)
    if measure is None:
        return None
    d = measure().as_dict()
    busy = d["tick_busy_us"]
    ticks = d.get("ticks", busy.get("ticks"))
    return {
        "tick_period_us": float(d["tick_period_us"]),
        "tick_busy_us": {"ticks": int(ticks), "mean": float(busy["mean"]), "p99": float(busy["p99"]),
                         "max": float(busy["max"])},
    }


def clear_ticks(sim: SimulatedRobot) -> None:
    """Start a new tick-budget window on an emulated MCU (nothing on other boards)."""
    clear = getattr(sim.board, "clear_ticks", None)
    if clear is not None:
        clear()
