"""Signal processing on sampled poses and forces: rotations, Savitzky-Golay filters, smoothing
splines and noise estimators (NumPy and SciPy only; no knowledge of the platform)."""
