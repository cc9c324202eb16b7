"""The arm-emu board's native helper: the cycle-counting block hook and the I2C devices.

``cycles.c`` and ``i2cbus.c`` (next to this file: which device answers where on the two
buses) and the shared register-level models of every simulated board
(``firmware_templates/hal/sim/``: ``sim_mpu6050.c``, and ``sim_tca9548a.c``, the
TCA9548A multiplexer host-sim and avr-emu use too) are compiled with ``cc`` into one
small shared library, cached under ``$PROLEG_CACHE/emu-arm/<hash>/``. Each
emulated board loads its own copy (the library holds that board's cycle counter and IMU
states in C globals), like ``proleg.sim.board.SimBoard`` does.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import subprocess
from ctypes import POINTER, c_double, c_int, c_uint8, c_uint16, c_uint32, c_uint64, c_void_p
from pathlib import Path

from ...errors import SimError
from ...paths import cache_dir, templates_dir
from ...sim.private_library import load_private_copy

_HERE = Path(__file__).resolve().parent

_SIGNATURES = {
    "emu_setup": ([POINTER(c_uint32), c_uint32, c_uint32, POINTER(c_uint16), c_void_p], None),
    "sim_mpu_power_on": ([c_uint32], None),
    "sim_mpu_set_truth_slot": ([c_uint8, c_double, c_double], None),
    "sim_mpu_set_fault_slot": ([c_uint8, c_uint8], None),
    "sim_mpu_set_noise_slot": ([c_uint8, c_double, c_double, c_double], None),
    "sim_mpu_peek_slot": ([c_uint8, c_uint8], c_uint8),
    "sim_tca_control": ([c_uint8, c_uint8], c_uint8),
    "sim_tca_writes": ([], c_uint32),
    "emu_i2c_unwire": ([], None),
    "emu_i2c_wire": ([c_uint8, c_uint8, c_uint8, c_uint8, c_uint8], None),
    "emu_i2c_add_mux": ([c_uint8, c_uint8], None),
    "emu_i2c_transfer": ([c_uint8, c_uint8, POINTER(c_uint8), c_uint8, POINTER(c_uint8), c_uint8, c_uint64], c_int),
    "emu_i2c_stop": ([c_uint8], None),
    "emu_i2c_mux_active": ([c_uint8, c_uint8], c_uint8),
    "emu_i2c_set_startup_us": ([c_uint8, c_uint64], None),
}


def _sim_dir() -> Path:
    return templates_dir() / "hal" / "sim"


def _sources() -> list[Path]:
    sim = _sim_dir()
    return [_HERE / "cycles.c", _HERE / "i2cbus.c", sim / "sim_mpu6050.c", sim / "sim_mpu6050.h",
            sim / "sim_tca9548a.c", sim / "sim_tca9548a.h"]


def native_library() -> Path:
    """Compile (once per source hash) and return the path of the shared helper library."""
    digest = hashlib.sha256()
    for src in _sources():
        digest.update(src.name.encode() + b"\0" + src.read_bytes())
    out = cache_dir("emu-arm") / digest.hexdigest()[:16]
    lib = out / "libarmemu.so"
    if lib.exists():
        return lib
    out.mkdir(parents=True, exist_ok=True)
    tmp = out / f".libarmemu.{os.getpid()}.so"
    srcs = [str(s) for s in _sources() if s.suffix == ".c"]
    cmd = ["cc", "-std=c99", "-O2", "-fPIC", "-shared", "-Wall", "-Wextra", "-Werror", f"-I{_sim_dir()}", "-o", str(tmp),
           *srcs, "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SimError("cannot build the arm-emu helper library:\n  " + (proc.stdout + proc.stderr).strip())
    os.replace(tmp, lib)
    return lib


class Native:
    """One loaded copy of the helper library: this board's cycle counter and IMU models."""

    def __init__(self) -> None:
        self.lib = load_private_copy(native_library(), prefix="proleg-armemu-", what="the arm-emu helper library")
        for name, (args, res) in _SIGNATURES.items():
            fn = getattr(self.lib, name)
            fn.argtypes, fn.restype = args, res
        self.cycles = c_uint64.in_dll(self.lib, "emu_cycles")
        self.deadline = c_uint64.in_dll(self.lib, "emu_deadline")
        self.blocks = c_uint64.in_dll(self.lib, "emu_blocks")
        self.block_hook = ctypes.cast(self.lib.emu_block_hook, c_void_p).value
        self._keep: list = []

    def setup(self, table: list[int] | bytes, base: int, image: bytes, stop_fn: int) -> None:
        cum = (c_uint32 * len(table))(*table)
        img = (c_uint16 * (len(image) // 2)).from_buffer_copy(image[: len(image) // 2 * 2])
        self._keep = [cum, img]
        self.lib.emu_setup(cum, base, len(table), img, c_void_p(stop_fn))

    # -- the I2C devices (i2cbus.c) ----------------------------------------------------
    def bus_transfer(self, bus: int, addr: int, tx: bytes, nrx: int, t_us: int) -> bytes | None:
        """One transaction on ``bus`` (0 = I2C1) with whatever answers at ``addr``; None: NACK."""
        txb = (c_uint8 * max(1, len(tx))).from_buffer_copy(tx or b"\0")
        rxb = (c_uint8 * max(1, nrx))()
        if self.lib.emu_i2c_transfer(bus, addr, txb, len(tx), rxb, nrx, t_us) != 0:
            return None
        return bytes(rxb[:nrx])
