"""p-values of the classical tests the discovery makes, from ``scipy.special`` alone.

``scipy.stats`` gives the same numbers (to rounding; ``tests/test_pvalues.py`` compares them)
but takes half a second to import, a sixth of a short ``gsfric discover``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.special import chdtrc, fdtrc, stdtr


def f_sf(f: float, dfn: float, dfd: float) -> float:
    """P(F > f) for an F distribution with (dfn, dfd) degrees of freedom.

    Examples
    --------
    >>> from gsfric.discovery.pvalues import f_sf
    >>> round(f_sf(1.0, 2, 2), 6)
    0.5
    """
    return float(fdtrc(dfn, dfd, f))


def chi2_sf(x: float, df: float) -> float:
    """P(X > x) for a chi-square distribution with ``df`` degrees of freedom.

    Examples
    --------
    >>> from gsfric.discovery.pvalues import chi2_sf
    >>> round(chi2_sf(2.0, 2), 6)   # exp(-x / 2) for two degrees of freedom
    0.367879
    """
    return float(chdtrc(df, x))


def t_greater(values: np.ndarray) -> float:
    """One-sample t-test of a mean above zero: p-value (``scipy.stats.ttest_1samp(values,
    0, alternative="greater")``); NaN with fewer than two values or no spread.

    Examples
    --------
    >>> import numpy as np
    >>> from gsfric.discovery.pvalues import t_greater
    >>> round(t_greater(np.array([1.0, 2.0, 3.0])), 4)
    0.0371
    """
    values = np.asarray(values, float)
    n = len(values)
    if n < 2:
        return float("nan")
    with np.errstate(divide="ignore", invalid="ignore"):
        t = values.mean() / (values.std(ddof=1) / np.sqrt(n))
    return float(stdtr(n - 1, -t))


def alexander_govern(groups: Sequence[np.ndarray]) -> float:
    """Alexander-Govern test of equal means with unequal variances: p-value
    (``scipy.stats.alexandergovern(*groups).pvalue``).

    Each group's mean is compared with the variance-weighted common mean by a t statistic,
    normalised (Alexander and Govern, 1994, J. Educ. Behav. Stat. 19(2)) and summed in
    squares to a chi-square statistic with ``len(groups) - 1`` degrees of freedom. NaN when a
    group has no spread.

    Parameters
    ----------
    groups : sequence of ndarray (n_i,)
        At least two groups of at least two values each.

    Examples
    --------
    >>> import numpy as np
    >>> from gsfric.discovery.pvalues import alexander_govern
    >>> g = [np.array([1.0, 2.0, 3.0, 4.0]), np.array([2.0, 3.5, 4.0, 6.0])]
    >>> 0.0 < alexander_govern(g) < 1.0
    True
    """
    with np.errstate(divide="ignore", invalid="ignore"):   # no spread: NaN, as SciPy
        z = _normalised_t(groups)
    return chi2_sf(float(z @ z), len(groups) - 1)


def _normalised_t(groups: Sequence[np.ndarray]) -> np.ndarray:
    """Each group's t statistic against the common mean, normalised (``alexander_govern``)."""
    means = np.array([np.mean(g) for g in groups])
    n = np.array([len(g) for g in groups], float)
    se2 = np.array([np.var(g, ddof=1) for g in groups]) / n
    se = np.sqrt(se2)
    se = np.where(se <= np.abs(np.finfo(float).eps * means), np.nan, se)
    weights = (1 / se2) / np.sum(1 / se2)
    t = (means - np.sum(weights * means)) / se
    v = n - 1
    a = v - 0.5
    b = 48 * a ** 2
    c = np.sqrt(a * np.log(1 + t ** 2 / v))
    return c + (c ** 3 + 3 * c) / b - (4 * c ** 7 + 33 * c ** 5 + 240 * c ** 3 + 855 * c) / \
        (b ** 2 * 10 + 8 * b * c ** 4 + 1000 * b)
