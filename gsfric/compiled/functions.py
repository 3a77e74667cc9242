"""The generated functions evaluated over batches of steps, in C through ctypes.

``CompiledFunction`` calls the batch driver of the compiled model (``batch.c``), which loops
over steps in C, reading and writing NumPy buffers directly (no CasADi objects on the hot path),
optionally on several POSIX threads, and computes the step flags in the same pass. ``declare``
gives a loaded build's entry points their C signatures.
"""

from __future__ import annotations

import ctypes
import functools

import numpy as np

from gsfric.compiled.manifest import BASENAME, function
from gsfric.compiled.state import motion_arrays, state_layout
from gsfric.errors import GsfricError, InputError, InputTypeError
from gsfric.signal.rotations import rotation_defects


class _Fn(ctypes.Structure):
    _fields_ = [("simd", ctypes.c_void_p), ("eval", ctypes.c_void_p), ("work", ctypes.c_void_p),
                ("n_in", ctypes.c_int), ("n_out", ctypes.c_int)]


class _Bound(ctypes.Structure):
    """The fixed arguments of a control-loop call (``gsfric_bound`` in ``batch.c``)."""

    _fields_ = [("fn", ctypes.POINTER(_Fn)), ("fixed", ctypes.c_void_p),
                ("in_stride", ctypes.c_void_p), ("out_stride", ctypes.c_void_p),
                ("index", ctypes.c_int), ("n_threads", ctypes.c_int),
                ("check", ctypes.c_void_p)]


class FlagSpec(ctypes.Structure):
    """Settings of the step flags computed in C (``gsfric_flags`` in ``batch.c``)."""

    _fields_ = [("d", ctypes.c_int), ("s2", ctypes.c_int), ("h", ctypes.c_int),
                ("has_stroke", ctypes.c_int), ("stroke_lo", ctypes.c_double),
                ("stroke_hi", ctypes.c_double), ("universal_limit", ctypes.c_double),
                ("singular_limit", ctypes.c_double), ("x_size", ctypes.c_longlong),
                ("cc", ctypes.c_int), ("f0", ctypes.c_int), ("coupling_tol", ctypes.c_double),
                ("rotation", ctypes.c_longlong), ("rotation_tol", ctypes.c_double)]

    def outputs_read(self) -> tuple[int, ...]:
        """The indices of the outputs the flags read (``flag_outputs`` in ``batch.c``): they
        are computed whether or not they are selected, into a buffer allocated for the call
        unless the caller passes one."""
        return tuple(k for k in (self.d, self.s2, self.h, self.cc, self.f0) if k >= 0)


