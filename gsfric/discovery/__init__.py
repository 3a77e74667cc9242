"""Discrepancy discovery: where model and measurement disagree, and which effect is missing.

>>> from gsfric.discovery import discover
>>> result = discover(motion, forces, platform)        # a record of yours  # doctest: +SKIP
>>> result.names, result.rms_before, result.rms_after  # a record of yours  # doctest: +SKIP
>>> discover("measured.csv", out="out")                # a file of yours    # doctest: +SKIP

``discover`` (``api``, also ``gsfric.discover``) is ``gsfric discover``: it reads a
measured-data file, a DataFrame or a Motion with its forces, runs the workflow and, given
``out``, writes ``summary.json``, ``report.md``, plots and ``report.html``. Modules: ``api`` (the inputs),
``model`` (the compiled model as a function of its parameters), ``candidates`` (what
may change), ``statistics`` (prewhitening, block cross-validation, block bootstrap),
``regimes`` (where the residuals concentrate), ``workflow`` (the rounds), ``floor`` (the
noise floor of the verdict), ``dictionary`` (structure outside the catalog), ``verdict``
(the decision and its reason), ``summary`` (summary.json), ``markdown`` (report.md),
``report`` (the files written), ``view`` (report.html, the 3-D view).
"""

from gsfric.discovery.api import discover
from gsfric.discovery.candidates import CANDIDATE_NAMES, CANDIDATES, REFIT
from gsfric.discovery.outcome import Discovery
from gsfric.discovery.results import Finding
from gsfric.discovery.settings import Settings

__all__ = ["CANDIDATES", "CANDIDATE_NAMES", "REFIT", "Discovery", "Finding", "Settings",
           "discover"]
