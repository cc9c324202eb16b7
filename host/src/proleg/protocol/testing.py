"""Hypothesis strategies for protocol messages and damaged streams (test helper; needs
``hypothesis``).

``messages()`` draws any valid message of the definition (or of the given names), with
every field in its range, arrays up to the build's limits, text ASCII without NUL.
``corrupted_stream(msgs, data)`` frames them with some damaged and garbage in between.
"""

from __future__ import annotations

from hypothesis import strategies as st

from proleg.protocol.codec import Message, encode
from proleg.protocol.definition import BY_NAME, CHANNEL_CEILING, LIMB_CEILING, MESSAGES, TYPES, Field

_TEXT = st.characters(min_codepoint=1, max_codepoint=127)


def field_values(f: Field, max_limbs: int = LIMB_CEILING, max_channels: int = CHANNEL_CEILING) -> st.SearchStrategy:
    _, _, lo, hi = TYPES[f.type]
    if f.length is not None:
        return st.text(_TEXT, max_size=f.length - 1)
    scalar = st.integers(lo, hi)
    if f.is_array:
        return st.lists(scalar, max_size=f.resolved_max(max_limbs, max_channels)).map(tuple)
    return scalar


def messages(
    names: list[str] | None = None, max_limbs: int = LIMB_CEILING, max_channels: int = CHANNEL_CEILING
) -> st.SearchStrategy[Message]:
    specs = [BY_NAME[n] for n in names] if names else list(MESSAGES)
    return st.one_of(
        [
            st.fixed_dictionaries({f.name: field_values(f, max_limbs, max_channels) for f in spec.fields}).map(
                lambda fields, name=spec.name: Message(name, fields)
            )
            for spec in specs
        ]
    )


def _mutate(body: bytes, data) -> bytes:
    """Damage a frame body (without its delimiter) by a flip, insertion, deletion or replacement."""
    kind = data.draw(st.sampled_from(["flip", "insert", "delete", "replace", "truncate"]))
    b = bytearray(body)
    i = data.draw(st.integers(0, len(b) - 1))
    if kind == "flip":
        b[i] ^= data.draw(st.integers(1, 255))
    elif kind == "insert":
        b.insert(i, data.draw(st.integers(0, 255)))
    elif kind == "delete":
        del b[i]
    elif kind == "replace":
        b = bytearray(data.draw(st.binary(min_size=1, max_size=80)))
    else:
        del b[i:]
    return bytes(b)


def corrupted_stream(msgs: list[Message], data) -> tuple[bytes, list[Message]]:
    """A stream of the frames of msgs, some damaged, with garbage between some of them
    (always ending in 0x00 so it cannot swallow the next frame). Returns the stream and the
    untouched messages, in order."""
    parts: list[bytes] = []
    untouched: list[Message] = []
    for m in msgs:
        if data.draw(st.booleans()):
            parts.append(data.draw(st.binary(max_size=90)) + b"\0")
        frame = encode(m)
        if data.draw(st.booleans()):
            parts.append(_mutate(frame[:-1], data) + b"\0")
        else:
            parts.append(frame)
            untouched.append(m)
    return b"".join(parts), untouched


def is_subsequence(small: list[Message], big: list[Message]) -> bool:
    it = iter(big)
    return all(any(x == y for y in it) for x in small)


def nonempty_chunks(stream: bytes) -> int:
    return sum(1 for c in stream.split(b"\0")[:-1] if c)
