"""Render a robot's configuration and gait tables for the firmware core.

``render_config(robot, gaits_by_direction, board)`` fills ``firmware_templates/robot_config.h.j2``
and ``gait_table.c.j2``. Only data is rendered (STYLE.md: generate data, keep logic
hand-written): limb levels, the Q14 cos/sin of every hysteresis band edge (so the control
path classifies ψ with two multiplications, no atan2), actuator channels and the board's
PWM pin map, the safety envelope in ticks, the gait step tables of both directions and
the allowed-transition bitmap. Same inputs, same bytes: no timestamps.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import jinja2

from .. import __version__
from ..errors import BuildError
from ..paths import home, templates_dir

Q14 = 1 << 14
#: LOAD_GAIT capacity (the protocol's MAX_GAIT_STEPS).
MAX_LOADED_STEPS = 24
#: Largest state space whose allowed-transition table is a bitmap (n*n bits); above, a sorted key list.
BITMAP_MAX_STATES = 64
FAMILY_IDS = {"sim": 0, "avr": 1, "stm32f1": 2}

# ATmega328P: Arduino pin name / port pin / compare output → HAL code (hal_avr.c).
_AVR_PWM = {
    "D9": "HAL_AVR_OC1A", "PB1": "HAL_AVR_OC1A", "OC1A": "HAL_AVR_OC1A",
    "D10": "HAL_AVR_OC1B", "PB2": "HAL_AVR_OC1B", "OC1B": "HAL_AVR_OC1B",
    "D11": "HAL_AVR_OC2A", "PB3": "HAL_AVR_OC2A", "OC2A": "HAL_AVR_OC2A",
    "D3": "HAL_AVR_OC2B", "PD3": "HAL_AVR_OC2B", "OC2B": "HAL_AVR_OC2B",
}
# STM32F103: pin → (timer, channel, port 0=A 1=B, pin). TIM2..TIM4, avoiding USART1/I2C1 pins.
_STM32_PWM = {
    "PA0": (2, 1, 0, 0), "PA1": (2, 2, 0, 1), "PA2": (2, 3, 0, 2), "PA3": (2, 4, 0, 3),
    "PA6": (3, 1, 0, 6), "PA7": (3, 2, 0, 7), "PB0": (3, 3, 1, 0), "PB1": (3, 4, 1, 1),
    "PB8": (4, 3, 1, 8), "PB9": (4, 4, 1, 9),
}


def _get(obj: Any, key: str, default: Any = None) -> Any:
    if isinstance(obj, Mapping):
        return obj.get(key, default)
    getter = getattr(obj, "get", None)
    if callable(getter):
        return getter(key, default)
    return getattr(obj, key, default)


def _ticks(ms: float, tick_hz: int) -> int:
    return int(math.ceil(ms * tick_hz / 1000.0 - 1e-9))


#: Thermal-budget keys of [safety] (docs/safety.md) and their defaults when a robot file
#: (or a robot.py that predates them) has none: hold_max_duty None = max(0.3, control.hold_duty).
BUDGET_DEFAULTS: dict[str, Any] = {
    "hold_max_duty": None,
    "max_mean_duty": 0.5,
    "duty_window_ms": 10_000,
    "on_limit_latch": 3,
}


def _thermal_budget(name: str, safety: Any, ctl: Any) -> dict[str, int]:
    """The [safety] keys of the thermal budget, read with their defaults (docs/safety.md)."""
    v = {k: getattr(safety, k, d) for k, d in BUDGET_DEFAULTS.items()}
    max_duty = float(safety.max_duty)
    hold_max = v["hold_max_duty"]
    if hold_max is None:
        hold_max = min(max_duty, max(0.3, float(ctl.hold_duty)))
    mean = min(float(v["max_mean_duty"]), max_duty)
    if not 0.0 <= float(hold_max) <= mean:
        raise BuildError(
            f"robot {name}: safety.hold_max_duty {hold_max:g} must lie in 0 .. max_mean_duty ({mean:g}): "
            "a duty the coil may hold forever must fit the mean-duty window"
        )
    if not 8 <= int(v["duty_window_ms"]) <= 600_000:
        raise BuildError(f"robot {name}: safety.duty_window_ms {v['duty_window_ms']} must lie in 8 .. 600000")
    if not 1 <= int(v["on_limit_latch"]) <= 255:
        raise BuildError(f"robot {name}: safety.on_limit_latch {v['on_limit_latch']} must lie in 1 .. 255")
    return dict(
        hold_max_duty_pm=round(float(hold_max) * 10000),
        mean_duty_pm=round(mean * 10000),
        duty_window_ms=int(v["duty_window_ms"]),
        on_limit_latch=int(v["on_limit_latch"]),
    )


def _q14(deg: float) -> tuple[int, int]:
    r = math.radians(deg)
    return round(math.cos(r) * Q14), round(math.sin(r) * Q14)


def _file_sha256(path: Any) -> str:
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except (OSError, TypeError):
        return "unavailable"


def _display_path(path: Any) -> str:
    if path is None:
        return "(no file)"
    p = Path(path).resolve()
    try:
        return str(p.relative_to(home()))
    except ValueError:
        return str(p)


def _pwm_map(board: Any, family: str, pins: Sequence[str]) -> list[str]:
    out = []
    for i, pin in enumerate(pins):
        key = str(pin).upper()
        if family == "avr":
            if key not in _AVR_PWM:
                raise BuildError(
                    f"board {_get(board, 'name')}: PWM pin {pin!r} (channel {i}) is not a hardware PWM output "
                    f"this HAL drives (expected one of: {', '.join(sorted(_AVR_PWM))})"
                )
            out.append(_AVR_PWM[key])
        elif family == "stm32f1":
            if key not in _STM32_PWM:
                raise BuildError(
                    f"board {_get(board, 'name')}: PWM pin {pin!r} (channel {i}) is not a timer output "
                    f"this HAL drives (expected one of: {', '.join(sorted(_STM32_PWM))})"
                )
            t, ch, port, p = _STM32_PWM[key]
            out.append(f"{{{t}u, {ch}u, {port}u, {p}u}}")
        else:
            out.append(f"{i}u")
    return out


def gait_table_rows(gaits_by_direction: Mapping[str, Sequence[Any]]) -> list[tuple[int, str, tuple[int, ...]]]:
    """(direction code, direction, open step list) of every compiled gait: +x first, then -x."""
    rows = []
    for code, d in ((0, "+x"), (1, "-x")):
        for g in gaits_by_direction.get(d, ()) or ():
            st = tuple(int(s) for s in g.states)
            if len(st) >= 2 and st[-1] == st[0]:
                st = st[:-1]
            rows.append((code, d, st))
    return rows


def render_config(robot: Any, gaits_by_direction: Mapping[str, Sequence[Any]], board: Any) -> dict[str, str]:
    """Filename → text of ``robot_config.h`` and ``gait_table.c`` for this robot on this board.

    Raises BuildError when the robot does not fit what the firmware supports (thresholds
    near ±90°, more states than 65535, a channel the board lacks, a pin the HAL cannot drive).
    """
    family = str(_get(board, "family"))
    board_name = str(_get(board, "name"))
    if family not in FAMILY_IDS:
        raise BuildError(f"board {board_name}: unknown family {family!r}")
    pins = list(_get(board, "pwm_channels", None) or _get(board, "pwm_pins", ()) or ())
    if not pins:
        raise BuildError(f"board {board_name}: no PWM channels")
    i2c = _get(board, "i2c", {}) or {}
    imu_addresses = list(_get(i2c, "imu_addresses", None) or [0x68, 0x69])
    uart_baud = int(_get(board, "uart_baud", None) or _get(board, "uart_baud_rate", 115200))
    clock_hz = int(_get(board, "clock_hz", 0) or 0)
    pwm_hz = int(_get(board, "pwm_frequency_hz", 1000) or 1000)
    i2c_hz = int(_get(i2c, "hz", 400000) or 400000)

    limbs = list(robot.limbs)
    actuators = list(robot.actuators)
    if len(limbs) > len(imu_addresses):
        raise BuildError(
            f"robot {robot.name}: {len(limbs)} limbs but board {board_name} has {len(imu_addresses)} IMU addresses"
        )
    act_index = {a.name: i for i, a in enumerate(actuators)}
    for a in actuators:
        if not 0 <= a.channel < len(pins):
            raise BuildError(
                f"robot {robot.name}: actuator {a.name!r} on channel {a.channel}, board {board_name} "
                f"has channels 0..{len(pins) - 1}"
            )
    levels = [int(limb.levels) for limb in limbs]
    n_states = math.prod(levels)
    if n_states > 0xFFFF:
        raise BuildError(f"robot {robot.name}: {n_states} states, the firmware supports at most 65535")
    max_thr = max(k - 1 for k in levels)

    thresholds = []  # per limb: list of (up_c, up_s, lo_c, lo_s), padded
    psi_cdeg = []
    for limb in limbs:
        rows = []
        h = float(limb.hysteresis_deg)
        for p in limb.psi_star_deg:
            up, lo = p + h / 2.0, p - h / 2.0
            if not (-90.0 < lo and up < 90.0):
                raise BuildError(
                    f"robot {robot.name}: limb {limb.name!r}: band {lo:g}..{up:g} deg around psi* {p:g} "
                    "must lie strictly inside (-90, 90)"
                )
            rows.append((*_q14(up), *_q14(lo)))
        rows += [(0, 0, 0, 0)] * (max_thr - len(rows))
        thresholds.append(rows)
        psi_cdeg.append([round(p * 100) for p in limb.psi_star_deg] + [0] * (max_thr - len(limb.psi_star_deg)))

    ctl, safety = robot.control, robot.safety
    tick_hz = int(ctl.tick_hz)
    budget = _thermal_budget(robot.name, safety, ctl)
    tick_us = round(1_000_000 / tick_hz)
    if tick_hz < 200:
        raise BuildError(f"robot {robot.name}: control.tick_hz {tick_hz} below 200")

    rows = gait_table_rows(gaits_by_direction)
    n_px = sum(1 for r in rows if r[0] == 0)
    n_mx = len(rows) - n_px
    if n_px > 255 or n_mx > 255:
        raise BuildError(f"robot {robot.name}: more than 255 optimal gaits in one direction")
    steps: list[int] = []
    gait_first, gait_len = [], []
    for _, _, st in rows:
        gait_first.append(len(steps))
        gait_len.append(len(st))
        steps.extend(st)
    if len(steps) > 0xFFFF:
        raise BuildError(f"robot {robot.name}: gait table of {len(steps)} steps, at most 65535")

    table = robot.transitions
    src = [int(x) for x in table.src]
    dst = [int(x) for x in table.dst]
    use_bitmap = n_states <= BITMAP_MAX_STATES
    if use_bitmap:
        bitmap = [0] * ((n_states * n_states + 7) // 8)
        for a, b in zip(src, dst):
            k = a * n_states + b
            bitmap[k >> 3] |= 1 << (k & 7)
        edges: list[int] = []
    else:
        bitmap = []
        edges = sorted(a * n_states + b for a, b in zip(src, dst))

    # The gait hash covers exactly what gait_table.c carries: steps, gaits, allowed transitions.
    gh = hashlib.sha256()
    gh.update(f"states={n_states};".encode())
    for code, _, st in rows:
        gh.update(f"g{code}:{','.join(map(str, st))};".encode())
    gh.update(("t:" + ",".join(f"{a}>{b}" for a, b in zip(src, dst))).encode())
    gait_hash = int.from_bytes(gh.digest()[:4], "big")

    robot_sha = _file_sha256(getattr(robot, "path", None))
    robot_path = _display_path(getattr(robot, "path", None))
    bh = hashlib.sha256(
        f"proleg {__version__}|{robot_sha}|{board_name}|{family}|{','.join(map(str, pins))}|{gait_hash:08x}".encode()
    )
    build_id = int.from_bytes(bh.digest()[:4], "big")

    ctx = dict(
        version=__version__,
        robot_path=robot_path,
        robot_sha=robot_sha,
        robot_name=robot.name,
        board_name=board_name,
        family=family,
        family_id=FAMILY_IDS[family],
        build_id=f"0x{build_id:08X}",
        gait_hash=f"0x{gait_hash:08X}",
        n_limbs=len(limbs),
        n_actuators=len(actuators),
        n_states=n_states,
        state_type="uint8_t" if n_states <= 256 else "uint16_t",
        state_bytes=1 if n_states <= 256 else 2,
        max_levels=max(levels),
        max_thr=max_thr,
        limbs=limbs,
        levels=levels,
        limb_actuator=[act_index[limb.actuator] for limb in limbs],
        imu_addr=[f"0x{imu_addresses[i]:02X}u" for i in range(len(limbs))],
        thresholds=thresholds,
        psi_cdeg=psi_cdeg,
        hyst_cdeg=[round(float(limb.hysteresis_deg) * 100) for limb in limbs],
        actuators=actuators,
        act_channels=[a.channel for a in actuators],
        pins=pins,
        pwm_map=_pwm_map(board, family, pins),
        tick_hz=tick_hz,
        tick_us=tick_us,
        debounce=int(ctl.debounce_ticks),
        hold_ms=int(ctl.hold_ms),
        hold_ticks=_ticks(ctl.hold_ms, tick_hz),
        hold_margin_cdeg=round(float(ctl.hold_margin_deg) * 100),
        telemetry_hz=int(ctl.telemetry_hz),
        drive_pm=round(float(ctl.drive_duty) * 10000),
        hold_pm=round(float(ctl.hold_duty) * 10000),
        max_duty_pm=round(float(safety.max_duty) * 10000),
        max_on_ms=int(safety.max_on_ms),
        max_on_ticks=_ticks(safety.max_on_ms, tick_hz),
        cooldown_ms=int(safety.min_cooldown_ms),
        cooldown_ticks=_ticks(safety.min_cooldown_ms, tick_hz),
        timeout_ms=int(safety.state_timeout_ms),
        timeout_ticks=_ticks(safety.state_timeout_ms, tick_hz),
        watchdog_ms=int(safety.link_watchdog_ms),
        watchdog_ticks=_ticks(safety.link_watchdog_ms, tick_hz),
        **budget,
        stuck_samples=max(20, tick_hz // 5),
        uart_baud=uart_baud,
        clock_hz=clock_hz,
        pwm_hz=pwm_hz,
        i2c_hz=i2c_hz,
        max_loaded=MAX_LOADED_STEPS,
        n_px=n_px,
        n_mx=n_mx,
        rows=rows,
        steps=steps,
        gait_first=gait_first,
        gait_len=gait_len,
        use_bitmap=use_bitmap,
        bitmap=[f"0x{b:02X}" for b in bitmap],
        edges=[f"{e}UL" for e in edges],
        n_transitions=len(src),
        labels=[table.label(i) for i in range(n_states)] if n_states <= 64 else [],
    )
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(templates_dir())),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters["chunks"] = _chunks
    return {
        "robot_config.h": env.get_template("robot_config.h.j2").render(**ctx),
        "gait_table.c": env.get_template("gait_table.c.j2").render(**ctx),
    }


def _chunks(values: Sequence[Any], per_line: int = 16) -> list[str]:
    """Comma-joined lines of at most per_line values (for C initialisers)."""
    vals = [str(v) for v in values]
    return [", ".join(vals[i : i + per_line]) for i in range(0, len(vals), per_line)]
