"""Evaluation of a platform over a motion: actuator forces, joint reactions and friction, the
step flags, the breakdown of the forces into their parts, the output columns, and the
differentiation's uncertainty of the forces with the legs possibly at rest (``uncertainty``).

>>> from gsfric.evaluation import Evaluator, state_array
"""

from gsfric.evaluation.evaluator import Evaluator, evaluate_motion, state_array
from gsfric.evaluation.result import Result

__all__ = ["Evaluator", "Result", "evaluate_motion", "state_array"]