def declare(lib: ctypes.CDLL) -> ctypes.CDLL:
    """The loaded library with the C signatures of its entry points (``batch.c``) set."""
    lib.gsfric_run.restype = ctypes.c_longlong
    lib.gsfric_run.argtypes = [ctypes.POINTER(_Fn), ctypes.c_void_p, ctypes.c_void_p,
                               ctypes.c_void_p, ctypes.c_void_p, ctypes.c_longlong, ctypes.c_int,
                               ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                               ctypes.c_void_p, ctypes.c_void_p]
    check = ctypes.c_void_p  # the gsfric_flags of the rotation test, or None
    lib.gsfric_run_one.restype = ctypes.c_longlong
    lib.gsfric_run_one.argtypes = [ctypes.POINTER(_Fn), ctypes.c_void_p, ctypes.c_void_p,
                                   ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int,
                                   ctypes.c_void_p, ctypes.c_longlong, ctypes.c_int, check]
    lib.gsfric_run_one_motion.restype = ctypes.c_longlong
    lib.gsfric_run_one_motion.argtypes = [ctypes.POINTER(_Fn), ctypes.c_void_p, ctypes.c_void_p,
                                          ctypes.c_void_p, *([ctypes.c_void_p] * 6),
                                          ctypes.c_int, ctypes.c_void_p, ctypes.c_longlong,
                                          ctypes.c_int, check]
    objects = [ctypes.POINTER(_Fn), ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
    lib.gsfric_run_one_objects.restype = ctypes.c_longlong
    lib.gsfric_run_one_objects.argtypes = objects + [ctypes.py_object, ctypes.c_int,
                                                     ctypes.py_object, ctypes.c_longlong,
                                                     ctypes.c_int, check]
    lib.gsfric_run_one_motion_objects.restype = ctypes.c_longlong
    lib.gsfric_run_one_motion_objects.argtypes = objects + [ctypes.py_object] * 6 + [
        ctypes.c_int, ctypes.py_object, ctypes.c_longlong, ctypes.c_int, check]
    for bound in (lib.gsfric_bound_states, lib.gsfric_bound_motion):
        bound.restype = ctypes.c_longlong
        bound.argtypes = [ctypes.c_void_p, ctypes.py_object, ctypes.c_longlong]
    lib.gsfric_tuple_item.restype = ctypes.c_longlong
    lib.gsfric_tuple_item.argtypes = [ctypes.py_object, ctypes.c_int]
    lib.gsfric_array_data.restype = ctypes.c_longlong
    lib.gsfric_array_data.argtypes = [ctypes.py_object]
    lib.gsfric_simd_lanes.restype = ctypes.c_int
    lib.gsfric_cpu_level.restype = ctypes.c_int
    return lib


class CompiledFunction:
    """One generated function, evaluated step by step in C over NumPy buffers.

    Inputs are arrays of shape (N, size) (one block per step) or (size,) (the same block for
    every step); outputs are (N, size) arrays, C-contiguous float64.

    Concurrency: an instance holds only read-only descriptions; every call builds its own
    argument arrays, so any number of threads may call one instance at once (each with its
    own output buffers). The C code runs without the GIL.
    """

    def __init__(self, lib: ctypes.CDLL, name: str) -> None:
        meta = function(name)
        self.name = name
        self.inputs = [(i["name"], i["size"]) for i in meta["inputs"]]
        self.outputs = [(o["name"], o["size"], tuple(o["shape"])) for o in meta["outputs"]]
        full = f"{BASENAME}_{name}"
        self._lib = lib
        try:
            simd = ctypes.cast(getattr(lib, f"{full}_batch"), ctypes.c_void_p)
        except AttributeError:
            simd = None
        self._fn = _Fn(simd, ctypes.cast(getattr(lib, full), ctypes.c_void_p),
                       ctypes.cast(getattr(lib, f"{full}_work"), ctypes.c_void_p),
                       len(self.inputs), len(self.outputs))
        self.simd = simd is not None
        # read only from here on
        self._out_strides = (ctypes.c_longlong * len(self.outputs))(
            *[size for _, size, _ in self.outputs])
        self._index = {name: k for k, (name, _, _) in enumerate(self.outputs)}

    def __call__(self, inputs, outputs=None, n_threads: int = 1, select=None,
                 flags: FlagSpec | None = None, flag: np.ndarray | None = None,
                 motion=None, check: FlagSpec | None = None, caller: str | None = None
                 ) -> dict:
        """Evaluate over N steps.

        Parameters
        ----------
        inputs : sequence of ndarray
            One per input, (N, size) or (size,); with ``motion``, input 0 is None.
        outputs : dict of name -> ndarray (N, size), optional
            Preallocated output buffers (C-contiguous float64); others are allocated.
        n_threads : int
            Threads (POSIX threads created for the call when N is large enough).
        select : iterable of str, optional
            Outputs to compute (default all); the others are skipped.
        flags : FlagSpec, optional
            Compute the step flags into ``flag`` (int64 (N,)) in the same pass; a non-finite
            step's outputs are set to NaN. The outputs the flags read are computed whether
            or not they are selected.
        motion : sequence of 6 ndarray, optional
            position (N, 3), rotation (N, 3, 3), velocity, omega, acceleration, alpha (N, 3)
            in place of the state input 0 (laid out in C, block by block: no (N, 24) array).
        check : FlagSpec, optional
            Without ``flags``: the rotation test of ``check`` (``rotation``, ``rotation_tol``)
            on every step's state; the first step that fails it is an ``InputError`` (step
            and the measure that fails, ``caller`` naming the call; default the function's
            name). With ``flags`` the steps are flagged ``FLAG_ROTATION`` instead.

        Returns
        -------
        dict of output name -> ndarray (N, size).
        """
        parts = None if motion is None else motion_arrays(self.name, motion)
        arrays, n = self._input_arrays(inputs, parts)
        # this call's own argument arrays
        in_ptrs = (ctypes.c_void_p * len(arrays))(
            *[None if a is None else a.ctypes.data for a in arrays])
        in_strides = (ctypes.c_longlong * len(arrays))(
            *[state_layout().size if a is None else a.shape[1] if a.ndim == 2 else 0
              for a in arrays])
        motion_ptrs = None if parts is None else \
            (ctypes.c_void_p * 6)(*[a.ctypes.data for a in parts])
        out_ptrs = (ctypes.c_void_p * len(self.outputs))()
        result = self._output_buffers(outputs or {}, select, n, out_ptrs)
        flag_ptr = None if flags is None else self._flag_pointer(flag, n)
        rejected = ctypes.c_longlong(-1)
        failed = self._lib.gsfric_run(ctypes.byref(self._fn), in_ptrs, in_strides, out_ptrs,
                                      self._out_strides, n, int(n_threads),
                                      None if flags is None else ctypes.byref(flags), flag_ptr,
                                      motion_ptrs, None if check is None else ctypes.byref(check),
                                      ctypes.byref(rejected))
        if failed:
            raise GsfricError(f"{self.name}: evaluation failed at {failed} steps")
        if rejected.value >= 0:
            raise not_rotation(caller or self.name, rejected.value, check,
                               states=arrays[0], rotation=None if parts is None else parts[1])
        return result

    def _flag_pointer(self, flag: np.ndarray | None, n: int) -> int:
        """The data pointer of the step flags' array ``flag``, checked: int64 (n,),
        C-contiguous, writeable."""
        if flag is None or flag.shape != (n,) or flag.dtype != np.int64 or \
                not flag.flags.c_contiguous:
            raise InputError(f"{self.name}: flag must be a C-contiguous int64 array of "
                              f"shape ({n},)")
        if not flag.flags.writeable:
            raise InputError(read_only(self.name, "flag"))
        return flag.ctypes.data

    def _input_arrays(self, inputs, parts: list[np.ndarray] | None) -> tuple[list, int]:
        """The inputs as C-contiguous float64 arrays (None for a state laid out from the
        motion's ``parts``) and the number of steps N they agree on (1 if none varies)."""
        arrays, n = [], None if parts is None else parts[0].shape[0]
        for (name, size), value in zip(self.inputs, inputs):
            if value is None and parts is not None:
                arrays.append(None)
                continue
            if value is None:
                raise InputTypeError(f"{self.name}: input {name} is None; give an array")
            try:
                a = np.ascontiguousarray(value, dtype=np.float64)
            except (TypeError, ValueError):
                raise InputTypeError(f"{self.name}: input {name} must be an array of numbers, "
                                     f"got {type(value).__name__}") from None
            if a.ndim == 1:
                if a.shape[0] != size:
                    raise InputError(f"{self.name}: input {name} has {a.shape[0]} values, "
                                      f"expected {size}")
            elif a.ndim == 2 and a.shape[1] == size:
                if n is not None and a.shape[0] != n:
                    raise InputError(f"{self.name}: input {name} has {a.shape[0]} steps, "
                                      f"expected {n}")
                n = a.shape[0]
            else:
                raise InputError(f"{self.name}: input {name} has shape {a.shape}, expected "
                                  f"(N, {size}) or ({size},)")
            arrays.append(a)
        return arrays, 1 if n is None else n

    def _output_buffers(self, outputs: dict, select, n: int, out_ptrs) -> dict:
        """The selected outputs' buffers (given ones checked, others allocated), their data
        pointers written into ``out_ptrs`` (the others stay null: not computed)."""
        wanted = None if select is None else set(select)
        result = {}
        for k, (name, size, _) in enumerate(self.outputs):
            if wanted is not None and name not in wanted:
                continue
            buf = outputs.get(name)
            if buf is None:
                buf = np.empty((n, size))
            elif buf.shape != (n, size) or buf.dtype != np.float64 or \
                    not buf.flags.c_contiguous:
                raise InputError(f"{self.name}: output buffer {name} must be a C-contiguous "
                                  f"float64 array of shape ({n}, {size})")
            elif not buf.flags.writeable:
                raise InputError(read_only(self.name, f"output buffer {name}"))
            out_ptrs[k] = buf.ctypes.data
            result[name] = buf
        return result

    def bound(self, constants: list[np.ndarray], output: str, n_threads: int = 1,
              check: FlagSpec | None = None, caller: str | None = None):
        """A lean callable ``f(x, out)`` for the control loop's repeated calls.

        Input 0 varies (``x``, C-contiguous float64 of shape (N, size)); the other inputs are
        fixed to ``constants`` (one block each, broadcast to every step); only ``output`` is
        computed, into ``out`` (C-contiguous float64, (N, size)). Shapes are checked, nothing
        is copied or allocated. With ``check``, every state has its rotation test (as in
        ``__call__``; the rows of the steps that fail it are NaN); ``caller`` names the call in
        the errors (default the function's name). The callable holds only read-only arrays
        (the C side builds each call's own argument arrays): threads may share it.
        """
        index = self._index[output]
        size_x, size_out = self.inputs[0][1], self.outputs[index][1]
        fixed, fixed_ptrs, in_strides, checked = self._fixed(constants, size_x, check)
        fn = ctypes.byref(self._fn)
        out_strides, name, threads = self._out_strides, caller or self.name, int(n_threads)
        by_object = _objects_readable(self._lib)
        run_one = self._lib.gsfric_run_one_objects if by_object else self._lib.gsfric_run_one
        bound, bound_ref, tuples = self._bound_struct(fixed_ptrs, in_strides, index, threads,
                                                      by_object, checked)
        run_tuple = self._lib.gsfric_bound_states

        def call(x: np.ndarray, out: np.ndarray) -> np.ndarray:
            try:
                wrong = (x.dtype != np.float64 or x.ndim != 2 or x.shape[1] != size_x
                         or not x.flags.c_contiguous or out.dtype != np.float64
                         or out.shape != (x.shape[0], size_out) or not out.flags.c_contiguous
                         or not out.flags.writeable)
            except AttributeError:
                raise InputTypeError(f"{name}: x and out must be NumPy arrays, got "
                                     f"{type(x).__name__} and {type(out).__name__}") from None
            if wrong:
                if not out.flags.writeable:
                    raise InputError(read_only(name, "out"))
                raise InputError(f"{name}: x must be C-contiguous float64 (N, {size_x}) "
                                  f"and out (N, {size_out})")
            if tuples:
                status = run_tuple(bound_ref, (x, out), x.shape[0])
            elif by_object:
                status = run_one(fn, fixed_ptrs, in_strides, out_strides, x, index, out,
                                 x.shape[0], threads, checked)
            else:
                status = run_one(fn, fixed_ptrs, in_strides, out_strides, x.ctypes.data, index,
                                 out.ctypes.data, x.shape[0], threads, checked)
            if status:
                raise _failure(status, name, check, states=x)
            return out

        call.keep = (fixed, fixed_ptrs, in_strides, bound, check, self)  # alive with the call
        return call

    def _fixed(self, constants: list[np.ndarray], size_x: int, check: FlagSpec | None):
        """The fixed arguments of a control-loop callable: the constants as float64 arrays
        (kept alive by the callable), their pointers (input 0's left null), the inputs'
        strides (input 0's ``size_x``, the constants broadcast) and the address of the
        rotation test's settings ``check`` (or None)."""
        fixed = [np.ascontiguousarray(c, dtype=np.float64) for c in constants]
        n_in = len(self.inputs)
        fixed_ptrs = (ctypes.c_void_p * n_in)(0, *[c.ctypes.data for c in fixed])
        in_strides = (ctypes.c_longlong * n_in)(size_x, *([0] * (n_in - 1)))
        return fixed, fixed_ptrs, in_strides, None if check is None else ctypes.addressof(check)

    def _bound_struct(self, fixed_ptrs, in_strides, index: int, threads: int, by_object: bool,
                      checked: int | None):
        """The fixed arguments of a bound call in one ``_Bound`` (kept alive by the caller;
        ``checked``: the address of the rotation test's settings, or None), a reference to
        it, and whether the call may pass its arrays in one tuple; ``(None, None, False)``
        when it may not (the struct is only read by the tuple calls)."""
        if not (by_object and _tuples_readable(self._lib)):
            return None, None, False
        bound = _Bound(ctypes.pointer(self._fn), ctypes.cast(fixed_ptrs, ctypes.c_void_p),
                       ctypes.cast(in_strides, ctypes.c_void_p),
                       ctypes.cast(self._out_strides, ctypes.c_void_p), index, threads, checked)
        return bound, ctypes.byref(bound), True

    def bound_motion(self, constants: list[np.ndarray], output: str, n_threads: int = 1,
                     check: FlagSpec | None = None, caller: str | None = None):
        """``bound``'s callable from a motion's arrays: ``f(position, rotation, velocity,
        omega, acceleration, alpha, out=None)``, shapes (N, 3) and rotation (N, 3, 3); arrays
        that are not C-contiguous float64 are converted; ``out`` (N, size) is allocated when
        not given. The states are laid out in C; ``check`` and ``caller`` as in ``bound``."""
        size_x = state_layout().size
        if self.inputs[0][1] != size_x:
            raise GsfricError(f"{self.name}: input 0 is not a motion's state")
        fixed, fixed_ptrs, in_strides, checked = self._fixed(constants, size_x, check)
        index = self._index[output]
        size_out = self.outputs[index][1]
        fn = ctypes.byref(self._fn)
        out_strides, name, threads = self._out_strides, caller or self.name, int(n_threads)
        f64 = np.float64
        by_object = _objects_readable(self._lib)
        run = self._lib.gsfric_run_one_motion_objects if by_object else \
            self._lib.gsfric_run_one_motion
        bound, bound_ref, tuples = self._bound_struct(fixed_ptrs, in_strides, index, threads,
                                                      by_object, checked)
        run_tuple = self._lib.gsfric_bound_motion
        empty = np.empty

        def call(position, rotation, velocity, omega, acceleration, alpha, out=None):
            try:
                p = np.ascontiguousarray(position, dtype=f64)
                T = np.ascontiguousarray(rotation, dtype=f64)
                v = np.ascontiguousarray(velocity, dtype=f64)
                w = np.ascontiguousarray(omega, dtype=f64)
                a = np.ascontiguousarray(acceleration, dtype=f64)
                al = np.ascontiguousarray(alpha, dtype=f64)
            except (TypeError, ValueError):
                raise InputTypeError(f"{name}: position, rotation, velocity, omega, "
                                     "acceleration and alpha must be arrays of numbers") from None
            n = p.shape[0] if p.ndim == 2 else -1
            three = (n, 3)
            if (p.shape, v.shape, w.shape, a.shape, al.shape, T.shape) != \
                    (three, three, three, three, three, (n, 3, 3)):
                raise InputError(f"{name}: position, velocity, omega, acceleration, alpha "
                                  "must be (N, 3) and rotation (N, 3, 3) with the same N; got "
                                  f"{[x.shape for x in (p, T, v, w, a, al)]}")
            if out is None:
                out = empty((n, size_out))
            elif not isinstance(out, np.ndarray) or out.dtype != f64 or \
                    out.shape != (n, size_out) or not out.flags.c_contiguous:
                raise InputError(f"{name}: out must be C-contiguous float64 ({n}, {size_out})")
            elif not out.flags.writeable:
                raise InputError(read_only(name, "out"))
            if tuples:
                status = run_tuple(bound_ref, (p, T, v, w, a, al, out), n)
            elif by_object:
                status = run(fn, fixed_ptrs, in_strides, out_strides, p, T, v, w, a, al, index,
                             out, n, threads, checked)
            else:
                status = run(fn, fixed_ptrs, in_strides, out_strides, p.ctypes.data,
                             T.ctypes.data, v.ctypes.data, w.ctypes.data, a.ctypes.data,
                             al.ctypes.data, index, out.ctypes.data, n, threads, checked)
            if status:
                raise _failure(status, name, check, rotation=T)
            return out

        call.keep = (fixed, fixed_ptrs, in_strides, bound, check, self)  # alive with the call
        return call


def not_rotation(name: str, step: int, check: FlagSpec, states: np.ndarray | None = None,
                 rotation: np.ndarray | None = None) -> InputError:
    """The error for step ``step`` of a call ``name``, whose rotation block failed the test of
    ``check`` (``rotation_flag`` in batch.c): the block of ``states`` (N, size) or (size,), or
    ``rotation`` (N, 3, 3) of a motion, and the measure that fails."""
    if rotation is None:
        block = states.reshape(-1, states.shape[-1])[step, check.rotation:check.rotation + 9]
        where = f"x[{step}]: the rotation block is"
    else:
        block, where = rotation[step], f"rotation[{step}]:"
    error, det = (float(v[0]) for v in rotation_defects(np.reshape(block, (1, 3, 3))))
    why = (f"|R^T R - I| = {error:.3g} > {check.rotation_tol:g}"
           if error > check.rotation_tol else f"det R = {det:.3g} < 0")
    return InputError(f"{name}: {where} not a rotation ({why})")


def _failure(status: int, name: str, check: FlagSpec | None, **arrays) -> GsfricError:
    """The error of a control-loop call's non-zero ``status`` (``status`` in batch.c): the
    evaluation failed at -status steps, or step status - 1 is ``not_rotation``."""
    if status < 0:
        return GsfricError(f"{name}: evaluation failed at {-status} steps")
    return not_rotation(name, status - 1, check, **arrays)


def read_only(name: str, argument: str) -> str:
    """The message for an output array that cannot be written (``out.flags.writeable`` is
    False, a view of immutable memory), worded as NumPy's."""
    return f"{name}: {argument}: output array is read-only; give a writeable array"


@functools.lru_cache(maxsize=None)
def _tuples_readable(lib) -> bool:
    """True when the library reads a tuple's items as Python does (``gsfric_tuple_item``,
    batch.c): the control loop's calls then pass their arrays as one tuple."""
    samples = [(np.zeros(1), np.zeros((2, 3))), tuple(np.zeros(3) for _ in range(7))]
    try:
        return all(lib.gsfric_tuple_item(t, k) == id(t[k]) for t in samples
                   for k in range(len(t)))
    except Exception:  # noqa: BLE001 - any failure: one argument per array
        return False


@functools.lru_cache(maxsize=None)
def _objects_readable(lib) -> bool:
    """True when the library reads a NumPy array's data pointer from the array object as
    NumPy itself gives it (``gsfric_array_data``, batch.c) for arrays, views and
    slices: the control loop's calls then pass arrays as objects."""
    base = np.arange(60.0).reshape(5, 12)
    samples = [base, base[2:], base[1:3, 4:], np.empty((1, 6)), np.zeros(0)]
    try:
        return all(lib.gsfric_array_data(a) == a.ctypes.data for a in samples)
    except Exception:  # noqa: BLE001 - any failure: the pointers' way
        return False
