"""Thresholds of the identification, each with its reason (one place; every module of
``gsfric.identification`` may import it)."""

from __future__ import annotations

RANK_RTOL = 1e-5
"""A direction of the column-normalised, noise-weighted regressor whose singular value is below
``RANK_RTOL`` times the largest is taken as not identifiable. With unit columns, the ratio is the
inverse of the condition number: below 1e-5 a combination's standard deviation would be 10^5
times that of the best-determined one (useless for any rig), and it is within a factor 100 of
the relative error of the regressor's columns (central differences of stepped parameters,
``FD_RSTEP``), so it cannot be told apart from a direction the data do not reach."""

ZERO_RTOL = 1e-9
"""A parameter whose column (in its typical unit, ``TYPICAL``) is below ``ZERO_RTOL`` times the
largest one does not act on the forces along this motion at all (an inertia without rotation,
a friction coefficient without speed): it is held at its prior value and named as unreached."""

MOVED_RTOL = 1e-6
"""A parameter the data do not reach has moved in the fit when it differs from its prior by
more than ``MOVED_RTOL`` of its size (``max(|prior|, TYPICAL[unit])``): the rows that hold it
leave it there to the fit's rounding, far below this."""

MIXED_TOL = 1e-3
"""A parameter is individually identifiable when less than ``MIXED_TOL`` of its (unit-scaled)
direction lies in the regressor's null space; otherwise only combinations with others are."""

FD_RSTEP = 1e-4
"""Central-difference step of a parameter without a compiled derivative, relative to
``max(|value|, TYPICAL[unit])``. F is affine in the inertial parameters (up to the friction they
load), so the truncation error is of the order of the step squared times the friction's
curvature; 1e-4 keeps the rounding error of the difference (1e-16 / 1e-4 of F) far below it."""

TYPICAL = {"kg": 1.0, "kg m": 0.1, "kg m^2": 0.01, "N": 1.0, "1": 0.01, "N s/m": 1.0,
           "N m s/rad": 0.01, "m": 0.1, "m/s": 0.01, "N s^2/m^2": 1.0, "N/m": 1.0, "s": 1e-3}
"""Typical size of a parameter of each unit: the floor of its finite-difference step, and the
scale of the test for columns that do not act (``ZERO_RTOL``)."""

PRIOR_LOAD_RATIO = 300.0
"""Factor between the measured forces' load and the prior's model's along the same poses
beyond which ``identify`` takes the forces to be in another unit (``check_forces``): the prior
is a guess that identify corrects, masses off by tens of times included, so only the factor a
unit makes (1000 between N and kN) is refused; ``discover``, which trusts its platform, refuses
30 (``UNIT_RATIO``)."""

IMPLAUSIBLE_SIGMA = 3.0
"""A mass the data call for (the unconstrained estimate) more than ``IMPLAUSIBLE_SIGMA``
standard deviations below zero is implausible: the fit is refused, not written (a force sign or
unit, or a platform that does not match the rig)."""

MAX_NFEV = 60
"""Most residual evaluations of the nonlinear least squares (Gauss-Newton on a nearly linear
model converges in a few; more means the model does not describe the data)."""

CONFIDENCE_Z = 1.959963984540054
"""Two-sided 95 % normal quantile: the intervals written in the platform file's comments."""

MAX_SAMPLES_EXCITE = 400
"""Samples of one period on which ``excite`` scores candidate motions (100 Hz over the default
4 s period: 80 samples per cycle of the highest harmonic, 1.25 Hz). The information of a smooth
excitation grows with the samples, but its shape is set by the low harmonics: a coarse grid
ranks candidates as the full one does, at a fraction of the cost."""

EXCITE_CANDIDATES = 24
"""Random Fourier-series candidates ``excite`` scores before refining the best one."""

EXCITE_HARMONICS = 5
"""Harmonics of the excitation's finite Fourier series per pose coordinate."""

EXCITE_SAMPLES_PER_CYCLE = 20
"""Fewest samples per cycle of the excitation's highest harmonic (``EXCITE_HARMONICS`` cycles a
period): fewer draw the series as a polygon, whose leg speeds and accelerations (the limits'
and the regressor's) are no longer those of the motion a controller would follow."""

MAX_EXCITE_SAMPLES = 1_000_000
"""Most samples of a designed excitation (33 minutes at 500 Hz): its expected standard
deviations hold the regressor of every sample (about 1.5 kB a sample with the load cells'
parameters), 1.5 GB at this size."""

WEAK_RELATIVE_STD = 0.05
"""A standard deviation, relative to the platform's value, above which ``excite``'s report and
``identify``'s statement (``Identification.weak``) also give how much the parameter moves a
force along the motion: a parameter known to worse than a few percent is one whose whole effect
is near the force noise, which a longer or faster motion shifts only as far as the limits
allow."""

MISFIT_RATIO = 10.0
"""A fit whose residual RMS exceeds this many times the noise (given, or the forces' own
high-frequency noise, ``high_frequency_std``) leaves forces the model does not reproduce: a
prior far from the rig (a local minimum of the nonlinear fit) or an effect the model lacks.
The statement says so (``Identification.misfit``). Ten: a high-frequency estimate sees the
white part of a load cell's noise only, so coloured noise leaves a good fit above it (AR(1)
noise of coefficient 0.99: about twice), while a prior far from the rig leaves tens of times
the noise (zero masses and friction: about fifteen)."""
