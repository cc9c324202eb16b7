"""Which piece an exploration runs next: link-free planning for ``runner.Explorer``.

Contract. ``plan_piece(table, start, demand, limits, seed)`` returns a loadable piece from
``start`` (the state the robot is measured in) that makes at least one transition still to do
(``demand[k] > 0``, over ``table``'s transitions), or None when no piece within ``limits``
reaches one (the caller names them and says why).

The first piece of a random tour may make none of what is still to do (only transitions
that balance or join the tour): ``plan_piece`` tries ``PLAN_TRIES`` tours, then takes the
shortest way to a transition still to do that fits in one piece. A tour is planned for at
most ``PLAN_DEMAND_CAP`` trials of a transition: only its first piece is used. Same ``seed``,
same piece (each try's tour is seeded ``seed * PLAN_TRIES + try``); None, a fresh draw.
"""

from __future__ import annotations

import numpy as np

from ..transitions import TransitionTable
from .pieces import Piece, PieceLimits, split
from .tours import _bfs_path, exploration, successors

#: random tours ``plan_piece`` tries for a first piece that makes progress
PLAN_TRIES = 8
#: the most trials of one transition a piece's tour is planned for: only the tour's first piece
#: is used, and the tour is planned again for the next, so a tour of the whole demand cost its
#: length at every piece (--repeats 999999999 on R1 planned a tour of 12e9 transitions, 10 GB
#: in 16 s and no trial made; --more's 100,000 extra trials each took 10 s a piece). Tours of
#: every run asking at most this many are planned as before.
PLAN_DEMAND_CAP = 100


def plan_piece(t: TransitionTable, start: int, demand: np.ndarray, limits: PieceLimits,
               seed: int | None = None) -> Piece | None:
    """The first piece of a random tour from ``start`` that makes at least one transition
    still to do (a few tours are tried); else the shortest way to one of them; None when no
    piece within ``limits`` reaches any."""
    demand = np.minimum(demand, PLAN_DEMAND_CAP)
    for attempt in range(PLAN_TRIES):
        plan = exploration(t, demand=demand, start=start, seed=None if seed is None else seed * PLAN_TRIES + attempt)
        tour = next((x for x in plan.tours if x.states[0] == start), None)
        if tour is None:
            break
        piece = split(t, tour.states, limits)[0]
        if piece.loadable and any(demand[t.lookup(a, b)] > 0 for a, b in piece.transitions):
            return piece
    succ = successors(t)
    best: Piece | None = None
    for (a, b), k in zip(zip(t.src.tolist(), t.dst.tolist()), demand.tolist()):
        way = _bfs_path(t.n_states, succ, start, a) if k > 0 else None
        if way is None:
            continue
        pieces = split(t, way + [b], limits)
        if len(pieces) == 1 and pieces[0].loadable and (best is None or len(pieces[0].states) < len(best.states)):
            best = pieces[0]
    return best
