"""Benchmarks of the compiled model (``gsfric bench``) and the plain NumPy engine they compare
it with; neither is on the evaluation path."""
