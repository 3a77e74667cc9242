"""``gsfric.discover``: the one way into discovery, for the command line and for Python.

It takes a measured-data file, a DataFrame or a Motion with its forces, reads and checks the
inputs once, runs the workflow (``workflow.discover_motion``) and, given ``out``, writes the
outputs (``report.write``). ``gsfric discover`` calls it.

>>> import gsfric
>>> result = gsfric.discover("measured.csv", out="out")  # a file of yours  # doctest: +SKIP
>>> result                                              # a file of yours  # doctest: +SKIP
<Discovery explained: stribeck; residual 0.3573 N -> 0.09936 N RMS over 3800 samples, ...>
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Sequence

import numpy as np

from gsfric._checks import short
from gsfric.discovery.floor import read_noise_record
from gsfric.discovery.outcome import Discovery
from gsfric.discovery.report import write
from gsfric.discovery.rest import poses_from_columns
from gsfric.discovery.workflow import discover_motion
from gsfric.errors import InputError, InputTypeError
from gsfric.io.files import check_output_folder, check_outputs
from gsfric.io.logs import FORCES, LogFormat
from gsfric.io.readers import motion_from_frame, read_measured_columns
from gsfric.models import check_measured_forces, platform_from
from gsfric.platform.description import Platform
from gsfric.platform.usable import check_poses
from gsfric.signal.noise import ForceNoise
from gsfric.signal.savgol import DEFAULT_POLYORDER
from gsfric.trajectory import Motion

LENGTH_GAP = 1e-3
"""m RMS: leg lengths D1..D6 of a file further than this from those of its recorded poses
are noted (a geometry that is not the rig's; a millimetre is above any pose noise)."""


def discover(data, forces: np.ndarray | None = None,
             platform: Platform | str | os.PathLike[str] | None = None, *,
             out: str | os.PathLike[str] | None = None, seed: int = 0, progress: bool = False,
             figures: bool = True, force_noise: float | Sequence[float] | None = None,
             noise_record: str | os.PathLike[str] | None = None,
             log_format: LogFormat | None = None, **options) -> Discovery:
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
        ``gsfric discover --out``). Checked before the work starts: it must not be, or
        hold, an input.
    seed, progress : int, bool
        Seed of the block bootstrap; progress on stderr.
    figures : bool
        With ``out``: write the plots and report.html (the 3-D view).
    force_noise : float, sequence of 6 floats or ForceNoise, optional
        The load cells' noise, N (a sensor specification; ``--force-noise``), one value or
        one per leg. Default: ``noise_record``'s, else the ``force_noise`` of ``log_format``,
        else estimated from the force channels.
    noise_record : path-like, optional
        A recording at rest (CSV or Parquet with F1..F6): each force channel's standard
        deviation about its mean is the load cells' noise.
    log_format : LogFormat, optional
        The column map and units of a file written by another program.
    **options
        ``gsfric.discovery.Settings`` fields; ``poses`` (the recorded positions and
        rotations, see ``workflow.discover_motion``) with a Motion.

    Returns
    -------
    Discovery
        ``repr`` gives the answer in a line; ``summary()`` the content of summary.json;
        ``report()`` the Markdown report; ``written`` the files written to ``out``.

    Raises
    ------
    InputTypeError
        ``data`` of another type, an unknown option.
    InputError
        Unreadable data (naming the row and column), a Motion without forces of shape
        (N, 6), mostly unusable data, an output that is an input, a bad setting.
    OutputError
        An output could not be written (a full disk); nothing partial is left.

    Examples
    --------
    A record with a hidden low-speed friction peak (seconds to run, so not a doctest):

    >>> import gsfric
    >>> from gsfric.synth import synthesize
    >>> record = synthesize(effects=["stribeck:static=2,velocity=0.01"], noise=0.1, seed=1)
    >>> result = gsfric.discover(record.frame)        # takes seconds  # doctest: +SKIP
    >>> result.verdict, result.names                  # takes seconds  # doctest: +SKIP
    ('explained', ['stribeck'])
    >>> print(result.report().splitlines()[0])        # takes seconds  # doctest: +SKIP
    # Discrepancy discovery
    """
    is_file = isinstance(data, (str, os.PathLike))
    platform_file = platform if isinstance(platform, (str, os.PathLike)) else None
    if out is not None:
        check_outputs([out], {"platform": platform_file, "noise-record": noise_record,
                              "measured-data": data if is_file else None})
        check_output_folder(out)
    sensor = _force_noise(force_noise, noise_record, log_format)
    result = _discover_data(data, forces, platform, log_format,
                            dict(seed=seed, progress=progress, force_noise=sensor, **options))
    if out is not None:
        return dataclasses.replace(result, written=write(result, out, figures=figures))
    return result


def _discover_data(data, forces, platform, log_format: LogFormat | None, run: dict
                   ) -> Discovery:
    """The workflow on ``data`` as ``discover`` takes it (a file, a Motion with its forces or a
    DataFrame); ``run``: the workflow's keyword arguments."""
    if isinstance(data, (str, os.PathLike)):
        return _discover_file(data, platform, log_format, run)
    if isinstance(data, Motion):
        if forces is None:
            raise InputError("forces: required with a Motion (shape (N, 6), N)")
        return discover_motion(data, forces, platform, **run)
    if hasattr(data, "columns"):
        missing = [c for c in FORCES if c not in data.columns]
        if missing:
            raise InputError(f"DataFrame: missing force columns {', '.join(missing)}")
        return discover_motion(motion_from_frame(data), data[list(FORCES)].to_numpy(float),
                               platform, **run)
    raise InputTypeError(f"data: expected a file path, a DataFrame or a Motion, got "
                         f"{short(data)}")


def _discover_file(measured: str | os.PathLike[str], platform, log_format: LogFormat | None,
                   run: dict) -> Discovery:
    """The workflow on a measured-data file: its columns read with ``log_format``, the poses
    and forces checked against the platform."""
    model = platform_from(platform)
    motion, forces, lengths, columns = read_measured_columns(measured, None, DEFAULT_POLYORDER,
                                                          log_format)
    poses = poses_from_columns(columns)
    check_poses(model, *poses, motion.t, str(measured))
    check_measured_forces(model, motion, forces, str(measured))
    result = discover_motion(motion, forces, model, poses=poses, **run)
    notes = []
    how = motion.differentiation()
    if how is not None:
        notes.append(f"differentiation: {how.describe()}")
    if lengths is not None:
        gap = float(np.sqrt(np.mean((lengths - result.result_before.D) ** 2)))
        if gap > LENGTH_GAP:
            notes.append(
                f"the leg lengths D1..D6 in the file differ from those of the recorded pose by "
                f"{gap * 1e3:.3g} mm RMS: check the platform's geometry")
    given = str(platform) if isinstance(platform, (str, os.PathLike)) else ""
    return dataclasses.replace(result, source=str(measured), platform_source=given,
                               notes=[*result.notes, *notes])


def _force_noise(force_noise, noise_record, log_format) -> ForceNoise | None:
    """The load cells' noise the user gives, by precedence: ``force_noise``,
    ``noise_record``, the log format's ``force_noise``; None: estimated."""
    if isinstance(force_noise, ForceNoise):
        return force_noise
    if force_noise is not None:
        return ForceNoise.specified(force_noise)
    if noise_record is not None:
        return read_noise_record(noise_record, log_format)
    if log_format is not None and log_format.force_noise is not None:
        return ForceNoise.specified(log_format.force_noise, "force_noise of the column map")
    return None
