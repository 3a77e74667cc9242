"""p-values of the classical tests the discovery makes (``scipy.special``, ``scipy.stats``): every
F-test's p-value is ``f_sf``.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np
from scipy.special import chdtrc, fdtrc, stdtr

from gsfric._optional import optional


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
    (``scipy.stats.alexandergovern(*groups).pvalue``); NaN when a group has no spread.

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
    with warnings.catch_warnings():   # a group without spread: NaN, and SciPy's warnings
        warnings.simplefilter("ignore", RuntimeWarning)
        return float(optional("scipy.stats").alexandergovern(*groups).pvalue)
