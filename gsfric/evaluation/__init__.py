"""Evaluation of a platform over a motion: actuator forces, joint reactions and friction, the
step flags, the breakdown of the forces into their parts, and the output columns.

>>> from gsfric.evaluation import Evaluator, state_array
"""

from gsfric.evaluation.evaluator import Evaluator, Result, evaluate, state_array

__all__ = ["Evaluator", "Result", "evaluate", "state_array"]
