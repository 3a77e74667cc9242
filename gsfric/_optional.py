"""Heavy dependencies loaded on first use (plots, Parquet, Dask): ``optional("pyarrow.parquet")``.

They are installed with gsfric, but loading them costs time that most calls never need: the
control loop does not plot, a CSV run does not read Parquet. Every such import goes through
``optional``, so that the modules that use them can be imported quickly and a missing or broken
installation is reported in one line naming the package.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from gsfric.errors import GsfricError

HEAVY = ("matplotlib", "pyarrow", "dask", "distributed", "casadi")
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
