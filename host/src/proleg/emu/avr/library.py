"""The avr-emu harness library: SOURCES (harness.c and its parts) + the shared MPU-6050 models, compiled
with the host's C compiler against libsimavr (Debian ``libsimavr-dev``) on first use and
cached under ``$PROLEG_CACHE/avr-emu`` (default ``~/.cache/proleg/avr-emu``), keyed by
the sources, the flags and the simavr version.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

from ...errors import SimError
from ...paths import cache_dir, templates_dir

HERE = Path(__file__).resolve().parent
SOURCES = ("harness.c", "uart.c", "pwm.c", "skips.c", "twi.c", "i2cbus.c", "boot.c")
HEADERS = ("harness.h",)
#: host-sim's device models the bus shares (firmware_templates/hal/sim)
MODEL_FILES = ("sim_mpu6050.c", "sim_mpu6050.h", "sim_tca9548a.c", "sim_tca9548a.h")
SIMAVR_INCLUDE = Path("/usr/include/simavr")
CFLAGS = ("-std=gnu99", "-O2", "-fPIC", "-shared", "-fvisibility=hidden", "-Wall", "-Wextra", "-Werror")
LIBS = ("-lsimavr", "-lm")
PACKAGES = "simavr libsimavr-dev"


def cache_root() -> Path:
    return cache_dir("avr-emu")


def imu_model_dir() -> Path:
    """Where the shared MPU-6050 model (sim_mpu6050.[ch], also used by host-sim) lives."""
    tdir = templates_dir()
    for candidate in [tdir / "hal" / "sim", *sorted(p.parent for p in tdir.rglob("sim_mpu6050.c"))]:
        if (candidate / "sim_mpu6050.c").exists() and (candidate / "sim_mpu6050.h").exists():
            return candidate
    raise SimError(f"{tdir}: no sim_mpu6050.c (the MPU-6050 model the emulated boards share)")


def _simavr_include() -> Path:
    try:
        out = subprocess.run(
            ["pkg-config", "--cflags-only-I", "simavr"], capture_output=True, text=True, check=False
        ).stdout.split()
        for flag in out:
            if flag.startswith("-I") and (Path(flag[2:]) / "sim_avr.h").exists():
                return Path(flag[2:])
    except OSError:
        pass
    if (SIMAVR_INCLUDE / "sim_avr.h").exists():
        return SIMAVR_INCLUDE
    raise SimError(
        f"simavr headers not found ({SIMAVR_INCLUDE}/sim_avr.h): install the Debian packages {PACKAGES} "
        "(`make toolchains` does it)"
    )


def _simavr_version() -> str:
    try:
        proc = subprocess.run(["pkg-config", "--modversion", "simavr"], capture_output=True, text=True, check=False)
        return proc.stdout.strip() or "unknown"
    except OSError:
        return "unknown"


def harness_library() -> Path:
    """Path of the compiled harness (built now if the cache has no copy for these sources)."""
    include = _simavr_include()
    model = imu_model_dir()
    cc = os.environ.get("CC", "cc")
    files = [HERE / s for s in SOURCES + HEADERS] + [model / f for f in MODEL_FILES]
    digest = hashlib.sha256()
    for f in files:
        digest.update(f.name.encode() + b"\0" + f.read_bytes() + b"\0")
    digest.update(" ".join((cc, *CFLAGS, *LIBS, _simavr_version())).encode())
    out = cache_root() / f"harness-{digest.hexdigest()[:16]}.so"
    if out.exists():
        return out
    if shutil.which(cc) is None:
        raise SimError(f"C compiler {cc!r} not found: install the Debian package gcc (`make toolchains` does it)")
    out.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".harness-", suffix=".so", dir=out.parent)
    os.close(fd)
    cmd = [
        cc,
        *CFLAGS,
        "-isystem",
        str(include),
        "-I",
        str(model),
        *(str(HERE / s) for s in SOURCES),
        *(str(model / f) for f in MODEL_FILES if f.endswith(".c")),
        "-o",
        tmp,
        *LIBS,
    ]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        os.unlink(tmp)
        lines = (proc.stdout + proc.stderr).strip().splitlines()
        hint = f" (is {PACKAGES} installed?)" if "simavr" in proc.stderr else ""
        raise SimError("compiling the avr-emu harness failed" + hint + ":\n  " + "\n  ".join(lines[-12:]))
    os.replace(tmp, out)  # atomic: concurrent builders all end with a complete file
    return out
