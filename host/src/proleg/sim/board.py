"""The simulated-board interface, and its host-sim implementation ``SimBoard``.

``SimulatedBoardLike`` is the interface every simulated board offers (the host-sim build
here; emulated MCUs elsewhere); ``proleg.sim.closed_loop.SimulatedRobot`` drives any object
that has it. ``SimBoard`` is the ``host-sim`` build of the generated firmware, in-process: the firmware is the same C that runs on the microcontrollers, compiled against the
``hal/sim`` port into a shared library (see the host-sim ABI in docs/ARCHITECTURE.md).
``SimBoard`` loads it with ctypes and steps it tick by tick in virtual time. Each
instance loads its own copy of the library (copied to a unique temporary name), so
several boards, each with its own firmware globals, can run in one process.
"""

from __future__ import annotations

import ctypes
from ctypes import POINTER, c_double, c_uint8, c_uint16, c_uint32, c_uint64
from pathlib import Path
from typing import Protocol, runtime_checkable

from ..errors import SimError
from ..protocol.enums import ResetCause
from .private_library import load_private_copy

#: Resets that are not a power-on, by name ("external", "brown-out", "watchdog", "software").
RESTART_CAUSES = {c.name.lower().replace("_", "-"): int(c) for c in ResetCause
                  if c not in (ResetCause.UNKNOWN, ResetCause.POWER_ON)}

#: IMU fault modes understood by the C MPU-6050 model.
IMU_FAULTS = {"ok": 0, "no-ack": 1, "stuck": 2, "garbage": 3}

_SIGNATURES = {
    "sim_reset": ([c_uint32], None),
    "sim_restart": ([c_uint8], None),
    "sim_run_ticks": ([c_uint32], None),
    "sim_time_us": ([], c_uint64),
    "sim_tick_period_us": ([], c_uint32),
    "sim_pwm_duty": ([c_uint8], c_uint16),
    "sim_uart_write": ([POINTER(c_uint8), c_uint32], None),
    "sim_uart_read": ([POINTER(c_uint8), c_uint32], c_uint32),
    "sim_imu_set_truth": ([c_uint8, c_double, c_double], None),
    "sim_imu_set_fault": ([c_uint8, c_uint8], None),
    "sim_imu_set_noise": ([c_uint8, c_double, c_double, c_double], None),
    "sim_imu_peek_reg": ([c_uint8, c_uint8], c_uint8),
}
#: Only in images whose host link is CAN (board file [link] transport = "can": hal/sim/can_sim.c).
_CAN_SIGNATURES = {
    "sim_can_write": ([c_uint16, POINTER(c_uint8), c_uint8], None),
    "sim_can_read": ([POINTER(c_uint16), POINTER(c_uint8), POINTER(c_uint8)], c_uint32),
    "sim_can_bitrate": ([], c_uint32),
}


@runtime_checkable
class SimulatedBoardLike(Protocol):
    """What ``SimulatedRobot`` needs from a simulated board running one firmware image.

    Time is virtual: nothing happens between calls. ``tick_us`` is the control tick period.
    """

    tick_us: int

    def reset(self, seed: int = 1) -> None:
        """Power-on reset: firmware state cleared, time 0, FIFOs empty; ``seed`` seeds the models."""

    def restart(self, cause: str = "external") -> None:
        """A reset that is not a power-on ("external": the reset pin; the host-sim build also
        "brown-out", "watchdog" and "software"): the firmware restarts, RAM keeps what the
        chip's keeps, the models stay powered."""

    def run_ticks(self, n: int) -> None:
        """Run ``n`` control ticks of the firmware."""

    @property
    def time_us(self) -> int: ...

    @property
    def time_s(self) -> float: ...

    def pwm(self, channel: int) -> float:
        """MOSFET duty of an actuator channel, 0..1."""

    def pwm_permyriad(self, channel: int) -> int: ...

    def write(self, data: bytes) -> None:
        """Host → board UART bytes."""

    def read(self) -> bytes:
        """Board → host UART bytes sent since the last read."""

    def imu_truth(self, addr: int, psi_deg: float, dpsi_dps: float) -> None:
        """The true contact angle and rate the IMU at ``addr`` senses."""

    def imu_fault(self, addr: int, mode: str) -> None:
        """``mode`` in ``IMU_FAULTS``: ok, no-ack, stuck, garbage."""

    def imu_noise(self, addr: int, accel_ug_rthz: float, gyro_dps_rthz: float, accel_offset_mg: float) -> None: ...

    def imu_register(self, addr: int, reg: int) -> int: ...


