"""Link protocol benchmark.

Host decode rate of TELEMETRY frames (2 limbs, 2 channels; also 8/8) from a byte stream
through ``FrameDecoder.feed`` in 4 KiB reads (like a serial port), best of 3; encode rate;
frame sizes; code size of the C runtime (host ``cc -Os``, and ``avr-gcc -Os
-mmcu=atmega328p`` when installed). Prints a table and writes bench/results/protocol.json.
Target: ≥ 100,000 decoded TELEMETRY frames/s.
"""

from __future__ import annotations

import json
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "host" / "src"))

from proleg.protocol import FrameDecoder, Message, encode, render_c  # noqa: E402
from proleg.protocol.definition import MESSAGES  # noqa: E402

TARGET = 100_000
N_FRAMES = 200_000
READ = 4096
CORE = ROOT / "firmware_templates" / "core"


def telemetry(seq: int, limbs: int, channels: int) -> Message:
    return Message.new(
        "TELEMETRY",
        seq=seq & 0xFFFF,
        time_ms=seq * 20,
        measured=seq & 3,
        target=(seq + 1) & 3,
        gait=0,
        direction=0,
        step=seq % 4,
        flags=1,
        psi=tuple((seq * 37 + i * 1000) % 9000 - 4500 for i in range(limbs)),
        duty=tuple((seq * 13 + i) % 10001 for i in range(channels)),
    )


def decode_rate(limbs: int, channels: int) -> dict[str, float]:
    frames = [encode(telemetry(i, limbs, channels)) for i in range(1000)]
    stream = b"".join(frames) * (N_FRAMES // 1000)
    best = float("inf")
    for _ in range(3):
        dec = FrameDecoder(max_limbs=limbs, max_channels=channels)
        t0 = time.perf_counter()
        n = 0
        for k in range(0, len(stream), READ):
            n += len(dec.feed(stream[k : k + READ]))
        best = min(best, time.perf_counter() - t0)
        assert n == N_FRAMES == dec.frames_ok, (n, dec.counters())
    return {
        "frames_per_s": N_FRAMES / best,
        "bytes_per_frame": len(stream) / N_FRAMES,
        "mbytes_per_s": len(stream) / best / 1e6,
    }


def encode_rate() -> float:
    msgs = [telemetry(i, 2, 2) for i in range(1000)]
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        for _ in range(50):
            for m in msgs:
                encode(m)
        best = min(best, time.perf_counter() - t0)
    return 50_000 / best


def c_sizes() -> dict[str, dict[str, int]]:
    """text/data/bss bytes per object of the C runtime (2 limbs, 2 channels build)."""
    out: dict[str, dict[str, int]] = {}
    compilers = [("host_cc_Os", "cc", "size", []), ("avr_atmega328p_Os", "avr-gcc", "avr-size", ["-mmcu=atmega328p"])]
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        for name, text in render_c(2, 2).items():
            (d / name).write_text(text)
        for f in ["proto.h", "proto.c", "cobs.h", "cobs.c", "crc16.h", "crc16.c"]:
            shutil.copy(CORE / f, d / f)
        for label, cc, size, extra in compilers:
            if shutil.which(cc) is None or shutil.which(size) is None:
                continue
            srcs = ["proto.c", "proto_gen.c", "cobs.c", "crc16.c"]
            subprocess.run([cc, "-std=c99", "-Os", *extra, "-c", *srcs], cwd=d, check=True)
            res = subprocess.run([size, *[s.replace(".c", ".o") for s in srcs]], cwd=d, capture_output=True, text=True)
            per: dict[str, int] = {}
            for line in res.stdout.splitlines()[1:]:
                parts = line.split()
                per[parts[5]] = int(parts[0]) + int(parts[1])  # flash = text + data
            per["total_flash"] = sum(per.values())
            out[label] = per
    return out


def main() -> int:
    results: dict[str, object] = {"target_frames_per_s": TARGET, "python": platform.python_version()}
    rows = []
    for limbs, channels in [(2, 2), (8, 8)]:
        r = decode_rate(limbs, channels)
        results[f"decode_telemetry_{limbs}x{channels}"] = r
        rows.append((f"decode TELEMETRY {limbs} limbs/{channels} ch", f"{r['frames_per_s']:,.0f} frames/s", f"{r['bytes_per_frame']:.0f} B/frame on wire"))
    enc = encode_rate()
    results["encode_telemetry_2x2_frames_per_s"] = enc
    rows.append(("encode TELEMETRY 2/2", f"{enc:,.0f} frames/s", ""))
    sizes = {m.name: {"max_2x2": m.max_frame(2, 2), "max_8x8": m.max_frame(8, 8)} for m in MESSAGES}
    results["frame_bytes_before_cobs"] = sizes
    big = max(sizes.items(), key=lambda kv: kv[1]["max_8x8"])
    rows.append(("largest frame (before COBS)", f"{big[0]}: {big[1]['max_8x8']} B", "limit 64 B"))
    cs = c_sizes()
    results["c_object_bytes_2x2"] = cs
    for label, per in cs.items():
        detail = ", ".join(f"{k} {v}" for k, v in per.items() if k != "total_flash")
        rows.append((f"C runtime flash ({label})", f"{per['total_flash']} B", detail))
    ok = results["decode_telemetry_2x2"]["frames_per_s"] >= TARGET  # type: ignore[index]
    results["meets_target"] = ok
    w = max(len(r[0]) for r in rows)
    w2 = max(len(r[1]) for r in rows)
    for a, b, c in rows:
        print(f"{a:<{w}}  {b:>{w2}}  {c}")
    print(f"target ≥ {TARGET:,} TELEMETRY frames/s: {'met' if ok else 'NOT met'}")
    out = ROOT / "bench" / "results" / "protocol.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=1, sort_keys=True) + "\n")
    print(f"wrote {out.relative_to(ROOT)}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
