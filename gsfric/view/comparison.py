"""Model against measurement in a 3-D view: the plots of a measured-data file's view
(``gsfric view``: measured and model forces, the residual) and of a discovery's
(``gsfric discover``'s report.html: the final model evaluated along the measured motion, with
the measured and model forces per leg, the residual before and after, and each named effect's
contribution).

``discovery_plots`` reads a ``gsfric.discovery.Discovery`` by its attributes (``forces``,
``forces_after``, ``residual_*``, ``result_before``, ``used``, ``effects``), so that this
package stays below the discovery's (docs/explanation/architecture.md).
"""

from __future__ import annotations

import numpy as np

from gsfric.view.data import DASHES, DEFAULT_PLOTS, Curve, Plot
from gsfric.view.frames import Frames


def _at(values, steps: np.ndarray) -> np.ndarray:
    """Rows ``steps`` of ``values`` (M, 6) as float; all NaN for ``values`` None."""
    if values is None:
        return np.full((len(steps), 6), np.nan)
    return np.asarray(values, float)[steps]


def measured_plots(frames: Frames) -> tuple[Plot, ...]:
    """The plots of a view with measured forces: ``F`` measured (solid) and of the model
    (dashed), the residual ``F_measured - F``, and the prismatic friction ``Ffr``, per leg, N;
    ``DEFAULT_PLOTS`` when no frame has a measured force (``frames.F_measured`` all NaN)."""
    measured = np.asarray(frames.F_measured, float)
    if not np.isfinite(measured).any():
        return DEFAULT_PLOTS
    return (Plot("actuator force F: measured, model", "N",
                 (Curve("measured", "F_measured"), Curve("model", "F", "dashed"))),
            Plot("residual F measured \u2212 F model", "N",
                 (Curve("residual", "F_measured", minus="F"),)),
            DEFAULT_PLOTS[1])


def discovery_plots(discovery, frames: Frames) -> tuple[Plot, ...]:
    """The plots of a discovery's view, at ``frames``.

    Parameters
    ----------
    discovery : gsfric.discovery.Discovery
        A finished discovery (``forces`` and ``forces_after`` set: ``gsfric.discover``'s).
    frames : Frames
        Frames of an evaluation of the used samples only, ``frames.step`` the samples' index
        in the measured data (from ``discovery.used.start`` to ``discovery.used.stop - 1``).

    Returns
    -------
    tuple of Plot
        ``F`` measured (solid), of the model as given (dotted) and of the final model
        (dashed), N; the residual ``F_measured - F_model`` of the model as given (dotted) and
        of the final one (solid) at every used sample, sliding or not, N; each named effect's
        contribution to ``F`` (absent without one), N.
    """
    used = discovery.used
    steps = np.asarray(frames.step, np.int64) - used.start
    measured = _at(discovery.forces, steps)
    before = np.asarray(discovery.result_before.F, float)[used][steps]
    after = _at(discovery.forces_after, steps)
    plots = [
        Plot("actuator force F: measured, model as given, final model", "N",
             (Curve("measured", measured), Curve("as given", before, "dotted"),
              Curve("final", after, "dashed"))),
        Plot("residual F measured \u2212 F model", "N",
             (Curve("as given", measured - before, "dotted"),
              Curve("final", measured - after))),
    ]
    named = [f for f in discovery.effects if f.contribution is not None]
    if named:
        plots.append(Plot("contribution to F of " + ", ".join(f.name for f in named), "N",
                          tuple(Curve(f.name, _at(f.contribution, steps),
                                      DASHES[k % len(DASHES)])
                                for k, f in enumerate(named))))
    return tuple(plots)
