/* The Python module around one build of the compiled model.
 *
 * Each build of the generated C code (the per-step CasADi functions, the SIMD-over-steps
 * functions for one instruction set and the batch driver batch.c) is packaged as an extension
 * module named GSFRIC_MODULE, so that it is installed, found and rebuilt as any compiled part
 * of a Python package. Python never calls into it as a module: gsfric/compiled/native.py loads
 * the same file with ctypes and calls the driver's entry points. The module itself is empty.
 */
#define Py_LIMITED_API 0x030B0000
#include <Python.h>

#define GSFRIC_CAT(a, b) a##b
#define GSFRIC_INIT(name) GSFRIC_CAT(PyInit_, name)
#define GSFRIC_STR(x) #x
#define GSFRIC_NAME(x) GSFRIC_STR(x)

static struct PyModuleDef gsfric_module = {
    PyModuleDef_HEAD_INIT, GSFRIC_NAME(GSFRIC_MODULE),
    "One build of gsfric's compiled model, loaded with ctypes by gsfric.compiled.native.",
    0, NULL, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC GSFRIC_INIT(GSFRIC_MODULE)(void) { return PyModuleDef_Init(&gsfric_module); }
