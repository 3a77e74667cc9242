"""The result of an evaluation: named arrays with the step as the leading axis, and their tables.

Detail outputs (``DETAILS``: R_3 and M_3 in the leg frames, the parts of the prismatic
friction, the bushings' normal forces, the coupled solve's last change) are not kept by the
evaluation: a Result computes them, all at once, in one more compiled pass over its motion the
first time one of them is read (``Result.arrays`` holds them from then on). The evaluation then
writes 229 of the 313 values per step (1.8 kB instead of 2.5 kB).
"""

from __future__ import annotations

from collections.abc import Callable, MutableMapping
from dataclasses import dataclass, field

import numpy as np

from gsfric._optional import optional
from gsfric.compiled.manifest import function
from gsfric.errors import GsfricError
from gsfric.evaluation.breakdown import frame as breakdown_frame
from gsfric.evaluation.breakdown import parts as breakdown_parts
from gsfric.evaluation.columns import annotate, plan
from gsfric.evaluation.flags import FLAG_NAMES, flag_message
from gsfric.evaluation.peaks import Peaks
from gsfric.view import FrameCollector, page, write_page
from gsfric.view import show as show_page

DETAILS = ("R_3_leg", "M_3_leg", "coupling_change", "Ffr_viscous", "Ffr_coulomb",
           "Ffr_bushing", "Ffr_seal", "Ffr_effects", "N_bushing")
"""Outputs computed on first access (see the module's docstring): copies of other outputs in
another frame, and the parts of sums that are kept (``Ffr``)."""


@dataclass(frozen=True)
class Pending:
    """The detail outputs of a Result still to compute, and what computes them.

    Attributes
    ----------
    names : tuple of str
        The detail outputs (``DETAILS``) of the evaluated function, in its order.
    compute : callable
        ``compute(names) -> {name: ndarray (N, ...)}``: the outputs at every step of the
        evaluated motion (non-finite steps NaN, as in the first pass). Picklable (a Result
        travels between processes).
    """

    names: tuple[str, ...]
    compute: Callable[[tuple[str, ...]], dict[str, np.ndarray]]


class Outputs(MutableMapping):
    """The named arrays of a Result: those the evaluation kept and, on first access to any of
    them, the detail outputs (``DETAILS``), computed together in one more compiled pass over
    the motion (non-finite steps NaN, as in the first pass). Iteration lists both (the kept
    ones first); ``kept()`` gives the arrays held now, without computing.
    """

    def __init__(self, arrays: dict, later: Pending | None = None) -> None:
        self._arrays = dict(arrays)
        self._later = later

    def _pending(self) -> tuple:
        return () if self._later is None else self._later.names

    def __getitem__(self, key):
        try:
            return self._arrays[key]
        except KeyError:
            if key not in self._pending():
                raise
        self._arrays.update(self._later.compute(self._later.names))
        self._later = None
        return self._arrays[key]

    def __setitem__(self, key, value) -> None:
        self._arrays[key] = value

    def __delitem__(self, key) -> None:
        if key in self._pending():
            self[key]
        del self._arrays[key]

    def __iter__(self):
        yield from self._arrays
        yield from (k for k in self._pending() if k not in self._arrays)

    def __len__(self) -> int:
        return len(self._arrays) + sum(k not in self._arrays for k in self._pending())

    def __contains__(self, key) -> bool:
        return key in self._arrays or key in self._pending()

    def kept(self) -> dict[str, np.ndarray]:
        """The arrays held now (no computation)."""
        return dict(self._arrays)


