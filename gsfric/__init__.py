"""gsfric: reaction forces and friction in every joint of a Gough-Stewart platform.

The mechanics are derived symbolically (derive/), generated as C by CasADi (generated/) and
evaluated here over trajectories, with NumPy and the compiled functions only.

>>> import gsfric
>>> platform = gsfric.reference_platform()
>>> result = gsfric.evaluate(platform, gsfric.models.paper_motion())
>>> result.F.shape
(40, 6)

Main names: ``evaluate`` (a platform over a motion -> ``Result``), ``discover`` (measured
data -> ``Discovery``: which effect the model misses), ``identify`` (measured data ->
``Identification``: the platform's parameters with their standard deviations), ``Platform``
(``reference_platform()``, ``paper_platform()``, ``Platform.from_toml``), ``Motion`` (and
``gsfric.models`` for reference motions), ``read_trajectory`` / ``read_measured`` with a
``LogFormat`` for other programs' logs, ``Evaluator`` for repeated calls, ``columns`` for the
units and meaning of every output column. ``help(gsfric.evaluate)`` and the README tell more.
"""

import importlib as _importlib

__version__ = "0.1.0"

_LAZY = {
    "Platform": ("gsfric.platform.description", "Platform"),
    "Motion": ("gsfric.trajectory", "Motion"),
    "Evaluator": ("gsfric.evaluation.evaluator", "Evaluator"),
    "Result": ("gsfric.evaluation.result", "Result"),
    "evaluate": ("gsfric.simulate.api", "evaluate"),
    "discover": ("gsfric.discovery.api", "discover"),
    "Discovery": ("gsfric.discovery.outcome", "Discovery"),
    "identify": ("gsfric.identification.fit", "identify"),
    "Identification": ("gsfric.identification.results", "Identification"),
    "reference_platform": ("gsfric.models", "reference_platform"),
    "paper_platform": ("gsfric.models", "paper_platform"),
    "LogFormat": ("gsfric.io.logs", "LogFormat"),
    "read_trajectory": ("gsfric.io.readers", "read_trajectory"),
    "read_measured": ("gsfric.io.readers", "read_measured"),
    "GsfricError": ("gsfric.errors", "GsfricError"),
    "InputError": ("gsfric.errors", "InputError"),
}
"""Public names, imported on first use (``import gsfric`` stays fast: no NumPy, no compiler)."""

_MODULES = {"models": "gsfric.models", "io": "gsfric.io", "columns": "gsfric.evaluation.columns",
            "catalog": "gsfric.platform.catalog", "trajectory": "gsfric.trajectory",
            "platform": "gsfric.platform", "evaluation": "gsfric.evaluation",
            "signal": "gsfric.signal", "simulate": "gsfric.simulate", "synth": "gsfric.synth",
            "discovery": "gsfric.discovery", "identification": "gsfric.identification",
            "sweep": "gsfric.sweep", "paper": "gsfric.paper"}
"""Modules reachable as attributes, e.g. ``gsfric.models.sinusoidal``."""

__all__ = sorted(_LAZY) + ["columns", "io", "models", "sweep"]


def __getattr__(name):
    if name in _LAZY:
        module, attr = _LAZY[name]
        value = getattr(_importlib.import_module(module), attr)
        globals()[name] = value          # later look-ups skip this function
        return value
    if name in _MODULES:
        return _importlib.import_module(_MODULES[name])
    raise AttributeError(f"module 'gsfric' has no attribute {name!r}")


def __dir__():
    """Every public name, loaded or not (for ``dir(gsfric)`` and tab completion)."""
    return sorted({"__version__", *_LAZY, *_MODULES})
