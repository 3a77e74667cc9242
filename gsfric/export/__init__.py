"""A self-contained C library of one platform for a real-time controller (``gsfric export``).

``writer.export_library`` writes the folder (header with the platform baked in, the model,
the step flags, Makefile, CMakeLists.txt, example, README); ``verify.verify_library`` builds it
with the system compiler and compares it with ``Evaluator``. The model is one of two builds:
``folded`` prints the generated function with the platform's numbers folded in as
straight-line C (the default, "specialised"); ``source`` cuts CasADi's generated function of
every platform out of the committed generated code ("generic"), and the step flags out of
gsfric/compiled/batch.c; ``text`` writes the C that depends on the platform and the manifest.
"""
