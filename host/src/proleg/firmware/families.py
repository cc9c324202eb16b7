"""HAL families: ``firmware_templates/hal/<family>/`` holds the board-specific C and a
``family.toml`` with the data proleg needs to render for it (its id and which PWM pins the
HAL drives, with the ``CFG_PWM_MAP`` entry of each). A family exists when its folder has a
``family.toml``; nothing outside the folder names a family.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

from ..errors import BoardError, BuildError
from ..paths import templates_dir

#: The largest UART ring a board file may ask for (``uart.rx_buffer``/``tx_buffer``), on a
#: family that sets no lower ``[uart] max_ring_bytes``.
MAX_RING_BYTES = 32768
#: the most a board's UART may run off the rate its file names: the host's USB-serial adapter
#: makes the rate exactly, and 8N1 at U2X tolerates about ±3.7 % in all (ATmega328P data
#: sheet, "Asynchronous Operational Range"); the Nano's 16 MHz makes 115200 as 117,647 (+2.1 %)
MAX_BAUD_ERROR = 0.03
STANDARD_BAUDS = (9600, 19200, 38400, 57600, 115200, 230400, 250000, 460800, 500000, 921600, 1000000)


def is_ring_size(v: object, top: int = MAX_RING_BYTES) -> bool:
    """A UART ring's size (core/ring.h): a whole power of two from 16 to ``top`` bytes."""
    return isinstance(v, int) and not isinstance(v, bool) and 16 <= v <= top and not v & (v - 1)


