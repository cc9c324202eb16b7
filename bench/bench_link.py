"""Link benchmark: frames/s decoded through the full client path from a recorded byte stream
(target ≥ 50,000 frames/s), and lost frames at 1 kHz telemetry over the simulator's pty.

    .venv/bin/python bench/bench_link.py [--frames N] [--pty-seconds S]

Prints a table and writes bench/results/link.json.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import threading
import time
from pathlib import Path

from proleg.link import CallbackListener, Notifier, RobotClient
from proleg.errors import LinkError
from proleg.link.base import Link
from proleg.protocol import Message, encode

RESULTS = Path(__file__).resolve().parent / "results" / "link.json"
TARGET_FPS = 50_000


class ReplayLink(Link):
    """Replays a recorded byte stream in fixed-size reads, like a fast serial port."""

    def __init__(self, data: bytes, chunk: int = 4096):
        self.data = data
        self.chunk = chunk
        self.pos = 0
        self.description = "replay"

    def write(self, data: bytes) -> None:
        pass

    def read(self, timeout: float) -> bytes:
        out = self.data[self.pos:self.pos + self.chunk]
        self.pos += len(out)
        return out

    def close(self) -> None:
        pass


def recorded_stream(frames: int, limbs: int = 2) -> bytes:
    parts = []
    for k in range(frames):
        parts.append(encode(Message.new(
            "TELEMETRY", seq=k & 0xFFFF, time_ms=k, measured=k % 4, target=(k + 1) % 4, gait=0, direction=0,
            step=k % 4, flags=1, psi=tuple((k * 7 + 100 * i) % 4000 for i in range(limbs)),
            duty=tuple(6000 if (k + i) % 3 else 0 for i in range(limbs)))))
        if k % 100 == 0:
            parts.append(encode(Message.new("EVENT", time_ms=k, kind=1, code=k % 4, detail=k % 4)))
    return b"".join(parts)


def bench_client(frames: int) -> dict:
    data = recorded_stream(frames)
    best = 0.0
    for _ in range(3):
        client = RobotClient(ReplayLink(data))
        n = 0
        t0 = time.perf_counter()
        while client.recv(0.0) is not None or client.link.pos < len(data):  # type: ignore[attr-defined]
            n += 1
        dt = time.perf_counter() - t0
        assert client.stats.telemetry == frames and client.stats.lost == 0
        best = max(best, client.stats.frames_ok / dt)
    return {"case": "client.recv from recorded stream", "frames": frames, "bytes": len(data),
            "frames_per_s": round(best), "target": TARGET_FPS, "ok": best >= TARGET_FPS}


def bench_notifier(frames: int) -> dict:
    data = recorded_stream(frames)
    client = RobotClient(ReplayLink(data))
    count = [0]
    done = threading.Event()

    def on(rx) -> None:
        count[0] += 1
        if count[0] == client.stats.frames_ok and client.link.pos >= len(data):  # type: ignore[attr-defined]
            done.set()

    t0 = time.perf_counter()
    notifier = Notifier(client, [CallbackListener(on)], poll_s=0.0)
    done.wait(60)
    dt = time.perf_counter() - t0
    notifier.stop()
    fps = count[0] / dt
    return {"case": "Notifier → listener from recorded stream", "frames": count[0], "frames_per_s": round(fps),
            "target": TARGET_FPS, "ok": fps >= TARGET_FPS}


def bench_pty(seconds: float, hz: int = 1000) -> dict:
    case = f"{hz} Hz telemetry over the simulator's pty"
    try:
        from proleg.link.serial_link import SerialLink
        from proleg.paths import robots_dir
        from proleg.robot import load_robot
        from proleg.sim.pty import PtyServer
        from proleg.sim.closed_loop import SimulatedRobot
    except ImportError as e:
        return {"case": case, "missing": str(e)}
    sim = SimulatedRobot(load_robot(robots_dir() / "paper-r1.toml"))
    server = PtyServer(sim, speed=1.0)
    stop = threading.Event()
    thread = threading.Thread(target=server.serve, kwargs={"should_stop": stop.is_set}, daemon=True)
    thread.start()
    try:
        with RobotClient(SerialLink(server.path)) as client:
            client.connect()
            client.set_telemetry_rate(hz)
            client.start(0, "+x")
            t_settle = time.monotonic()
            while time.monotonic() - t_settle < 0.3:  # settle at the new rate
                client.recv(0.05)
            first = client.stats.telemetry
            lost0 = client.stats.lost
            t0 = time.monotonic()
            while time.monotonic() - t0 < seconds:
                client.recv(0.05)
            dt = time.monotonic() - t0
            received = client.stats.telemetry - first
            lost = client.stats.lost - lost0
            fw = None
            try:
                client.set_telemetry_rate(50)
                client.stop()
                fw = client.firmware_stats().tx_dropped
            except LinkError:
                pass  # replies lost in the overrun too

    finally:
        stop.set()
        thread.join(5)
        server.close()
    return {"case": case, "seconds": round(dt, 2), "frames": received, "frames_per_s": round(received / dt),
            "lost": lost, "corrupt": client.stats.corrupt, "dropped_by_pty": server.bytes_dropped,
            "firmware_tx_dropped": fw, "ok": lost == 0 and client.stats.corrupt == 0 and received / dt > 0.9 * hz}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=200_000)
    ap.add_argument("--pty-seconds", type=float, default=5.0)
    args = ap.parse_args(argv)
    rows = [bench_client(args.frames), bench_notifier(args.frames), bench_pty(args.pty_seconds, 1000),
            bench_pty(args.pty_seconds, 250)]
    print(f"{'case':<44} {'frames':>8} {'frames/s':>10}  result")
    for r in rows:
        if "missing" in r:
            print(f"{r['case']:<44} {'-':>8} {'-':>10}  missing: {r['missing']}")
            continue
        extra = f"  lost {r['lost']}, corrupt {r['corrupt']}" if "lost" in r else ""
        print(f"{r['case']:<44} {r['frames']:>8} {r['frames_per_s']:>10}  {'ok' if r['ok'] else 'BELOW TARGET'}{extra}")
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    payload = {"python": sys.version.split()[0], "machine": platform.machine(), "cpus": os.cpu_count(), "results": rows}
    fd, tmp = tempfile.mkstemp(dir=RESULTS.parent, suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        json.dump(payload, f, indent=2)
        f.write("\n")
    os.replace(tmp, RESULTS)
    print(f"wrote {RESULTS}")
    return 0 if all(r.get("ok", True) for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
