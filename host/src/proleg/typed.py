"""Numbers as a person types them: on a command line, in a ``--condition``, a tracker's CSV
cell, a transition CSV's reward and duration, a Δx at the manual-entry prompt.

Python's ``float()`` and ``int()`` take digit separators (PEP 515): ``"1_0"`` reads as 10.
From a person that is a typo, not a number, and it went into a run or a trial log without a
word. Each reader here is the builtin but for that, raising ``ValueError`` for it as for any
other text that is no number; the caller says what it expected.
"""

from __future__ import annotations


def typed_float(text: str) -> float:
    """``float(text)``, but ``"1_0"`` is ``ValueError``."""
    if "_" in text:
        raise ValueError(f"digit separator in {text!r}")
    return float(text)


def typed_int(text: str, base: int = 10) -> int:
    """``int(text, base)``, but ``"1_0"`` is ``ValueError``."""
    if "_" in text:
        raise ValueError(f"digit separator in {text!r}")
    return int(text, base)