@dataclass
class Result:
    """Named arrays of one evaluation, step as the leading axis.

    The outputs are attributes, for N steps in SI units and the base frame: ``t`` (N,) s;
    ``F``, ``F0`` (N, 6) N; ``R_E``, ``R_C``, ``R_3`` (N, 6, 3) N; ``M_C`` (N, 6) N m;
    ``M_3`` (N, 6, 3) N m; ``MfrE``, ``MfrC`` (N, 6, 3) N m; ``Ffr`` (N, 6) N; the paper's
    signed scalars ``MfrE_s``, ``MfrC_s`` (N, 6) N m and ``Ffr_s`` (N, 6) N; ``D``, ``D_dot``
    (N, 6); ``u``, ``omega_leg``, ``omega_rel``, ``R_3_leg``, ``M_3_leg`` (N, 6, 3); ``s2``
    (N, 6); ``flag`` (N,) int. Every output column with its meaning is listed by
    ``gsfric.columns``.

    Attributes
    ----------
    F : ndarray, shape (N, 6)
        Actuator force of each leg with friction and effects, N; positive pushes the platform
        away from the base.
    R_E : ndarray, shape (N, 6, 3)
        Force of each leg on the platform at its spherical joint E_i, base frame, N.
    flag : ndarray of int, shape (N,)
        0 for a sound step, else the sum of the flag bits (``gsfric.evaluation.flags``).
    sigma_F : ndarray, shape (N, 6)
        One standard deviation of each actuator force from the differentiation of the
        recorded poses, N (``gsfric.evaluation.uncertainty.force_sigma``): present for a
        motion with ``Motion.rate_uncertainty()`` (made by ``Motion.from_samples`` or read
        from a file) in the kinematic mode, absent otherwise.
    rest : ndarray, shape (N,)
        With ``sigma_F``: the legs possibly at rest (speed within ``REST_BAND`` standard
        deviations of zero), the sum of ``2**(i - 1)`` over those legs i (1..6); their friction
        is bounded by the Coulomb level rather than the sliding value in ``F``.

    Examples
    --------
    >>> import numpy as np, gsfric
    >>> result = gsfric.evaluate(gsfric.reference_platform(),
    ...                          gsfric.models.sinusoidal(np.linspace(0, 1, 101)))
    >>> result.F.shape, result.R_E.shape, result.to_frame().attrs["units"]["F1"]
    ((101, 6), (101, 6, 3), 'N')
    """

    t: np.ndarray
    arrays: dict[str, np.ndarray]
    flag: np.ndarray
    mode: str = "kinematic"
    notes: list[str] = field(default_factory=list)
    source: tuple | None = field(default=None, repr=False)   # (platform, motion) evaluated
    runner: Callable | None = field(default=None, repr=False)
    """``runner(platform, motion) -> Result``: evaluates the platform variants of ``breakdown``
    (an Evaluator's evaluation without reporting flags)."""

    def breakdown(self):
        """F per leg split into inertia, gravity, payload, joint friction carried, prismatic
        friction by kind and effects (``gsfric.evaluation.breakdown``; kinematic mode).

        Returns
        -------
        pandas.DataFrame
            Index ``step``; columns (part, leg), legs 1..6, N, for each part and ``F``, their
            sum, and ``t``, s: ``frame["gravity"]`` is one part's (N, 6) table.
            ``attrs["units"]`` gives each part's unit.
        """
        if self.source is None or self.runner is None or self.mode != "kinematic":
            raise GsfricError("breakdown: needs a kinematic-mode result of Evaluator.evaluate")
        platform, motion = self.source
        return breakdown_frame(self.t, breakdown_parts(self, self.runner, platform, motion))

    def __getattr__(self, name):
        arrays = self.__dict__.get("arrays", {})
        if name in arrays:
            return arrays[name]
        raise AttributeError(name)

    def __len__(self) -> int:
        return len(self.t)

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(self.__dict__.get("arrays", {})))

    def __repr__(self) -> str:
        n = len(self.t)
        span = f"t = {self.t[0]:.6g}..{self.t[-1]:.6g} s" if n else "no steps"
        flagged = int(np.count_nonzero(self.flag))
        names = ", ".join(sorted(self.arrays))
        return (f"<Result: {n} steps, {span}, mode {self.mode!r}, {flagged} flagged; "
                f"arrays {names}>")

    def summary(self) -> str:
        """The long form of the repr: the table of peaks per leg (``gsfric.evaluation.peaks``:
        the largest magnitudes of ``F``, ``Ffr`` (the friction that loads the actuators, the
        file's ``Ffr1..Ffr6``), ``R_E``, ``R_C`` (N) and ``M_C`` (N m) over the sound steps,
        each with its time from the first step, s), and what the flags say. ``gsfric simulate``
        prints the same table."""
        peaks = Peaks()
        peaks.add(self.t, self.arrays, self.flag)
        message = flag_message(self.flag)
        return "\n".join([repr(self), peaks.table(),
                          f"flags: {message}" if message else "flags: none"])

    def flagged(self) -> np.ndarray:
        """Indices of the steps with a non-zero flag."""
        return np.flatnonzero(self.flag)

    def to_legs_frame(self):
        """Per-joint values as a DataFrame indexed by (step, leg), leg 1..6.

        Columns: every per-leg array of the result, a vector ``(N, 6, 3)`` as three columns
        ``name_x, name_y, name_z`` (base frame), a scalar ``(N, 6)`` as one column; plus ``t``.
        ``attrs["units"]`` holds each column's unit (from the manifest).

        Returns
        -------
        pandas.DataFrame
            6 N rows, MultiIndex levels ``step`` (0..N-1) and ``leg`` (1..6).
        """
        pd = optional("pandas")
        n = len(self.t)
        index = pd.MultiIndex.from_product([np.arange(n), np.arange(1, 7)],
                                           names=["step", "leg"])
        known = {o["name"]: o.get("unit", "") for o in function("eval")["outputs"]}
        cols: dict[str, np.ndarray] = {"t": np.repeat(self.t, 6)}
        units = {"t": "s"}
        for name, values in self.arrays.items():
            if values.shape[1:2] != (6,):
                continue
            if values.ndim == 2:
                cols[name] = values.reshape(-1)
                units[name] = known.get(name, "")
            elif values.ndim == 3 and values.shape[2] == 3:
                for j, axis in enumerate("xyz"):
                    cols[f"{name}_{axis}"] = values[:, :, j].reshape(-1)
                    units[f"{name}_{axis}"] = known.get(name, "")
        frame = pd.DataFrame(cols, index=index)
        frame.attrs["units"] = units
        return frame

    def to_xarray(self):
        """The per-joint values as an ``xarray.Dataset`` (dims ``step``, ``leg``); needs xarray.

        The variables and units (``attrs["units"]`` of each) of ``to_legs_frame``.
        """
        frame = self.to_legs_frame()
        try:
            data = frame.to_xarray()
        except ImportError:
            raise GsfricError("Result.to_xarray needs xarray (pip install xarray); "
                              "Result.to_legs_frame gives the same as a DataFrame") from None
        for name, unit in frame.attrs["units"].items():
            data[name].attrs["units"] = unit
        return data

    def _view_page(self, fps: float, title: str | None) -> str:
        """The HTML text of ``to_html`` and ``show``."""
        if self.source is None:
            raise GsfricError("to_html: needs a Result of Evaluator.evaluate or gsfric.evaluate "
                              "(it draws the platform and motion that were evaluated)")
        if not len(self.t):
            raise GsfricError("to_html: the result has no steps")
        platform = self.source[0]
        frames = FrameCollector(fps=fps).add_result(self).finish()
        return page(frames, platform, title=title if title is not None else
                    f"gsfric: {len(self.t)} steps, {self.mode} mode", flag_names=FLAG_NAMES,
                    steps=len(self.t))

    def to_html(self, path, *, fps: float = 60.0, title: str | None = None):
        """Write a 3-D view of the evaluation to one self-contained HTML page.

        The page (no network, no other file) draws the base and the platform, the legs
        coloured by ``F``, the reactions ``R_E`` and ``R_C`` as arrows, the joint friction
        (``|MfrE|``, ``|MfrC|``, ``|Ffr|``) as colours and the flagged steps, with plots of
        ``F`` and ``Ffr`` per leg, playback controls, and each leg's values on hover or click.
        ``#t=SECONDS`` at the end of its address opens it paused at that time.

        Parameters
        ----------
        path : path-like
            The ``.html`` file; written to a temporary name and renamed when complete.
        fps : float
            Frames per second of motion time kept for playback (at most
            ``gsfric.view.MAX_FRAMES`` frames in all); values are quantised to int16
            (``gsfric.view.data``: error at most 1.5e-5 of each array's largest magnitude).
        title : str, optional
            The page's title.

        Returns
        -------
        pathlib.Path
            ``path``.

        Examples
        --------
        >>> import numpy as np, gsfric, tempfile, pathlib
        >>> result = gsfric.evaluate(gsfric.reference_platform(),
        ...                          gsfric.models.sinusoidal(np.linspace(0, 2, 401)))
        >>> out = result.to_html(pathlib.Path(tempfile.mkdtemp()) / "view.html")
        >>> out.read_text().startswith("<!DOCTYPE html>")
        True
        """
        return write_page(path, self._view_page(fps, title))

    def show(self, *, fps: float = 60.0, title: str | None = None, height: int = 760) -> None:
        """Show the 3-D view of ``to_html`` in a Jupyter output cell (an iframe holding the
        page; needs IPython). ``height`` is the cell's, in CSS pixels."""
        show_page(self._view_page(fps, title), height)

    def to_frame(self):
        """A pandas DataFrame with the columns of ``gsfric simulate``, one row per step.

        ``attrs["units"]`` maps every column to its unit and ``attrs["descriptions"]`` to its
        meaning and sign convention (``gsfric.columns``; ``gsfric columns`` lists them).
        """
        pd = optional("pandas")
        n = len(self.t)
        cols = {"t": self.t}
        for column, key, index, _ in plan():
            values = self.arrays.get(key)
            if values is not None:
                cols[column] = values.reshape(n, -1)[:, index]
        cols["flag"] = self.flag
        return annotate(pd.DataFrame(cols))
