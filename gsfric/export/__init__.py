"""A self-contained C library of one platform for a real-time controller (``gsfric export``).

``writer.export_library`` writes the folder (header with the platform baked in, the generated
function made static, the step flags, Makefile, CMakeLists.txt, example, README);
``verify.verify_library`` builds it with the system compiler and compares it with
``Evaluator``. ``source`` cuts the C it copies out of the committed generated code and
gsfric/compiled/batch.c; ``text`` writes the C that depends on the platform and the manifest.
"""
