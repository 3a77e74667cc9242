"""The workflow's first stage: the refit of the model's own parameters.

The model's own parameters (``REFIT``: prismatic friction coefficients, payload mass, plus the
parameters of any effect the model already has) are refitted within their plausible ranges
before any candidate is tested. A refit that would need an implausible value is reported as
such; it is held at the range's edge and the rest of the gap is left to the candidates
(``rounds``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from gsfric.discovery import lackfit
from gsfric.discovery import statistics as st
from gsfric.discovery.evidence import Evidence, Rule, accept
from gsfric.discovery.refine import Refined, refine
from gsfric.discovery.residuals import Problem
from gsfric.discovery.results import RefitParameter, RefitReport, RefitTest
from gsfric.discovery.selection import low_band_of


@dataclass(frozen=True)
class Refit:
    """What the refit of the model's own parameters produced.

    Attributes
    ----------
    fit : Refined
        The refitted parameters (``Problem.refit_names([])``), the residual (M, 6) and the
        Jacobian there: where the first round starts.
    residual_before : ndarray, shape (M, 6)
        Residual of the model as given over the used samples, N (zero at the pairs not known
        to slide).
    rms_refit : float
        RMS of the refitted residual over the sliding pairs, N.
    report : RefitReport
        Model, refitted and unbounded values, plausible ranges and the refit's test
        (``Discovery.refit``).
    notes : tuple of str
        A note for each parameter whose unbounded refit is implausible.
    """

    fit: Refined
    residual_before: np.ndarray
    rms_refit: float
    report: RefitReport
    notes: tuple[str, ...]


def refit_own_parameters(problem: Problem, theta0: np.ndarray) -> Refit:
    """The refit of the model's own parameters from the model's values ``theta0``
    (n_theta,): within their plausible ranges by Gauss-Newton on the compiled model, with the
    unbounded values it would need and its test."""
    names = problem.refit_names([])
    F0, J0 = problem.model.jacobian(theta0, names, rows=problem.used)
    residual_before = problem.mask(problem.y - F0[problem.used])
    J0 *= problem.weight[:, :, None]
    whitener = _largest_model_whitener(problem, residual_before, J0)
    # the refit's columns prewhitened once, for its unbounded values and for its test
    s = problem.settings
    blocks = st.Blocks.whitened(whitener, J0, residual_before, s.n_blocks, ridge=s.ridge,
                                low=low_band_of(problem, whitener))
    unbounded, notes = _unbounded(problem, theta0, blocks)
    test = _refit_test(problem, blocks)
    del blocks
    theta, r, J = refine(problem, theta0, names, whitener, start=(residual_before, J0))
    del J0
    implausible = [n for n, p in unbounded.items() if not p.plausible_refit]
    report = RefitReport(_refitted(problem, theta0, theta, names, unbounded), implausible,
                         test)
    return Refit(Refined(theta, tuple(names), r, J), residual_before,
                 st.rms(r[problem.sliding]), report, tuple(notes))


def _refitted(problem: Problem, theta0: np.ndarray, theta: np.ndarray, names: list[str],
              unbounded: dict[str, RefitParameter]) -> dict[str, RefitParameter]:
    """``RefitReport.parameters``: the plausible ones of ``unbounded`` with their refitted
    value in theta, then the parameters of the effects the model has."""
    index = problem.model.index
    out = {name: dataclasses.replace(p, refit=float(theta[index[name]]))
           for name, p in unbounded.items()}
    for name in names:
        if name not in out:
            out[name] = RefitParameter(float(theta0[index[name]]), float(theta[index[name]]),
                                       None, list(problem.bounds(name)), True, own_effect=True)
    return out


def _largest_model_whitener(problem: Problem, residual: np.ndarray, J: np.ndarray
                            ) -> st.Whitener:
    """The AR noise model of the refit: fitted to the residual (M, 6) less its least-squares
    fit by the refitted parameters' columns J (M, 6, k), as each round's noise model is
    fitted to the residual of its largest model (``rounds``). Fitted to the residual of the
    model as given, the noise model takes what the refit is about to explain for noise (a
    missing seal force, a step at every start of a move, made white noise look like AR(12)
    noise of lag-one correlation 0.92 on point-to-point moves), and the prewhitened refit
    then weighs the differences of the residual over its level: it stopped at 2.07 times the
    noise where the refitted parameters reach 1.04 times."""
    flat = J.reshape(-1, J.shape[2])
    return lackfit.whitener_beyond(residual, J, problem.sliding, problem.settings,
                                   range(J.shape[2]),
                                   (flat.T @ flat, flat.T @ residual.reshape(-1)))


def _refit_test(problem: Problem, blocks: st.Blocks) -> RefitTest:
    """Is the refit of the model's own parameters significant? ``blocks``: its columns (at
    the model's values) and the residual, prewhitened, with the record's slowest components.
    The F-test of all of them against none, and the same test on the record's slowest
    components alone or on the rest alone (``statistics.band_p_value``, the smaller p-value
    times two), each at ``alpha``: a refit that takes up slow noise (a Coulomb coefficient and
    a payload mass that follow the wander of 1/f noise) is not a gap closed."""
    k = blocks.XtX.shape[1]
    if k == 0:
        return RefitTest(1.0, 1.0, False)
    lo, hi = np.full(k, -np.inf), np.full(k, np.inf)
    none, every = st.fit(blocks, [], lo, hi), st.fit(blocks, list(range(k)), lo, hi)
    p = st.f_test(none, every)[1]
    p_bands = st.band_p_value(blocks, none, every, k)
    significant = accept(Evidence(p, p_bands), Rule(problem.settings.alpha))
    return RefitTest(p, p_bands, significant)


def _unbounded(problem: Problem, theta0: np.ndarray, blocks: st.Blocks
               ) -> tuple[dict[str, RefitParameter], list[str]]:
    """The unbounded values a refit would need of the parameters with a plausible range,
    their plausibility (by name, the refit value still the model's), and a note for each
    implausible one.

    ``blocks`` holds the prewhitened derivatives of F at theta0 for the refitted parameters
    (the plausible ones first) and the residual there.
    """
    model = problem.model
    names = list(problem.plausible)
    out, notes = {}, []
    if not names:
        return out, notes
    A, b, _, _ = blocks.total()
    n = len(names)
    free = st.solve(A[:n, :n], b[:n], ridge=blocks.ridge)
    free += theta0[[model.index[n] for n in names]]
    for k, name in enumerate(names):
        lo, hi = problem.plausible[name]
        value0 = float(theta0[model.index[name]])
        plausible = bool(lo <= free[k] <= hi)
        out[name] = RefitParameter(value0, value0, float(free[k]), [lo, hi], plausible)
        if not plausible:
            notes.append(
                f"an unbounded refit of the model's parameters would need {name} = "
                f"{free[k]:.4g}, outside its plausible range [{lo:.4g}, {hi:.4g}]: not a wrong "
                "value but a missing effect is the likely cause; the refit is held within the "
                "range and the rest of the gap is left to the candidate effects")
    return out, notes
