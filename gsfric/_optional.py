"""Heavy dependencies loaded on first use (tables, SciPy, plots, Parquet, Dask, Jupyter display):
``optional("pyarrow.parquet")``.

They are installed with gsfric, but loading them costs time that most calls never need: the
control loop (``from gsfric.evaluation import Evaluator``, ``Evaluator.forces``) reads no table
and filters no signal, a CSV run does not read Parquet, only a report plots. pandas costs about
0.2 s to import and SciPy's rotations and splines about 0.2 s more. Every such import goes through
``optional``, so that the modules that use them can be imported quickly and a missing or broken
installation is reported in one line naming the package.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from gsfric.errors import GsfricError

HEAVY = ("pandas", "scipy", "matplotlib", "pyarrow", "dask", "distributed", "casadi",
         "IPython")
"""The packages loaded through ``optional``."""


def optional(name: str) -> ModuleType:
    """The module ``name`` (e.g. "matplotlib.figure"), imported on first use.

    Raises
    ------
    GsfricError
        The package cannot be imported (one line naming it and the reason).
    """
    package = name.split(".")[0]
    if package not in HEAVY:
        raise ValueError(f"optional: {package!r} is not one of {HEAVY}; import it at the top")
    try:
        return importlib.import_module(name)
    except ImportError as error:
        raise GsfricError(f"{name} is needed here and cannot be imported ({error}); "
                          f"pip install {package}") from None
