"""Compiled evaluation of the generated functions over batches of steps.

The C code in generated/ and the batch driver ``_native/batch.c`` are compiled once into a
shared library, cached under ``$GSFRIC_CACHE`` (default: the user cache directory) in a folder
named after the hash of the sources and the compiler command, and loaded with ctypes. The
driver loops over steps in C, reading and writing NumPy buffers directly (no CasADi objects on
the hot path), optionally on several POSIX threads, and computes the step flags in the same pass.

Without a working C compiler, the functions are evaluated by CasADi itself from the serialized
copy in generated/, with a warning: the same numbers, much slower.

Environment: ``CC`` (compiler, default ``cc``), ``GSFRIC_CACHE`` (cache directory),
``GSFRIC_NO_COMPILE=1`` (force the CasADi fallback), ``GSFRIC_MARCH`` (target CPU, default
``native``; ``x86-64-v3`` for a library that runs on any AVX2 machine), ``GSFRIC_LANES``
(steps per vector, default from the target: 8 with AVX-512, 4 with AVX, else 1).
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import os
import shlex
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np

from gsfric.errors import GsfricError
from gsfric.manifest import BASENAME, function, generated_dir, manifest

DRIVER = Path(__file__).resolve().parent / "_native" / "batch.c"


def _target_flags() -> tuple[str, ...]:
    """The target CPU (``GSFRIC_MARCH``, default native) and lane width (``GSFRIC_LANES``,
    default: from the target's vector width, see derive/simd.py)."""
    flags = (f"-march={os.environ.get('GSFRIC_MARCH') or 'native'}",)
    lanes = os.environ.get("GSFRIC_LANES")
    if lanes:
        if lanes not in ("1", "2", "4", "8"):
            raise GsfricError(f"GSFRIC_LANES: {lanes!r} is not one of 1, 2, 4, 8")
        flags += (f"-DGSFRIC_LANES={lanes}",)
    return flags


def _cpu_id() -> str:
    """The CPU's model and features (a native build runs only where they match)."""
    try:
        with open("/proc/cpuinfo") as f:
            lines = [ln for ln in f if ln.startswith(("model name", "flags"))]
        return "".join(sorted(set(lines)))
    except OSError:
        import platform

        return platform.processor() + platform.machine()


CFLAGS = ("-O2", *_target_flags(), "-fno-math-errno", "-freciprocal-math", "-fPIC",
          "-fno-semantic-interposition", "-pthread")


class BuildError(GsfricError):
    """The generated C code could not be compiled."""


def cache_dir() -> Path:
    env = os.environ.get("GSFRIC_CACHE")
    if env:
        return Path(env)
    from platformdirs import user_cache_dir

    return Path(user_cache_dir("gsfric"))


def _compiler() -> list[str]:
    return shlex.split(os.environ.get("CC", "cc"))


def _build_key(sources: list[Path], cmd: list[str]) -> str:
    h = hashlib.sha256()
    for s in sources:
        h.update(s.read_bytes())
    h.update(" ".join(cmd).encode())
    h.update(sys.platform.encode())
    if "-march=native" in cmd:
        h.update(_cpu_id().encode())
    return h.hexdigest()[:20]


def _sources() -> list[Path]:
    folder = generated_dir()
    return [DRIVER, folder / f"{BASENAME}.c", folder / f"{BASENAME}_batch.c"]


def _compile(cc: list[str], flags, sources: list[Path], target: Path) -> str | None:
    """Compile every source to an object in parallel and link them; an error line or None."""
    objects = [target.with_name(f"{target.stem}.{k}.o") for k in range(len(sources))]
    try:
        procs = [subprocess.Popen(cc + list(flags) + ["-c", str(src), "-o", str(obj)],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                 for src, obj in zip(sources, objects)]
    except FileNotFoundError:
        raise BuildError(f"no C compiler: {cc[0]!r} was not found (set CC to one)") from None
    errors = [p.communicate()[1] for p in procs]
    failed = [e for p, e in zip(procs, errors) if p.returncode]
    if not failed:
        link = subprocess.run(cc + list(flags) + ["-shared"] + [str(o) for o in objects]
                              + ["-o", str(target), "-lm"], capture_output=True, text=True)
        failed = [link.stderr] if link.returncode else []
    for obj in objects:
        obj.unlink(missing_ok=True)
    if not failed:
        return None
    lines = [line for e in failed for line in e.strip().splitlines()]
    return lines[-1] if lines else "(no message)"


def build_library() -> Path:
    """Compile (or find in the cache) the shared library; returns its path."""
    sources = _sources()
    for src in sources[1:]:
        if not src.exists():
            raise BuildError(f"{src} is missing: run `gsfric derive` to generate it")
    cc = _compiler()
    key = _build_key(sources, cc + list(CFLAGS))
    folder = cache_dir() / f"build-{key}"
    lib = folder / "libgsfric.so"
    if lib.exists():
        return lib
    folder.mkdir(parents=True, exist_ok=True)
    import fcntl

    with open(folder / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if lib.exists():
            return lib
        tmp = folder / f".libgsfric.{os.getpid()}.so"
        print(f"gsfric: compiling the generated model (once, about 30 s) into {folder}",
              file=sys.stderr)
        error = "(no message)"
        for flags in (CFLAGS, tuple(f for f in CFLAGS if not f.startswith("-march")),
                      ("-O1", "-fPIC", "-pthread")):
            error = _compile(cc, flags, sources, tmp)
            if error is None:
                tmp.replace(lib)
                return lib
        raise BuildError(f"compiling the generated model failed: {error}; check the compiler "
                         "(CC) or regenerate generated/ with `gsfric derive`")


class _Fn(ctypes.Structure):
    _fields_ = [("simd", ctypes.c_void_p), ("eval", ctypes.c_void_p), ("work", ctypes.c_void_p),
                ("n_in", ctypes.c_int), ("n_out", ctypes.c_int)]


class FlagSpec(ctypes.Structure):
    """Settings of the step flags computed in C (``gsfric_flags`` in ``_native/batch.c``)."""

    _fields_ = [("d", ctypes.c_int), ("s2", ctypes.c_int), ("h", ctypes.c_int),
                ("has_stroke", ctypes.c_int), ("stroke_lo", ctypes.c_double),
                ("stroke_hi", ctypes.c_double), ("universal_limit", ctypes.c_double),
                ("singular_limit", ctypes.c_double), ("x_size", ctypes.c_longlong)]


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
                 flags: FlagSpec | None = None, flag: np.ndarray | None = None) -> dict:
        """Evaluate over N steps.

        Parameters
        ----------
        inputs : sequence of ndarray
            One per input, (N, size) or (size,).
        outputs : dict of name -> ndarray (N, size), optional
            Preallocated output buffers (C-contiguous float64); others are allocated.
        n_threads : int
            Threads (POSIX threads created for the call when N is large enough).
        select : iterable of str, optional
            Outputs to compute (default all); the others are skipped.
        flags : FlagSpec, optional
            Compute the step flags into ``flag`` (int64 (N,)) in the same pass; a non-finite
            step's outputs are set to NaN.

        Returns
        -------
        dict of output name -> ndarray (N, size).
        """
        arrays, n = [], None
        for (name, size), value in zip(self.inputs, inputs):
            a = np.ascontiguousarray(value, dtype=np.float64)
            if a.ndim == 1:
                if a.shape[0] != size:
                    raise GsfricError(f"{self.name}: input {name} has {a.shape[0]} values, "
                                      f"expected {size}")
            elif a.ndim == 2 and a.shape[1] == size:
                if n is not None and a.shape[0] != n:
                    raise GsfricError(f"{self.name}: input {name} has {a.shape[0]} steps, "
                                      f"expected {n}")
                n = a.shape[0]
            else:
                raise GsfricError(f"{self.name}: input {name} has shape {a.shape}, expected "
                                  f"(N, {size}) or ({size},)")
            arrays.append(a)
        n = 1 if n is None else n
        # this call's own argument arrays
        in_ptrs = (ctypes.c_void_p * len(arrays))(*[a.ctypes.data for a in arrays])
        in_strides = (ctypes.c_longlong * len(arrays))(
            *[a.shape[1] if a.ndim == 2 else 0 for a in arrays])
        out_ptrs = (ctypes.c_void_p * len(self.outputs))()
        wanted = None if select is None else set(select)
        result = {}
        outputs = outputs or {}
        for k, (name, size, _) in enumerate(self.outputs):
            if wanted is not None and name not in wanted:
                continue
            buf = outputs.get(name)
            if buf is None:
                buf = np.empty((n, size))
            elif buf.shape != (n, size) or buf.dtype != np.float64 or \
                    not buf.flags.c_contiguous:
                raise GsfricError(f"{self.name}: output buffer {name} must be a C-contiguous "
                                  f"float64 array of shape ({n}, {size})")
            out_ptrs[k] = buf.ctypes.data
            result[name] = buf
        flag_ptr = None
        if flags is not None:
            if flag is None or flag.shape != (n,) or flag.dtype != np.int64 or \
                    not flag.flags.c_contiguous:
                raise GsfricError(f"{self.name}: flag must be a C-contiguous int64 array of "
                                  f"shape ({n},)")
            flag_ptr = flag.ctypes.data
        failed = self._lib.gsfric_run(ctypes.byref(self._fn), in_ptrs, in_strides, out_ptrs,
                                      self._out_strides, n, int(n_threads),
                                      None if flags is None else ctypes.byref(flags), flag_ptr)
        if failed:
            raise GsfricError(f"{self.name}: evaluation failed at {failed} steps")
        return result

    def bound(self, constants: list[np.ndarray], output: str, n_threads: int = 1):
        """A lean callable ``f(x, out)`` for the control loop's repeated calls.

        Input 0 varies (``x``, C-contiguous float64 of shape (N, size)); the other inputs are
        fixed to ``constants`` (one block each, broadcast to every step); only ``output`` is
        computed, into ``out`` (C-contiguous float64, (N, size)). Shapes are checked, nothing
        is copied or allocated. The callable holds only read-only arrays (the C side builds
        each call's own argument arrays): threads may share it.
        """
        fixed = [np.ascontiguousarray(c, dtype=np.float64) for c in constants]
        n_in = len(self.inputs)
        fixed_ptrs = (ctypes.c_void_p * n_in)(0, *[c.ctypes.data for c in fixed])
        in_strides = (ctypes.c_longlong * n_in)(self.inputs[0][1], *([0] * (n_in - 1)))
        index = self._index[output]
        size_x, size_out = self.inputs[0][1], self.outputs[index][1]
        run_one, fn = self._lib.gsfric_run_one, ctypes.byref(self._fn)
        out_strides, name, threads = self._out_strides, self.name, int(n_threads)

        def call(x: np.ndarray, out: np.ndarray) -> np.ndarray:
            if (x.dtype != np.float64 or x.ndim != 2 or x.shape[1] != size_x
                    or not x.flags.c_contiguous or out.dtype != np.float64
                    or out.shape != (x.shape[0], size_out) or not out.flags.c_contiguous):
                raise GsfricError(f"{name}: x must be C-contiguous float64 (N, {size_x}) "
                                  f"and out (N, {size_out})")
            run_one(fn, fixed_ptrs, in_strides, out_strides, x.ctypes.data, index,
                    out.ctypes.data, x.shape[0], threads)
            return out

        call.keep = (fixed, fixed_ptrs, in_strides, self)  # alive as long as the callable
        return call


class CasadiFunction:
    """The same interface, evaluated by CasADi from the serialized functions (no compiler)."""

    def __init__(self, f, name: str) -> None:
        meta = function(name)
        self.name = name
        self.inputs = [(i["name"], i["size"]) for i in meta["inputs"]]
        self.outputs = [(o["name"], o["size"], tuple(o["shape"])) for o in meta["outputs"]]
        self._f = f

    def __call__(self, inputs, outputs=None, n_threads: int = 1, select=None) -> dict:
        arrays = [np.asarray(a, dtype=np.float64) for a in inputs]
        n = max([a.shape[0] for a in arrays if a.ndim == 2] or [1])
        cols = [a.T if a.ndim == 2 else np.broadcast_to(a[:, None], (a.shape[0], n))
                for a in arrays]
        mapped = self._f.map(n, "thread", max(1, int(n_threads)))
        res = mapped(*cols)
        res = res if isinstance(res, tuple) else (res,)
        out = {}
        for (name, size, _), value in zip(self.outputs, res):
            if select is not None and name not in select:
                continue
            arr = np.array(value).reshape(size, n).T.copy()
            if outputs and name in outputs:
                outputs[name][...] = arr
                arr = outputs[name]
            out[name] = arr
        return out

    def bound(self, constants: list[np.ndarray], output: str, n_threads: int = 1):
        """``CompiledFunction.bound``'s interface, evaluated by CasADi."""
        def call(x, out):
            out[...] = self([x] + list(constants), n_threads=n_threads,
                            select=(output,))[output]
            return out

        return call


def check_generated() -> None:
    """Warn when generated/ is stale against derive/; fail when its files were altered."""
    from gsfric.manifest import staleness

    reason = staleness()
    if reason is None:
        return
    if reason.startswith("derive/"):
        warnings.warn(f"generated/ is stale: {reason}; run `gsfric derive` to regenerate it",
                      stacklevel=4)
    else:
        raise GsfricError(f"{reason}; regenerate it with `gsfric derive` "
                          "(or restore it with `git checkout generated/`)")


@functools.lru_cache(maxsize=None)
def _library():
    check_generated()
    if os.environ.get("GSFRIC_NO_COMPILE") == "1":
        return None
    try:
        path = build_library()
    except BuildError as exc:
        warnings.warn(f"{exc}; falling back to CasADi's own evaluation (much slower)",
                      stacklevel=3)
        return None
    lib = ctypes.CDLL(str(path))
    lib.gsfric_run.restype = ctypes.c_longlong
    lib.gsfric_run.argtypes = [ctypes.POINTER(_Fn), ctypes.c_void_p, ctypes.c_void_p,
                               ctypes.c_void_p, ctypes.c_void_p, ctypes.c_longlong, ctypes.c_int,
                               ctypes.c_void_p, ctypes.c_void_p]
    lib.gsfric_run_one.restype = ctypes.c_longlong
    lib.gsfric_run_one.argtypes = [ctypes.POINTER(_Fn), ctypes.c_void_p, ctypes.c_void_p,
                                   ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int,
                                   ctypes.c_void_p, ctypes.c_longlong, ctypes.c_int]
    lib.gsfric_simd_lanes.restype = ctypes.c_int
    return lib


@functools.lru_cache(maxsize=None)
def _serialized() -> dict:
    import casadi as ca

    path = generated_dir() / f"{BASENAME}.casadi"
    if not path.exists():
        raise GsfricError(f"{path} is missing: run `gsfric derive`")
    des = ca.FileDeserializer(str(path))
    out = {}
    for _ in manifest()["functions"]:
        f = des.unpack()
        out[f.name()] = f
    return out


@functools.lru_cache(maxsize=None)
def get(name: str):
    """The evaluator of generated function ``name`` (e.g. "eval", "actuator", "jacobian")."""
    lib = _library()
    if lib is not None:
        return CompiledFunction(lib, name)
    return CasadiFunction(_serialized()[f"{BASENAME}_{name}"], name)


def is_compiled() -> bool:
    """True when the compiled library is in use (False: CasADi fallback)."""
    return _library() is not None
