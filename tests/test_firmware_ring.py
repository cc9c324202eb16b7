"""core/ring.h (the UART rings) against a bounded FIFO oracle.

The C ring is compiled for 8-bit indices (a 128-byte ring, as on the Nano) and for 16-bit
indices (256 bytes), and driven with random put/get sequences long enough to wrap the
free-running indices many times; every result must equal a Python deque of the same
capacity: a ring holds exactly its size, refuses the next byte, and gives bytes back in
order.
"""

from __future__ import annotations

import shutil
import subprocess
from collections import deque
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parents[1]
CC = shutil.which("cc")
pytestmark = pytest.mark.skipif(CC is None, reason="no host C compiler")
CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O1"]


@pytest.fixture(scope="module", params=[128, 256], ids=["8-bit", "16-bit"])
def ring(request, tmp_path_factory):
    size = request.param
    d = tmp_path_factory.mktemp(f"ring{size}")
    (d / "robot_config.h").write_text(f"#define CFG_UART_RX_BYTES {size}u\n#define CFG_UART_TX_BYTES 16u\n")
    exe = d / "test_ring"
    subprocess.run(
        [CC, *CFLAGS, f"-I{d}", f"-I{ROOT / 'firmware_templates' / 'core'}", str(ROOT / "tests" / "c" / "test_ring.c"),
         "-o", str(exe)],
        check=True, capture_output=True, text=True,
    )
    return exe, size


def oracle(ops: list[int | None], size: int) -> list[int]:
    q: deque[int] = deque()
    out = []
    for op in ops:
        if op is None:
            out.append(q.popleft() if q else -1)
        elif len(q) < size:
            q.append(op)
            out.append(0)
        else:
            out.append(-1)
    return out


def run(exe: Path, ops: list[int | None]) -> list[int]:
    text = "".join("g\n" if op is None else f"p {op}\n" for op in ops)
    proc = subprocess.run([str(exe)], input=text, capture_output=True, text=True, check=True)
    return [int(x) for x in proc.stdout.split()]


def test_a_ring_holds_exactly_its_size_then_refuses(ring):
    exe, size = ring
    ops: list[int | None] = [i & 0xFF for i in range(size + 3)] + [None] * (size + 2)
    assert run(exe, ops) == oracle(ops, size)
    assert run(exe, ops)[size] == -1


@settings(max_examples=20, deadline=None)
@given(data=st.data())
def test_random_puts_and_gets_match_a_bounded_fifo(ring, data):
    exe, size = ring
    # Runs of puts and gets, long enough to wrap 8-bit and 16-bit indices.
    runs = data.draw(st.lists(st.tuples(st.booleans(), st.integers(1, 2 * size)), min_size=1, max_size=40))
    ops: list[int | None] = []
    for put, n in runs:
        ops += [data.draw(st.integers(0, 255)) for _ in range(n)] if put else [None] * n
    assert run(exe, ops) == oracle(ops, size)


def test_order_and_capacity_hold_across_the_index_wrap(ring):
    exe, size = ring
    wrap = 1 << (8 if size <= 128 else 16)
    ops: list[int | None] = [7] * (size // 2)  # half full, then past the wrap one in, one out
    for i in range(wrap + size):
        ops += [i & 0xFF, None]
    ops += [1] * size + [None] * (size + 1)  # full again after the wrap, then drained
    assert run(exe, ops) == oracle(ops, size)
