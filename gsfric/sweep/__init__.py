"""Joint sizing at scale: load envelopes per joint over motions, a workspace and platform
variants (``gsfric sweep``).

>>> import gsfric.sweep
>>> result = gsfric.sweep.sweep("sizing", trajectories="runs/*.csv")   # doctest: +SKIP
"""

from gsfric.sweep.sweep import SweepResult, Workspace, load, sweep

__all__ = ["SweepResult", "Workspace", "load", "sweep"]
