"""Signal processing on sampled poses and forces: rotations, Savitzky-Golay filters, smoothing
splines, noise estimators, and the smoother a time base calls for with the noise of its
derivatives (``smoothing``) (NumPy and SciPy only; no knowledge of the platform)."""
