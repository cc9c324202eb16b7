"""``AvrEmuBoard``: the exact arduino-nano ``firmware.elf`` on an emulated ATmega328P.

The same simulated-board interface as host-sim's ``proleg.sim.board.SimBoard``
(``reset``, ``run_ticks``, ``tick_us``, ``time_us``, ``time_s``, ``pwm``,
``pwm_permyriad``, ``write``, ``read``, ``imu_truth``, ``imu_fault``, ``imu_noise``,
``imu_register``), so the simulated robot drives it with the same plant and faults;
``advance(seconds)`` also lets a ``proleg.link.SimLink`` talk to it without a plant.
What only an emulated MCU can show comes on top: ``tick_budget()`` (busy time per
control tick, its I2C share, stack depth, emulation speed), the UART's losses, the
core's state, IMUs that answer late (``imu_startup``).

Time is emulated: ``run_ticks(n)`` runs n × tick_us µs of the MCU's clock (16 MHz
cycles), whatever the firmware does with them; the firmware paces its own ticks.
Each board loads a private copy of the harness library (its MPU-6050 models are
file-global), so several boards can run in one process.
"""

from __future__ import annotations

import re
import time
from ctypes import POINTER, c_char, c_char_p, c_double, c_int, c_uint8, c_uint16, c_uint32, c_uint64
from fractions import Fraction
from pathlib import Path

import numpy as np

from ...errors import SimError
from ...firmware.boards import Board, load_board
from ...sim.private_library import load_private_copy
from .budget import TickBudget, summarize
from .elf import TickMarkers, find_symbol, symbols, tick_markers
from .library import harness_library

#: IMU fault modes understood by the MPU-6050 model (as host-sim).
IMU_FAULTS = {"ok": 0, "no-ack": 1, "stuck": 2, "garbage": 3}

#: ATmega328P output-compare pins by Arduino Nano pin name (pwm.c numbering).
OC_PINS = {"D6": 0, "D5": 1, "D9": 2, "D10": 3, "D11": 4, "D3": 5}

#: simavr's cpu states (sim_avr.h).
CPU_STATES = ("limbo", "stopped", "running", "sleeping", "step", "step-done", "done", "crashed")

RAMEND = 0x8FF  # ATmega328P
CHUNK_S = 0.5  # tick records are drained at least this often (the harness keeps 16384)

_SIGNATURES = {
    "emu_open": ([c_char_p, c_uint32, c_uint32], c_int),
    "emu_reset": ([c_uint32], c_int),
    "emu_imu_attach": ([c_uint8], None),
    "emu_imu_wire": ([c_uint8, c_uint8, c_uint8, c_uint8], None),
    "emu_run_cycles": ([c_uint64], c_int),
    "emu_cycles": ([], c_uint64),
    "emu_frequency": ([], c_uint32),
    "emu_cpu_state": ([], c_int),
    "emu_pc": ([], c_uint32),
    "emu_mcu_resets": ([], c_uint64),
    "emu_read_data": ([c_uint16, POINTER(c_uint8), c_uint32], c_uint32),
    "emu_set_pwm_map": ([c_uint8, c_uint8], c_int),
    "emu_pwm_duty": ([c_uint8], c_uint16),
    "emu_port": ([c_char], c_uint16),
    "emu_uart_write": ([POINTER(c_uint8), c_uint32], None),
    "emu_uart_read": ([POINTER(c_uint8), c_uint32], c_uint32),
    "emu_uart_losses": ([POINTER(c_uint32)], None),
    "emu_uart_cycles_per_byte": ([], c_uint64),
    "emu_imu_set_truth": ([c_uint8, c_double, c_double], None),
    "emu_imu_set_fault": ([c_uint8, c_uint8], None),
    "emu_imu_set_noise": ([c_uint8, c_double, c_double, c_double], None),
    "emu_imu_peek_reg": ([c_uint8, c_uint8], c_uint8),
    "emu_imu_set_startup_us": ([c_uint8, c_uint64], None),
    "emu_i2c_hold_sda": ([c_int, c_uint8], None),
    "emu_i2c_transactions": ([], c_uint64),
    "emu_i2c_bus_cycles": ([], c_uint64),
    "emu_set_tick_markers": ([c_uint32, c_uint32], None),
    "emu_gpio_markers": ([], c_int),
    "emu_ticks_read": ([POINTER(c_uint64), POINTER(c_uint32), POINTER(c_uint32), c_uint32], c_uint32),
    "emu_ticks_lost": ([], c_uint64),
    "emu_sp_min": ([], c_uint16),
    "emu_jump": ([c_uint32], None),
    "emu_profile": ([c_int], None),
    "emu_profile_read": ([POINTER(c_uint64), c_uint32], c_uint32),
    "emu_set_boot_reset": ([c_uint32], None),
    "emu_external_reset": ([], None),
    "emu_flash_write": ([c_uint32, POINTER(c_uint8), c_uint32], c_int),
    "emu_flash_read": ([c_uint32, POINTER(c_uint8), c_uint32], c_int),
}


