"""The generated model at run time: the manifest of generated/ (``manifest``), the state
layout (``state``), the shared library built from it (``build``, with the batch driver
``batch.c``), its functions called through ctypes or CasADi (``functions``), looked up by name
on first use (``native``)."""
