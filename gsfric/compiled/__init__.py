"""The generated model at run time: the manifest of generated/ (``manifest``), the state
layout (``state``), the compiled builds of the model installed with the package (extension
modules ``_model*``, built by meson.build with the batch driver ``batch.c``), their functions
called through ctypes (``functions``), looked up by name on first use (``native``)."""