def _config_value(elf: Path, name: str) -> str | None:
    """A #define from the build's rendered robot_config.h next to the ELF, if there is one."""
    for cfg in (elf.parent / "gen" / "robot_config.h", *sorted(elf.parent.glob("**/robot_config.h"))):
        if cfg.exists():
            m = re.search(rf"#define\s+{name}\s+(.+?)\s*(?:/\*.*)?$", cfg.read_text(encoding="utf-8"), re.M)
            if m:
                return m.group(1)
    return None


class AvrEmuBoard:
    """An emulated arduino-nano running one ``firmware.elf``."""

    def __init__(
        self,
        elf_path: str | Path,
        seed: int = 1,
        *,
        tick_hz: float | None = None,
        board: Board | None = None,
        imu_addresses: tuple[int, ...] | None = None,
        imu_wiring: tuple[tuple[int, int, int], ...] | None = None,
    ):
        self.elf = Path(elf_path)
        if not self.elf.exists():
            raise SimError(f"{self.elf}: no firmware (build it with: proleg build ROBOT --board arduino-nano)")
        self.board_info = board or load_board("arduino-nano")
        if self.board_info.family != "avr" or self.board_info.mcu != "atmega328p":
            raise SimError(
                f"board {self.board_info.name}: avr-emu emulates the ATmega328P, "
                f"the board file says family {self.board_info.family!r}, mcu {self.board_info.mcu!r}"
            )
        self.tick_hz = float(tick_hz if tick_hz is not None else self._config_tick_hz())
        if not self.tick_hz > 0:
            raise SimError(f"{self.elf}: tick rate must be > 0 Hz, got {self.tick_hz}")
        self.imu_addresses = tuple(imu_addresses if imu_addresses is not None else self._config_imus())
        # Per limb (model slot): (address, multiplexer address or 0, channel); None: each of
        # imu_addresses wired directly. With a wiring, the IMU keys are host-sim's
        # (proleg.firmware.placement.sim_imu_keys: the address, or 0x80 | limb behind a mux).
        self.imu_wiring = tuple(imu_wiring) if imu_wiring is not None else None
        self.freq = int(self.board_info.clock_hz)
        self._cycles_per_tick = Fraction(self.freq) / Fraction(self.tick_hz).limit_denominator(10**6)

        self._lib = load_private_copy(harness_library(), prefix="proleg-avr-emu-", what="the avr-emu harness")
        for name, (args, res) in _SIGNATURES.items():
            fn = getattr(self._lib, name)
            fn.argtypes, fn.restype = args, res
        r = self._lib.emu_open(str(self.elf).encode(), self.freq, int(self.board_info.uart_baud))
        if r == -1:
            raise SimError(f"{self.elf}: simavr cannot load this ELF")
        if r != 0:
            raise SimError(f"{self.elf}: simavr has no atmega328p core")
        for ch, pin in enumerate(self.board_info.pwm_pins):
            if pin not in OC_PINS:
                raise SimError(
                    f"{self.board_info.path}: [pwm] pins: {pin} is not an ATmega328P output-compare pin "
                    f"(expected one of {', '.join(OC_PINS)})"
                )
            self._lib.emu_set_pwm_map(ch, OC_PINS[pin])
        self.markers: TickMarkers | None = tick_markers(self.elf)
        if self.markers is not None:
            self._lib.emu_set_tick_markers(self.markers.start, self.markers.end)
        # the end of static RAM: _end follows .noinit (state a warm reset keeps), __bss_end does not
        static_end = find_symbol(self.elf, "_end") or find_symbol(self.elf, "__bss_end")
        self._static_end = static_end.address if static_end is not None else 0
        self._rx_buf = (c_uint8 * 8192)()
        n = 1 << 14
        self._t_start, self._t_busy, self._t_i2c = (c_uint64 * n)(), (c_uint32 * n)(), (c_uint32 * n)()
        self.reset(seed)

    def _config_tick_hz(self) -> float:
        v = _config_value(self.elf, "CFG_TICK_HZ")
        if v is None:
            raise SimError(f"{self.elf}: no robot_config.h next to it: give the robot's tick rate (tick_hz=...)")
        return float(re.sub(r"[uUlL]+$", "", v))

    def _config_imus(self) -> tuple[int, ...]:
        v = _config_value(self.elf, "CFG_LIMB_IMU_ADDR")
        if v is not None:
            return tuple(int(x, 0) for x in re.findall(r"0x[0-9a-fA-F]+|\d+", v.replace("u", "")))
        return tuple(self.board_info.i2c.get("imu_addresses", [0x68, 0x69]))

    # -- time -------------------------------------------------------------------------
    def reset(self, seed: int = 1) -> None:
        """Power-on reset: a fresh MCU, IMUs powered up (asleep), time 0, FIFOs empty."""
        if self._lib.emu_reset(seed & 0xFFFFFFFF) != 0:
            raise SimError(f"{self.elf}: simavr could not reset the core")
        if self.imu_wiring is not None:
            for slot, (addr, mux, ch) in enumerate(self.imu_wiring):
                self._lib.emu_imu_wire(slot, addr, mux, ch)
        else:
            for addr in self.imu_addresses:
                self._lib.emu_imu_attach(addr)
        self._carry = Fraction(0)
        self._records: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self._window_cycles = 0
        self._window_wall = 0.0
        self._window_cpu = 0.0

    @property
    def tick_us(self) -> float:
        us = 1e6 / self.tick_hz
        return int(us) if us == int(us) else us

    def run_ticks(self, n: int) -> None:
        """Run n control-tick periods of emulated time."""
        if n <= 0:
            return
        exact = self._cycles_per_tick * n + self._carry
        cycles = int(exact)
        self._carry = exact - cycles
        self.run_cycles(cycles)

    def run_us(self, us: float) -> None:
        self.run_cycles(round(us * self.freq / 1e6))

    def advance(self, seconds: float) -> None:
        """Run the board alone (no plant) for ``seconds``: what a SimLink needs."""
        self.run_us(seconds * 1e6)

    def run_cycles(self, cycles: int) -> None:
        chunk = int(CHUNK_S * self.freq)
        t0, c0 = time.perf_counter(), time.process_time()
        while cycles > 0:
            step = min(cycles, chunk)
            self._lib.emu_run_cycles(step)
            cycles -= step
            self._window_cycles += step
            self._drain_ticks()
        self._window_wall += time.perf_counter() - t0
        self._window_cpu += time.process_time() - c0

    @property
    def time_us(self) -> int:
        return int(self._lib.emu_cycles()) * 1_000_000 // self.freq

    @property
    def time_s(self) -> float:
        return int(self._lib.emu_cycles()) / self.freq

    @property
    def cycles(self) -> int:
        return int(self._lib.emu_cycles())

    # -- outputs ----------------------------------------------------------------------
    def pwm(self, channel: int) -> float:
        """MOSFET duty of a board PWM channel, 0..1, from the timer registers now."""
        return self._lib.emu_pwm_duty(channel) / 10000.0

    def pwm_permyriad(self, channel: int) -> int:
        return int(self._lib.emu_pwm_duty(channel))

    def port(self, name: str) -> tuple[int, int]:
        """(DDRx, PORTx) of port B, C or D."""
        v = int(self._lib.emu_port(name.encode()))
        return v >> 8, v & 0xFF

    # -- host link (UART) -------------------------------------------------------------
    def write(self, data: bytes) -> None:
        """Bytes from the host; they reach the MCU's receiver one frame time apart."""
        if data:
            buf = (c_uint8 * len(data)).from_buffer_copy(data)
            self._lib.emu_uart_write(buf, len(data))

    def read(self) -> bytes:
        """Every byte the MCU has transmitted since the last read."""
        chunks = []
        while True:
            n = self._lib.emu_uart_read(self._rx_buf, len(self._rx_buf))
            if n:
                chunks.append(bytes(self._rx_buf[:n]))
            if n < len(self._rx_buf):
                return b"".join(chunks)

    def uart_losses(self) -> dict[str, int]:
        out = (c_uint32 * 4)()
        self._lib.emu_uart_losses(out)
        return {"rx_overrun": out[0], "rx_disabled": out[1], "rx_host_queue": out[2], "tx_host_queue": out[3]}

    @property
    def uart_frame_us(self) -> float:
        """The MCU's UART frame time as its registers set it (after the firmware's init)."""
        return int(self._lib.emu_uart_cycles_per_byte()) * 1e6 / self.freq

    # -- IMUs on the TWI bus ----------------------------------------------------------
    def imu_truth(self, addr: int, psi_deg: float, dpsi_dps: float) -> None:
        self._lib.emu_imu_set_truth(addr, psi_deg, dpsi_dps)

    def imu_fault(self, addr: int, mode: str) -> None:
        if mode not in IMU_FAULTS:
            raise SimError(f"unknown IMU fault {mode!r} (expected one of: {', '.join(IMU_FAULTS)})")
        self._lib.emu_imu_set_fault(addr, IMU_FAULTS[mode])

    def imu_noise(self, addr: int, accel_ug_rthz: float, gyro_dps_rthz: float, accel_offset_mg: float) -> None:
        self._lib.emu_imu_set_noise(addr, accel_ug_rthz, gyro_dps_rthz, accel_offset_mg)

    def imu_register(self, addr: int, reg: int) -> int:
        return int(self._lib.emu_imu_peek_reg(addr, reg))

    def imu_startup(self, addr: int, us: float) -> None:
        """The IMU at addr does not acknowledge until ``us`` after power-on (kept across resets)."""
        self._lib.emu_imu_set_startup_us(addr, max(0, round(us)))

    def i2c_hold_sda(self, held: bool = True, release_after_clocks: int = 9) -> None:
        """A device holds SDA low (a transfer cut short): no START until it has seen
        ``release_after_clocks`` SCL pulses, driven on PC5 as GPIO while the TWI is off
        (0 = never). Kept across MCU resets (watchdog), released by a power-on reset."""
        self._lib.emu_i2c_hold_sda(int(held), max(0, min(255, release_after_clocks)))

    @property
    def i2c_transactions(self) -> int:
        return int(self._lib.emu_i2c_transactions())

    # -- the core ---------------------------------------------------------------------
    @property
    def cpu_state(self) -> str:
        s = int(self._lib.emu_cpu_state())
        return CPU_STATES[s] if 0 <= s < len(CPU_STATES) else f"state {s}"

    def hang(self, symbol: str = "__stop_program") -> None:
        """Fault injection: the core jumps into an endless loop (``symbol``, avr-libc's
        ``rjmp .`` by default) as a stuck loop or a wild pointer would; only the watchdog
        gets it out."""
        sym = find_symbol(self.elf, symbol)
        if sym is None:
            raise SimError(f"{self.elf}: no symbol {symbol!r} to hang in")
        self._lib.emu_jump(sym.address)

    @property
    def mcu_resets(self) -> int:
        """MCU resets since power-on (watchdog, software), not counting the power-on."""
        return int(self._lib.emu_mcu_resets())

    def read_data(self, addr: int, n: int) -> bytes:
        """Data-space bytes: registers, I/O (0x20..0xFF), SRAM (0x100..0x8FF)."""
        buf = (c_uint8 * n)()
        got = self._lib.emu_read_data(addr, buf, n)
        return bytes(buf[:got])

    def read_symbol(self, name: str) -> bytes:
        sym = find_symbol(self.elf, name)
        if sym is None or sym.kind not in "bBdD":
            raise SimError(f"{self.elf}: no data symbol {name!r}")
        return self.read_data(sym.address, sym.size)

    # -- where the cycles go ------------------------------------------------------------
    def profile_start(self) -> None:
        """Count cycles per instruction from now on (slows the emulation a little)."""
        self._lib.emu_profile(1)

    def profile(self, stop: bool = True) -> dict[str, int]:
        """Cycles spent per function since ``profile_start``, largest first. Inlined code
        counts for the function it was inlined into (``main`` with today's LTO build)."""
        words = 1 << 14
        buf = (c_uint64 * words)()
        n = self._lib.emu_profile_read(buf, words)
        if stop:
            self._lib.emu_profile(0)
        cycles = np.ctypeslib.as_array(buf)[:n]
        funcs = sorted(
            (s.address, s.address + max(s.size, 2), s.name.split(".")[0])
            for s in symbols(self.elf).values()
            if s.kind in "tTW" and s.address < 2 * words
        )
        out: dict[str, int] = {}
        for word in np.flatnonzero(cycles):
            pc = int(word) * 2
            name = "?"
            for lo, hi, fname in funcs:
                if lo <= pc < hi:
                    name = fname
                    if hi - lo > 2:
                        break
            out[name] = out.get(name, 0) + int(cycles[word])
        return dict(sorted(out.items(), key=lambda kv: -kv[1]))

    # -- tick budget ------------------------------------------------------------------
    def _drain_ticks(self) -> None:
        cap = len(self._t_busy)
        while True:
            n = self._lib.emu_ticks_read(self._t_start, self._t_busy, self._t_i2c, cap)
            if n:
                self._records.append(
                    (
                        np.ctypeslib.as_array(self._t_start)[:n].copy(),
                        np.ctypeslib.as_array(self._t_busy)[:n].copy(),
                        np.ctypeslib.as_array(self._t_i2c)[:n].copy(),
                    )
                )
            if n < cap:
                return

    def clear_ticks(self) -> None:
        """Start a new measurement window (e.g. after boot)."""
        self._drain_ticks()
        self._records = []
        self._window_cycles = 0
        self._window_wall = 0.0
        self._window_cpu = 0.0

    @property
    def measures_ticks(self) -> bool:
        return self.markers is not None or bool(self._lib.emu_gpio_markers())

    def tick_budget(self) -> TickBudget:
        """The ticks completed in the window (since reset or ``clear_ticks``)."""
        if not self.measures_ticks:
            raise SimError(f"{self.elf}: no tick markers found (no wait_tick wait loop, no GPIOR0 writes)")
        self._drain_ticks()
        if self._records:
            starts, busy, i2c = (np.concatenate(parts) for parts in zip(*self._records))
        else:
            starts = busy = i2c = np.zeros(0, dtype=np.uint32)
        sp_min = int(self._lib.emu_sp_min())
        return summarize(
            starts,
            busy,
            i2c,
            freq_hz=self.freq,
            tick_period_us=1e6 / self.tick_hz,
            stack_peak_bytes=RAMEND - sp_min if sp_min <= RAMEND else 0,
            stack_margin_bytes=sp_min - self._static_end + 1 if sp_min <= RAMEND else RAMEND - self._static_end,
            emulated_s=self._window_cycles / self.freq,
            wall_s=self._window_wall,
            cpu_s=self._window_cpu,
        )

    # -- flash and the boot section (boot.c) ---------------------------------------------
    def flash_write(self, address: int, data: bytes) -> None:
        """Write program memory directly (as an ISP programmer would)."""
        buf = (c_uint8 * len(data)).from_buffer_copy(data)
        if self._lib.emu_flash_write(address, buf, len(data)) != 0:
            raise SimError(f"flash write of {len(data)} bytes at 0x{address:04x} is past the end of flash")

    def flash_read(self, address: int, n: int) -> bytes:
        buf = (c_uint8 * n)()
        if self._lib.emu_flash_read(address, buf, n) != 0:
            raise SimError(f"flash read of {n} bytes at 0x{address:04x} is past the end of flash")
        return bytes(buf)

    def install_bootloader(self, image: dict[int, bytes], boot_start: int, *, erase_application: bool = False) -> None:
        """Program a bootloader (``image``: address → bytes, e.g. from an Intel HEX file)
        into the boot section starting at ``boot_start`` and set BOOTRST: from now on
        every reset (power-on, watchdog, ``external_reset``) starts there, and flash keeps
        what the bootloader writes across power-on resets. ``erase_application`` leaves
        the application section blank (0xFF), as on a new chip."""
        for addr in image:
            if addr < boot_start:
                raise SimError(f"bootloader byte at 0x{addr:04x} is below the boot section (0x{boot_start:04x})")
        if erase_application:
            self.flash_write(0, b"\xff" * boot_start)
        for addr, data in image.items():
            self.flash_write(addr, data)
        self._lib.emu_set_boot_reset(boot_start)

    def external_reset(self) -> None:
        """Pull RESET low: the MCU restarts with MCUSR = EXTRF (a Nano's DTR auto-reset)."""
        self._lib.emu_external_reset()

    def restart(self, cause: str = "external") -> None:
        """A reset that is not a power-on (``SimBoard.restart``): here the RESET pin only; SRAM
        keeps what it held, as the chip's does."""
        if cause != "external":
            raise ValueError(f"restart cause {cause!r}: the emulated Nano restarts by its RESET pin only ('external')")
        self.external_reset()