class SimBoard:
    """One simulated board running one firmware image (implements ``SimulatedBoardLike``)."""

    def __init__(self, library: str | Path, seed: int = 1):
        library = Path(library)
        if not library.exists():
            raise SimError(f"{library}: no host-sim firmware (build it with: proleg build ROBOT --board host-sim)")
        self._lib = load_private_copy(library, prefix="proleg-sim-", what="the simulated board")
        for name, (args, res) in _SIGNATURES.items():
            try:
                fn = getattr(self._lib, name)
            except AttributeError:
                raise SimError(f"{library}: not a host-sim firmware (missing {name})") from None
            fn.argtypes, fn.restype = args, res
        self.has_can = all(hasattr(self._lib, name) for name in _CAN_SIGNATURES)
        if self.has_can:
            for name, (args, res) in _CAN_SIGNATURES.items():
                fn = getattr(self._lib, name)
                fn.argtypes, fn.restype = args, res
        self._can_id, self._can_dlc, self._can_data = c_uint16(), c_uint8(), (c_uint8 * 8)()
        self._rx_buf = (c_uint8 * 4096)()
        self.library = library
        self.tick_us = 0
        self._pending_us = 0.0
        self.reset(seed)

    # -- time -------------------------------------------------------------------------
    def reset(self, seed: int = 1) -> None:
        """Power-on reset: firmware globals cleared, IMUs asleep, time 0, FIFOs empty."""
        self._lib.sim_reset(seed & 0xFFFFFFFF)
        self.tick_us = int(self._lib.sim_tick_period_us())
        self._pending_us = 0.0

    def restart(self, cause: str = "external") -> None:
        """A reset that is not a power-on (``cause`` in ``RESTART_CAUSES``: a Nano's DTR
        auto-reset or its button, a brown-out, the watchdog): the firmware restarts with its
        clock at 0, the IMUs stay powered, and RAM keeps what a chip's keeps across it."""
        if cause not in RESTART_CAUSES:
            raise ValueError(f"restart cause {cause!r}: expected one of {', '.join(RESTART_CAUSES)}")
        self._lib.sim_restart(RESTART_CAUSES[cause])
        self._pending_us = 0.0

    def run_ticks(self, n: int) -> None:
        if n > 0:
            self._lib.sim_run_ticks(n)

    def advance(self, seconds: float) -> None:
        """Run the control ticks that fit in ``seconds`` of virtual time (a remainder shorter
        than a tick is carried over to the next call), so ``proleg.link.sim_link.SimLink``
        can drive the bare board tick by tick: ``SimLink(board, step_s=board.tick_us / 1e6)``."""
        self._pending_us += seconds * 1e6
        n = int(self._pending_us / self.tick_us + 1e-9)
        self._pending_us -= n * self.tick_us
        self.run_ticks(n)

    @property
    def time_us(self) -> int:
        return int(self._lib.sim_time_us())

    @property
    def time_s(self) -> float:
        return self.time_us / 1e6

    # -- outputs ----------------------------------------------------------------------
    def pwm(self, channel: int) -> float:
        """MOSFET duty of an actuator channel, 0..1, as the firmware last set it."""
        return self._lib.sim_pwm_duty(channel) / 10000.0

    def pwm_permyriad(self, channel: int) -> int:
        return int(self._lib.sim_pwm_duty(channel))

    # -- host link (UART) -------------------------------------------------------------
    def write(self, data: bytes) -> None:
        """Bytes from the host into the board's receive FIFO."""
        if data:
            buf = (c_uint8 * len(data)).from_buffer_copy(data)
            self._lib.sim_uart_write(buf, len(data))

    def read(self) -> bytes:
        """Every byte the board has sent since the last read."""
        chunks = []
        while True:
            n = self._lib.sim_uart_read(self._rx_buf, len(self._rx_buf))
            if n:
                chunks.append(bytes(self._rx_buf[:n]))
            if n < len(self._rx_buf):
                return b"".join(chunks)

    # -- host link (CAN: images built for a board with [link] transport = "can") ----------
    def can_write(self, arbitration_id: int, data: bytes) -> None:
        """A standard frame from the bus; the controller's filter passes this node's commands only."""
        self._need_can()
        buf = (c_uint8 * 8).from_buffer_copy(bytes(data[:8]).ljust(8, b"\0"))
        self._lib.sim_can_write(arbitration_id & 0x7FF, buf, min(8, len(data)))

    def can_read(self) -> list[tuple[int, bytes]]:
        """Every frame the board has put on the bus since the last read: (identifier, data)."""
        self._need_can()
        out = []
        while self._lib.sim_can_read(ctypes.byref(self._can_id), self._can_data, ctypes.byref(self._can_dlc)):
            out.append((int(self._can_id.value), bytes(self._can_data[: self._can_dlc.value])))
        return out

    def _need_can(self) -> None:
        if not self.has_can:
            raise SimError(f"{self.library}: this firmware's host link is not CAN (build it for host-sim-can)")

    # -- IMUs on the I2C bus ----------------------------------------------------------
    def imu_truth(self, addr: int, psi_deg: float, dpsi_dps: float) -> None:
        self._lib.sim_imu_set_truth(addr, psi_deg, dpsi_dps)

    def imu_fault(self, addr: int, mode: str) -> None:
        if mode not in IMU_FAULTS:
            raise SimError(f"unknown IMU fault {mode!r} (expected one of: {', '.join(IMU_FAULTS)})")
        self._lib.sim_imu_set_fault(addr, IMU_FAULTS[mode])

    def imu_noise(self, addr: int, accel_ug_rthz: float, gyro_dps_rthz: float, accel_offset_mg: float) -> None:
        self._lib.sim_imu_set_noise(addr, accel_ug_rthz, gyro_dps_rthz, accel_offset_mg)

    def imu_register(self, addr: int, reg: int) -> int:
        return int(self._lib.sim_imu_peek_reg(addr, reg))
