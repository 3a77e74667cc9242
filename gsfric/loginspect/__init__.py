"""Reading an unknown controller log: a proposed column map, log format and rig, with what was
assumed and why (``gsfric log inspect``).

Modules: ``names`` (what column names say), ``values`` (what the values say: time counter,
units, rates against the differentiated poses, rest), ``columns`` (the column map and its
assumptions), ``proposal`` (``inspect_log``: frame, home height, stroke, and the commented
files).
"""

from gsfric.loginspect.columns import Assumption
from gsfric.loginspect.proposal import LogInspection, Rest, inspect_log

__all__ = ["Assumption", "LogInspection", "Rest", "inspect_log"]