@dataclass(frozen=True)
class Family:
    name: str
    path: Path  # the HAL folder
    id: int  # CFG_BOARD_ID
    description: str
    pin_kind: str  # what a PWM pin is to this HAL ("timer output", "channel", ...)
    pwm_pins: dict[str, str] | None  # pin name (upper case) -> CFG_PWM_MAP entry; None: any pin, entry = channel
    # the largest UART ring the HAL takes: an 8-bit MCU reads only 8-bit ring indices in one
    # access (core/ring.h), so its rings stop at 128 bytes
    max_ring_bytes: int = MAX_RING_BYTES
    # the UART's bit period is baud_divider × n clock cycles, n a whole number the HAL rounds
    # (avr U2X: 8 × (UBRR + 1); stm32f1: BRR); None: the family does not say, nothing is checked
    baud_divider: int | None = None
    # the n the UART's register can hold (avr: UBRR0 + 1 of 12 bits, 1..4096; stm32f1: BRR, whose
    # 12-bit mantissa must not be 0, 16..65535); an n outside it is a rate the HAL cannot make
    baud_counts: tuple[int, int] = (1, 1 << 32)

    def baud_count(self, clock_hz: int, baud: int) -> int | None:
        """The whole number n the HAL rounds ``baud`` to on a ``clock_hz`` clock (None when the
        family gives no ``baud_divider``)."""
        if self.baud_divider is None:
            return None
        return (clock_hz + self.baud_divider * baud // 2) // (self.baud_divider * baud)

    def actual_baud(self, clock_hz: int, baud: int) -> float | None:
        """The rate the HAL's UART really runs at for ``baud`` on a ``clock_hz`` clock (None
        when the family gives no ``baud_divider``, or when the register cannot hold the n it
        would take: ``baud_counts``)."""
        n = self.baud_count(clock_hz, baud)
        if n is None or not self.baud_counts[0] <= n <= self.baud_counts[1]:
            return None
        return clock_hz / (self.baud_divider * n)

    def baud_problem(self, clock_hz: int, baud: int) -> str | None:
        """Why this HAL's UART cannot run at ``baud`` on a ``clock_hz`` clock (off by more than
        ``MAX_BAUD_ERROR``, or a divider its register cannot hold), naming the usual rates it
        can; None when it can, or when the family gives no ``baud_divider``."""
        if self.baud_divider is None:
            return None
        actual = self.actual_baud(clock_hz, baud)
        if actual is not None and abs(actual / baud - 1) <= MAX_BAUD_ERROR:
            return None

        def fits(b: int) -> bool:
            a = self.actual_baud(clock_hz, b)
            return a is not None and abs(a / b - 1) <= MAX_BAUD_ERROR

        usual = ", ".join(str(b) for b in STANDARD_BAUDS if fits(b)) or "none of the usual"
        if actual is None:  # the register cannot hold the divider (the 12-bit UBRR0, BRR's mantissa 0)
            lo, hi = self.baud_counts
            made = (f"is beyond what the {self.name} HAL's UART makes on a {clock_hz:,} Hz clock (board.clock_hz): "
                    f"{clock_hz / (self.baud_divider * hi):,.0f} to {clock_hz / (self.baud_divider * lo):,.0f} baud")
        else:
            made = (f"is made as {actual:,.0f} baud ({actual / baud - 1:+.1%}) by the {self.name} HAL on a "
                    f"{clock_hz:,} Hz clock (board.clock_hz), more than {MAX_BAUD_ERROR:.0%} off")
        return (f"{made}: the link would garble; rates within {MAX_BAUD_ERROR:.0%}: {usual} (give the host the same "
                "with --baudrate)")

    def pwm_entry(self, board_name: str, channel: int, pin: str) -> str:
        """The C initialiser of channel's CFG_PWM_MAP entry; BuildError for a pin the HAL cannot drive."""
        if self.pwm_pins is None:
            return f"{channel}u"
        key = str(pin).upper()
        if key not in self.pwm_pins:
            raise BuildError(
                f"board {board_name}: [pwm] pin {pin!r} (channel = {channel}) is not a {self.pin_kind} "
                f"this HAL drives (expected one of: {', '.join(sorted(self.pwm_pins))})"
            )
        return self.pwm_pins[key]


def hal_root() -> Path:
    return templates_dir() / "hal"


def available_families() -> list[str]:
    return sorted(p.parent.name for p in hal_root().glob("*/family.toml"))


def load_family(name: str) -> Family:
    path = hal_root() / name
    spec = path / "family.toml"
    if not spec.is_file():
        raise BoardError(
            f"no HAL family {name!r}: expected {spec} (families: {', '.join(available_families())})"
        )
    try:
        doc = tomllib.loads(spec.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as e:
        raise BoardError(f"{spec}: not valid TOML: {e}") from None
    fam, pwm = doc.get("family", {}), doc.get("pwm", {})
    fid = fam.get("id")
    if not isinstance(fid, int) or isinstance(fid, bool) or not 0 <= fid <= 255:
        raise BoardError(f"{spec}: family.id: expected an integer 0..255, got {fid!r}")
    pins = pwm.get("pins")
    if pins == "any":
        table = None
    elif isinstance(pins, dict) and pins:
        table = {str(k).upper(): _c_entry(spec, k, v) for k, v in pins.items()}
    else:
        raise BoardError(f"{spec}: pwm.pins: expected \"any\" or a table of pin = C entry")
    ring = doc.get("uart", {}).get("max_ring_bytes", MAX_RING_BYTES)
    if not is_ring_size(ring):
        raise BoardError(f"{spec}: uart.max_ring_bytes: expected a power of two from 16 to {MAX_RING_BYTES}, "
                         f"got {ring!r}")
    divider = doc.get("uart", {}).get("baud_divider")
    if divider is not None and (isinstance(divider, bool) or not isinstance(divider, int) or not 1 <= divider <= 64):
        raise BoardError(f"{spec}: uart.baud_divider: expected a whole number 1..64, got {divider!r}")
    counts = doc.get("uart", {}).get("baud_counts", [1, 1 << 32])
    if (not isinstance(counts, list) or len(counts) != 2 or any(isinstance(c, bool) or not isinstance(c, int) for c in counts)
            or not 1 <= counts[0] <= counts[1]):
        raise BoardError(f"{spec}: uart.baud_counts: expected [lowest, highest] whole numbers from 1, got {counts!r}")
    return Family(name, path, fid, str(fam.get("description", "")), str(pwm.get("pin_kind", "PWM pin")), table,
                  ring, divider, (counts[0], counts[1]))


def _c_entry(spec: Path, pin: str, value: object) -> str:
    """A pin's CFG_PWM_MAP entry: a C expression (string) or a list of unsigned fields."""
    if isinstance(value, str) and value:
        return value
    if isinstance(value, list) and value and all(isinstance(x, int) and x >= 0 for x in value):
        return "{" + ", ".join(f"{x}u" for x in value) + "}"
    raise BoardError(f"{spec}: pwm.pins.{pin}: expected a C expression or a list of unsigned integers")
