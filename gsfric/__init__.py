"""gsfric: reaction forces and friction in every joint of a Gough-Stewart platform.

The mechanics are derived symbolically (derive/), generated as C by CasADi (generated/) and
evaluated here over trajectories, with NumPy and the compiled functions only.

>>> import gsfric
>>> platform = gsfric.reference_platform()
>>> result = gsfric.evaluate(platform, gsfric.models.paper_motion())
>>> result.F.shape
(40, 6)
"""

from __future__ import annotations

__version__ = "0.1.0"

_LAZY = {
    "Platform": ("gsfric.platform", "Platform"),
    "Motion": ("gsfric.trajectory", "Motion"),
    "Evaluator": ("gsfric.evaluation", "Evaluator"),
    "Result": ("gsfric.evaluation", "Result"),
    "evaluate": ("gsfric.evaluation", "evaluate"),
    "reference_platform": ("gsfric.models", "reference_platform"),
    "paper_platform": ("gsfric.models", "paper_platform"),
    "GsfricError": ("gsfric.errors", "GsfricError"),
    "InputError": ("gsfric.errors", "InputError"),
}

__all__ = sorted(_LAZY) + ["models", "io", "sweep"]


def __getattr__(name):
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        return getattr(importlib.import_module(module), attr)
    if name in ("models", "io", "trajectory", "platform", "native", "catalog", "sweep"):
        import importlib

        return importlib.import_module(f"gsfric.{name}")
    raise AttributeError(f"module 'gsfric' has no attribute {name!r}")
