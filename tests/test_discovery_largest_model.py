"""The largest model behind a round's noise model: each candidate once, as it can be fitted."""

from types import SimpleNamespace

import numpy as np

from gsfric.discovery.residuals import Design
from gsfric.discovery.rounds import _noise_whitener
from gsfric.discovery.settings import Settings

DEFAULTS = Settings()


def hinge_design(residual, x, references, refit):
    """A design with one refitted column ``refit`` (M, 6) and a stroke-like candidate tried
    at ``references`` with both signs: the hinge ``max(sign (x - reference), 0)`` per variant
    (x (M, 6), the legs' position along the stroke)."""
    cols, variants, grid = [refit], [], []
    for sign in (1.0, -1.0):
        for ref in references:
            cols.append(np.maximum(sign * (x - ref), 0.0))
            variants.append([len(cols) - 1])
            grid.append({"reference": float(ref)})
    X = np.stack(cols, axis=2)
    k = X.shape[2]
    return Design(np.zeros(k), residual, X, ["refit"] + ["stroke_friction.slope"] * (k - 1),
                  np.full(k, -np.inf), np.full(k, np.inf), [0], {"stroke_friction": variants},
                  {"stroke_friction": grid})


def test_noise_model_does_not_take_what_only_a_combination_of_variants_fits():
    """A friction growing both ways from the middle of the stroke (``|x - middle|``) is no
    catalog effect: one hinge of stroke friction fits half of it, and only the sum of two
    variants (the two signs at the middle reference) fits all of it. The round's noise model
    is fitted beyond the refit and each candidate once, with the variant it is fitted with:
    the half that no candidate explains stays in what the noise model sees (its marginal
    spread), instead of being taken out by a combination of variants that is not a model."""
    rng = np.random.default_rng(5)
    m = 3000
    t = np.linspace(0.0, 1.0, m)
    x = 0.05 * np.sin(2 * np.pi * 3 * t)[:, None] + 0.01 * rng.uniform(size=6)
    middle = 0.5 * (x.min() + x.max())
    noise = 0.1
    residual = 20.0 * np.abs(x - middle) + rng.normal(0.0, noise, (m, 6))
    references = np.linspace(x.min(), x.max(), 9)
    assert np.any(np.isclose(references, middle))
    design = hinge_design(residual, x, references, np.ones((m, 6)))
    problem = SimpleNamespace(sliding=np.ones((m, 6), bool), settings=DEFAULTS)
    w = _noise_whitener(design, problem)
    # one hinge (and the constant) leave most of a V's other half: over twice the noise
    assert np.all(w.marginal_std > 2 * noise)
    # the largest model holds the refit and one column of the candidate
    assert design.largest_model(DEFAULTS.ridge)[0] == 0
    assert len(design.largest_model(DEFAULTS.ridge)) == 2


def test_largest_model_picks_the_variant_that_fits():
    """Of a candidate's variants, the largest model holds the one that fits the residual
    best with the refit (a hinge at the reference the data have)."""
    rng = np.random.default_rng(6)
    m = 2000
    t = np.linspace(0.0, 1.0, m)
    x = 0.05 * np.sin(2 * np.pi * 2 * t)[:, None] + 0.01 * rng.uniform(size=6)
    references = np.linspace(x.min(), x.max(), 9)
    true = 3
    residual = 15.0 * np.maximum(x - references[true], 0.0) + rng.normal(0.0, 0.1, (m, 6))
    design = hinge_design(residual, x, references, np.ones((m, 6)))
    cols = design.largest_model(DEFAULTS.ridge)
    assert cols == [0, 1 + true]
