"""The verdict of ``gsfric discover`` and its stated reason, from the evidence of the workflow.

``unexplained_discrepancy`` when any of these holds, in this order of precedence of the reason:

1. a group of the generic dictionary (``dictionary.find``) explains a part of the final
   residual under the candidates' held-out rule (lines, coupling, sensor memory, drift, a
   dependence on the state);
2. a lack-of-fit test of the final residual finds structure (``final_tests``), or a round's
   generic competitor did (a winner blocked or only imitating, a slow part);
3. the residual is more than ``Settings.floor_ratio`` times a noise floor the user gave (a
   sensor specification or a recording at rest, plus the pose noise propagated into the
   model's forces): a model right to within the sensors' noise cannot leave that.

Else ``explained`` (effects named, or a significant refit that closes ``min_gap``) or
``no_discrepancy``. Either way the reason says how the residual compares with the floor; a
residual above ``floor_ratio`` times an *estimated* floor without any structure found is
stated as such (the excess is a coloured noise, or a discrepancy this motion cannot tell from
one), with the noise model that whitens it, and what would decide (``--force-noise``,
``--noise-record``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gsfric.discovery.dictionary import Unexplained
from gsfric.discovery.floor import NoiseFloor
from gsfric.discovery.selection import NoiseModel


@dataclass(frozen=True)
class Verdict:
    """The verdict and why.

    Attributes
    ----------
    verdict : str
        One of ``VERDICTS``.
    reason : str
        One or two sentences: the evidence that decided, and the residual against the floor.
    decided_by : str
        ``dictionary``, ``lack of fit``, ``floor``, ``effects``, ``refit`` or ``none``.
    """

    verdict: str
    reason: str
    decided_by: str


def decide(*, structures: list[Unexplained], structure_found: bool, structure_text: str,
           floor: NoiseFloor, ratio_limit: float, named: list[str], refit_closes: bool,
           noise: NoiseModel) -> Verdict:
    """The verdict from the evidence.

    Parameters
    ----------
    structures : list of Unexplained
        The dictionary's groups found in the final residual.
    structure_found, structure_text
        Whether the lack-of-fit tests (or a round's generic competitor) found structure, and
        what it looks like.
    floor : NoiseFloor
    ratio_limit : float
        ``Settings.floor_ratio``.
    named : list of str
        The effects named.
    refit_closes : bool
        The refit of the model's own parameters is significant and closes ``min_gap``.
    noise : NoiseModel
        The AR model of the final residual.
    """
    ratio, against = _against(floor)
    if structures:
        what = "; ".join(s.description for s in structures)
        return Verdict("unexplained_discrepancy",
                       f"the residual holds structure that no catalog effect explains: {what}; "
                       f"{against}", "dictionary")
    if structure_found:
        return Verdict("unexplained_discrepancy",
                       f"the residual holds structure that no catalog effect explains"
                       f"{': ' + structure_text if structure_text else ''}; {against}",
                       "lack of fit")
    if ratio > ratio_limit and floor.trusted:
        return Verdict("unexplained_discrepancy",
                       f"{against}: more than {ratio_limit:g} x what the load cells' noise "
                       f"({floor.force_detail}) and the pose noise leave; the model and the data "
                       "disagree by more than the noise, in a form the dictionary does not "
                       "describe", "floor")
    if named:
        verdict, by = "explained", "effects"
    elif refit_closes:
        verdict, by = "explained", "refit"
    else:
        verdict, by = "no_discrepancy", "none"
    if ratio > ratio_limit:
        return Verdict(verdict, _coloured_excess(against, noise), by)
    return Verdict(verdict, against + ": within the noise", by)


def _against(floor: NoiseFloor) -> tuple[float, str]:
    """The residual over the noise floor, and the verdict's sentence comparing them (0 and
    what to give when no floor could be estimated)."""
    ratio = floor.residual_over_floor
    if not math.isfinite(ratio):
        # a record too short for the spectral estimate: nothing to compare with
        return 0.0, ("no noise floor could be estimated (too few samples); give "
                     "--force-noise or --noise-record")
    return ratio, (f"the residual is {ratio:.3g} x the noise floor of {floor.rms:.4g} N "
                   f"({floor.force_source} force noise and the pose noise in the model's "
                   "forces)")


def _coloured_excess(against: str, noise: NoiseModel) -> str:
    """The reason of a verdict whose residual is above an estimated floor without any
    structure in it (``against``: the comparison with the floor; ``noise``: the AR model of
    the final residual)."""
    orders = max(noise.ar_order) if noise.ar_order else 0
    return (f"{against}, but no structure is found in it (no line, coupling, sensor "
            "memory, drift or dependence on the state; no lack of fit): its excess over "
            f"the floor is a coloured noise that an AR model of order up to {orders} "
            "whitens. The floor is estimated from the force channels above a quarter of "
            "the sample rate, which holds no slow noise: either the load cells' noise is "
            "slower than white, or a discrepancy too smooth to tell from it on this "
            "motion. Give the load cells' noise (--force-noise, or --noise-record with a "
            "recording at rest) to decide")
