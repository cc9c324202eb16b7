"""The gait engine: optimal gaits of a transition table, and scores of typed sequences.

    optimal_gaits(table, objective="total"|"rate"|"speed", direction="+x"|"-x",
                  max_transitions=None) -> GaitResult
    evaluate_sequence(table, states) -> Gait

See ``optimal.py`` for which algorithm answers which objective.
"""

from .evaluate import evaluate_sequence
from .optimal import optimal_gaits
from .result import MAX_TIES, RELATIVE_TOLERANCE, Gait, GaitResult

__all__ = ["Gait", "GaitResult", "MAX_TIES", "RELATIVE_TOLERANCE", "evaluate_sequence", "optimal_gaits"]
