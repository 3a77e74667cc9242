"""Identification of a platform's parameters from measured motion and actuator forces.

``identify(motion, forces, platform)`` estimates the moving body's inertial parameters, the
legs' part masses, the friction coefficients, the platform's effects and (when asked) the load
cells' offsets and gains, with a standard deviation each, and names what the motion cannot
identify (``gsfric.identification.fit``). ``identify_file`` reads a measured file and writes
``platform.toml`` and ``identification.json`` (``gsfric.identification.files``).
``excite`` designs a motion that identifies them well (``gsfric.identification.excite``).
"""

from gsfric.identification.excite import Excitation, excite
from gsfric.identification.fit import identify, validate
from gsfric.identification.results import Combination, Estimate, Identification, Validation

__all__ = ["Combination", "Estimate", "Excitation", "Identification", "Validation", "excite",
           "identify", "validate"]
