"""Joint sizing at scale: load envelopes per joint over motions, a workspace and platform
variants (``gsfric sweep``).

``sweep`` evaluates every *case* (a motion or the workspace, on one platform variant) and
reduces it, where it is evaluated, to a **load envelope per joint**: the largest |R_E|, |R_C|,
|M_C|, |R_3|, |M_3|, the actuator force range, the peak friction force and moments, the peak
friction power and the dissipated friction energy of each leg's three joints, each extreme with
the motion, step, time and pose where it occurs. Only these envelopes leave a worker.

Modules: ``workspace`` (poses and dynamic states, reachability), ``variants`` (platform
variants), ``envelope`` (what an envelope holds, its block-by-block reduction), ``blocks``
(block evaluation), ``tasks`` (a task and its evaluation on a worker), ``plan`` (cutting a
sweep into tasks), ``run`` (``sweep``: schedulers, resume, output folder), ``result``
(merging, summary, limits, ``SweepResult``, ``load``), ``plot``.

Threads: every task builds its own evaluators and buffers and evaluates in one thread
(``n_threads=1``); Dask workers are processes with one thread each (and one BLAS thread: Dask
sets ``OMP_NUM_THREADS=1`` and the like in the processes it starts), one per core.

>>> import gsfric.sweep
>>> result = gsfric.sweep.sweep("sizing",
...                             trajectories="runs/*.csv")  # files of yours  # doctest: +SKIP
"""

from gsfric.sweep.result import SweepResult, load
from gsfric.sweep.run import sweep
from gsfric.sweep.workspace import Workspace

__all__ = ["SweepResult", "Workspace", "load", "sweep"]
