"""``gsfric.discover``: discovery on a measured-data file, a DataFrame or arrays, in one call.

>>> import gsfric
>>> result = gsfric.discover("measured.csv", out="out")  # a file of yours  # doctest: +SKIP
>>> result                                              # a file of yours  # doctest: +SKIP
<Discovery explained: stribeck; residual 0.3573 N -> 0.09936 N RMS over 3800 samples, ...>
"""

from __future__ import annotations

import os

import numpy as np

from gsfric.discovery.report import discover_file, write
from gsfric.discovery.results import Discovery
from gsfric.discovery.workflow import discover as discover_motion
from gsfric.errors import InputError
from gsfric.io.files import check_outputs
from gsfric.io.logs import FORCES
from gsfric.io.readers import motion_from_frame
from gsfric.platform.description import Platform
from gsfric.trajectory import Motion


def discover(data, forces: np.ndarray | None = None,
             platform: Platform | str | os.PathLike[str] | None = None, *,
             out: str | os.PathLike[str] | None = None, seed: int = 0, progress: bool = False,
             figures: bool = True, **options) -> Discovery:
    """Find which effects the model misses in measured data, fit them, measure the gap closed.

    Parameters
    ----------
    data : path-like, pandas.DataFrame or Motion
        A measured-data file (CSV or Parquet: trajectory columns plus F1..F6, as
        ``gsfric discover --measured``), a DataFrame with those columns, or a ``Motion``
        (then ``forces`` is required).
    forces : ndarray, shape (N, 6), optional
        Measured actuator forces F1..F6, N, when ``data`` is a Motion.
    platform : Platform or path-like, optional
        The current model (default: the reference platform).
    out : path-like, optional
        Also write summary.json, report.md, platform.toml and the plots there (as
        ``gsfric discover --out``).
    seed : int
        Seed of the block bootstrap.
    progress : bool
        Progress on stderr.
    figures : bool
        With ``out``: write the plots and report.html (the 3-D view).
    **options
        ``gsfric.discovery.Settings`` fields; ``log_format`` (a ``LogFormat``) for a file
        written by another program.

    Returns
    -------
    Discovery
        ``repr`` gives the answer in a line; ``summary()`` the content of summary.json;
        ``report()`` the Markdown report.

    Raises
    ------
    InputError
        Unreadable data, or a Motion without forces of shape (N, 6).

    Examples
    --------
    A record with a hidden low-speed friction peak (a run takes seconds, so it is not run as a
    doctest):

    >>> import gsfric
    >>> from gsfric.synth import synthesize
    >>> record = synthesize(effects=["stribeck:static=2,velocity=0.01"], noise=0.1, seed=1)
    >>> result = gsfric.discover(record.frame)        # takes seconds  # doctest: +SKIP
    >>> result.verdict, result.names                  # takes seconds  # doctest: +SKIP
    ('explained', ['stribeck'])
    >>> print(result.report().splitlines()[0])        # takes seconds  # doctest: +SKIP
    # Discrepancy discovery
    """
    platform_file = platform if isinstance(platform, (str, os.PathLike)) else None
    if out is not None:
        check_outputs([out], {"platform": platform_file,
                              **({"measured-data": data}
                                 if isinstance(data, (str, os.PathLike)) else {})})
    if isinstance(data, (str, os.PathLike)):
        result = discover_file(data, platform, seed=seed, progress=progress, **options)
    elif isinstance(data, Motion):
        if forces is None:
            raise InputError("forces: required with a Motion (shape (N, 6), N)")
        result = discover_motion(data, forces, platform, seed=seed, progress=progress,
                                 **options)
    elif hasattr(data, "columns"):
        missing = [c for c in FORCES if c not in data.columns]
        if missing:
            raise InputError(f"DataFrame: missing force columns {', '.join(missing)}")
        motion = motion_from_frame(data)
        result = discover_motion(motion, data[list(FORCES)].to_numpy(float), platform,
                                 seed=seed, progress=progress, **options)
    else:
        raise InputError(f"data: expected a file path, a DataFrame or a Motion, got "
                         f"{type(data).__name__}")
    if out is not None:
        write(result, out, figures=figures)
    return result
