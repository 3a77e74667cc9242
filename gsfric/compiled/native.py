"""Compiled evaluation of the generated functions over batches of steps.

The C code in generated/ and the batch driver ``batch.c`` are compiled once into a
shared library, cached under ``$GSFRIC_CACHE`` (default: the user cache directory) in a folder
named after the hash of the sources, the compiler command and the CPU's instruction-set
features (``-march=native`` code is only valid on the CPU it was built for), and loaded with
ctypes. The driver loops over steps in C, reading and writing NumPy buffers directly (no CasADi
objects on the hot path), optionally on several POSIX threads, and computes the step flags in
the same pass.

The cache is checked before every load: the library's size and SHA-256, recorded beside it when
it was built (``libgsfric.json``), must match; a damaged library (truncated, overwritten) is
removed and rebuilt, never loaded. A build writes to a temporary name, checks that the result is
a shared library, and renames it into place; compilers get ``GSFRIC_CC_TIMEOUT`` seconds
(default 600), after which their whole process group is killed.

Without a working C compiler (not found, failing, timed out), the functions are evaluated by
CasADi itself from the serialized copy in generated/, with a warning: the same numbers, much
slower. A cache that cannot be used (not a directory, not writable) or a compiler whose output
is not a shared library raises ``LibraryError`` (the CLI's exit 3) naming the path or variable.

Environment: ``CC`` (compiler, default ``cc``), ``GSFRIC_CACHE`` (cache directory),
``GSFRIC_CC_TIMEOUT`` (seconds per compiler run), ``GSFRIC_NO_COMPILE=1`` (force the CasADi
fallback), ``GSFRIC_MARCH`` (target CPU, default ``native``; ``x86-64-v3`` for a library that
runs on any AVX2 machine), ``GSFRIC_LANES`` (steps per vector, default from the target: 8 with
AVX-512, 4 with AVX, else 1).
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import hashlib
import json
import os
import platform as _platform_module
import shlex
import signal
import subprocess
import sys
import threading
import time
import warnings
from pathlib import Path

import numpy as np
from platformdirs import user_cache_dir

from gsfric.compiled.manifest import (
    BASENAME,
    function,
    generated_dir,
    manifest,
    staleness,
)
from gsfric.errors import GsfricError

DRIVER = Path(__file__).resolve().parent / "batch.c"


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


CFLAGS = ("-O2", *_target_flags(), "-fno-math-errno", "-freciprocal-math", "-fPIC",
          "-fno-semantic-interposition", "-pthread")
SIMD_CFLAGS = ("-O3", "-fschedule-insns")
"""Added for the SIMD-over-steps source (generated/*_batch.c, the hot paths) when it is
compiled at -O2: instruction scheduling before register allocation, which GCC leaves off on
x86, cuts the spills of vector registers in its long straight-line bodies (1.4x the hot path,
the same results bit for bit: docs/performance.md). CasADi's per-step source keeps -O2 (it is
large, and compiles much longer with these)."""
LIBRARY = "libgsfric.so"
RECORD = "libgsfric.json"
DEFAULT_CC_TIMEOUT = 600.0
"""Seconds a compiler run may take before its process group is killed (``GSFRIC_CC_TIMEOUT``)."""

_SHARED_MAGIC = (b"\x7fELF", b"\xcf\xfa\xed\xfe", b"\xce\xfa\xed\xfe", b"MZ")


class BuildError(GsfricError):
    """The generated C code could not be compiled (gsfric falls back to CasADi)."""

class LibraryError(GsfricError):
    """The compiled-library cache or the compiler's output cannot be used (no fallback)."""

def cache_dir() -> Path:
    """The root of the compiled-library cache: ``$GSFRIC_CACHE`` or the user cache directory."""
    env = os.environ.get("GSFRIC_CACHE")
    if env:
        return Path(env)

    return Path(user_cache_dir("gsfric"))


def _cache_variable() -> str:
    return "GSFRIC_CACHE" if os.environ.get("GSFRIC_CACHE") else "the user cache directory"


def _compiler() -> list[str]:
    """The compiler command from ``CC`` (default ``cc``); ``LibraryError`` if CC is unusable."""
    value = os.environ.get("CC", "cc")
    try:
        command = shlex.split(value)
    except ValueError as error:
        raise LibraryError(f"CC={value!r} cannot be parsed as a command ({error})") from None
    if not command:
        raise LibraryError("CC is set but empty; unset it or name a C compiler (e.g. CC=cc)")
    return command


def _timeout() -> float:
    value = os.environ.get("GSFRIC_CC_TIMEOUT", "")
    if not value:
        return DEFAULT_CC_TIMEOUT
    try:
        seconds = float(value)
    except ValueError:
        seconds = float("nan")
    if not seconds > 0 or seconds == float("inf"):
        raise LibraryError(f"GSFRIC_CC_TIMEOUT={value!r}: expected a positive number of "
                           "seconds")
    return seconds


@functools.lru_cache(maxsize=1)
def cpu_features() -> str:
    """The CPU's architecture and instruction-set flags (``/proc/cpuinfo``), for the cache key."""
    parts = [_platform_module.machine()]
    with contextlib.suppress(OSError):
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as handle:
            for line in handle:
                key, _, value = line.partition(":")
                if key.strip() in ("flags", "Features", "isa"):
                    parts.append(" ".join(sorted(value.split())))
                    break
    if len(parts) == 1:
        parts.append(_platform_module.processor())
    return " | ".join(parts)


def _build_key(sources: list[Path], cmd: list[str]) -> str:
    h = hashlib.sha256()
    for s in sources:
        h.update(s.read_bytes())
    h.update(" ".join(cmd).encode())
    h.update(" ".join(SIMD_CFLAGS).encode())
    h.update(sys.platform.encode())
    h.update(cpu_features().encode())
    return h.hexdigest()[:20]


def _sources() -> list[Path]:
    folder = generated_dir()
    return [DRIVER, folder / f"{BASENAME}.c", folder / f"{BASENAME}_batch.c"]


def _kill(procs: list[subprocess.Popen]) -> None:
    """Kill every still-running compiler's process group and reap it."""
    for p in procs:
        if p.poll() is None:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(p.pid, signal.SIGKILL)
    for p in procs:
        with contextlib.suppress(Exception):
            p.wait(timeout=5)


def _start(commands: list[list[str]], procs: list[subprocess.Popen]) -> None:
    """Start the compilers, each in its own process group, appending each to ``procs`` as
    soon as it runs, in a thread of its own: Python runs signal handlers in the main thread
    only, so an interrupt cannot land between a compiler's start and its entry in ``procs``
    (a compiler nobody would kill). An error starting one is raised here."""
    failure: list[BaseException] = []

    def start() -> None:
        try:
            for cmd in commands:
                procs.append(subprocess.Popen(cmd, stdout=subprocess.PIPE,
                                              stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
                                              text=True, start_new_session=True))
        except BaseException as exc:  # handed to the caller
            failure.append(exc)

    starter = threading.Thread(target=start, name="gsfric-compilers")
    starter.start()
    try:
        starter.join()
    finally:
        while starter.is_alive():  # an interrupt while starting: wait until procs is complete
            with contextlib.suppress(BaseException):
                starter.join()
    if failure:
        raise failure[0]


def _run(commands: list[list[str]], timeout: float) -> list[str]:
    """Run compiler commands in parallel, each in its own process group; their error texts
    ("" for success). A run past ``timeout`` seconds kills them all (``BuildError``); so does
    any exception (an interrupt, a signal) while waiting: no compiler is left behind."""
    procs: list[subprocess.Popen] = []
    try:
        _start(commands, procs)
        deadline = time.monotonic() + timeout
        errors = []
        for p in procs:
            try:
                _, err = p.communicate(timeout=max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                raise BuildError(f"the C compiler ({commands[0][0]}, from CC) did not finish "
                                 f"within {timeout:g} s (GSFRIC_CC_TIMEOUT); it was "
                                 "stopped") from None
            errors.append(err if p.returncode else "")
            if p.returncode and not err.strip():
                errors[-1] = f"{commands[0][0]} exited with status {p.returncode}"
        return errors
    except FileNotFoundError:
        raise BuildError(f"no C compiler: {commands[0][0]!r} was not found (set CC to "
                         "one)") from None
    except PermissionError:
        raise BuildError(f"the C compiler {commands[0][0]!r} (CC) cannot be run "
                         "(permission denied)") from None
    finally:
        _kill(procs)


def _extra_flags(source: Path, flags) -> tuple[str, ...]:
    """``SIMD_CFLAGS`` for the SIMD-over-steps source compiled at -O2, else nothing."""
    return SIMD_CFLAGS if source.name.endswith("_batch.c") and "-O2" in flags else ()


def _compile(cc: list[str], flags, sources: list[Path], target: Path) -> str | None:
    """Compile every source to an object in parallel and link them; an error line or None."""
    objects = [target.with_name(f"{target.stem}.{k}.o") for k in range(len(sources))]
    timeout = _timeout()
    try:
        failed = [e for e in _run([cc + list(flags) + list(_extra_flags(src, flags))
                                   + ["-c", str(src), "-o", str(obj)]
                                   for src, obj in zip(sources, objects)], timeout) if e]
        if not failed:
            failed = [e for e in _run([cc + list(flags) + ["-shared"]
                                       + [str(o) for o in objects]
                                       + ["-o", str(target), "-lm"]], timeout) if e]
    finally:
        for obj in objects:
            obj.unlink(missing_ok=True)
    if not failed:
        return None
    lines = [line for e in failed for line in e.strip().splitlines()]
    return lines[-1] if lines else "(no message)"


def _digest(path: Path) -> tuple[int, str]:
    """(size in bytes, SHA-256 hex) of a file."""
    h = hashlib.sha256()
    size = 0
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            h.update(block)
            size += len(block)
    return size, h.hexdigest()


def _damage(lib: Path, record: Path) -> str | None:
    """Why the cached library must not be loaded ("missing" included), or None if it is sound."""
    try:
        expected = json.loads(record.read_text(encoding="utf-8"))
        size, digest = int(expected["size"]), str(expected["sha256"])
    except FileNotFoundError:
        return "missing" if not lib.exists() else f"{record.name} is missing"
    except (OSError, ValueError, KeyError, TypeError):
        return f"{record.name} is unreadable"
    try:
        actual = lib.stat().st_size
    except FileNotFoundError:
        return "missing"
    except OSError as error:
        return f"cannot be read ({error.strerror})"
    if actual != size:
        return f"its size is {actual} bytes, {size} were recorded at build time"
    try:
        if _digest(lib)[1] != digest:
            return "its SHA-256 differs from the one recorded at build time"
    except OSError as error:
        return f"cannot be read ({error.strerror})"
    return None


def _check_shared_library(path: Path, cc: list[str]) -> None:
    """``LibraryError`` unless ``path`` starts like a shared library (ELF, Mach-O, PE)."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(4)
    except OSError as error:
        raise LibraryError(f"{path}: the compiler (CC={' '.join(cc)}) wrote no readable "
                           f"library ({error.strerror})") from None
    if not any(head.startswith(m) for m in _SHARED_MAGIC):
        raise LibraryError(f"{path}: the compiler (CC={' '.join(cc)}) did not produce a shared "
                           "library; check CC")


def _prepare(folder: Path) -> None:
    """Create the cache folder; ``LibraryError`` naming it when that is impossible."""
    root = cache_dir()
    for part in [root, *reversed(folder.parents)]:
        if part in root.parents:
            continue
        if part.exists() and not part.is_dir():
            raise LibraryError(f"{part}: the compiled-library cache ({_cache_variable()}) is "
                               "not a directory; set GSFRIC_CACHE to a writable directory")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise LibraryError(f"{folder}: cannot create the compiled-library cache "
                           f"({error.strerror}); set GSFRIC_CACHE to a writable "
                           "directory") from None
    if not os.access(folder, os.W_OK | os.X_OK):
        raise LibraryError(f"{folder}: the compiled-library cache ({_cache_variable()}) is not "
                           "writable; set GSFRIC_CACHE to a writable directory")


def _write_record(record: Path, size: int, digest: str) -> None:
    tmp = record.with_name(f".{record.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(json.dumps({"size": size, "sha256": digest}) + "\n", encoding="utf-8")
        tmp.replace(record)
    finally:
        tmp.unlink(missing_ok=True)


def build_library() -> Path:
    """Compile (or find, verified, in the cache) the shared library; returns its path.

    Raises
    ------
    BuildError
        The compiler is missing, fails or times out (callers fall back to CasADi).
    LibraryError
        The cache cannot be used, or the compiler's output is not a shared library.
    """
    sources = _sources()
    for src in sources[1:]:
        if not src.exists():
            raise BuildError(f"{src} is missing: run `gsfric derive` to generate it")
    cc = _compiler()
    key = _build_key(sources, cc + list(CFLAGS))
    folder = cache_dir() / f"build-{key}"
    lib, record = folder / LIBRARY, folder / RECORD
    if _damage(lib, record) is None:
        return lib
    _prepare(folder)
    import fcntl

    try:
        lock = open(folder / ".lock", "w")
    except OSError as error:
        raise LibraryError(f"{folder / '.lock'}: cannot write in the compiled-library cache "
                           f"({error.strerror}); set GSFRIC_CACHE to a writable "
                           "directory") from None
    with lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        damage = _damage(lib, record)
        if damage is None:
            return lib
        if damage != "missing":
            warnings.warn(f"{lib}: the cached compiled library is damaged ({damage}); "
                          "rebuilding it", stacklevel=3)
            lib.unlink(missing_ok=True)
            record.unlink(missing_ok=True)
        for stale in folder.glob(".libgsfric.*"):   # left by a killed build (SIGKILL)
            stale.unlink(missing_ok=True)
        tmp = folder / f".libgsfric.{os.getpid()}.so"
        print(f"gsfric: compiling the generated model (once, 1-2 minutes) into {folder}",
              file=sys.stderr)
        error = "(no message)"
        try:
            for flags in (CFLAGS, tuple(f for f in CFLAGS if not f.startswith("-march")),
                          ("-O1", "-fPIC", "-pthread")):
                error = _compile(cc, flags, sources, tmp)
                if error is None:
                    _check_shared_library(tmp, cc)
                    _write_record(record, *_digest(tmp))
                    tmp.replace(lib)
                    return lib
        except OSError as exc:
            raise LibraryError(f"{folder}: cannot write the compiled library "
                               f"({exc.strerror}); set GSFRIC_CACHE to a writable "
                               "directory") from None
        finally:
            tmp.unlink(missing_ok=True)
        raise BuildError(f"compiling the generated model failed: {error}; check the compiler "
                         "(CC) or regenerate generated/ with `gsfric derive`")


class _Fn(ctypes.Structure):
    _fields_ = [("simd", ctypes.c_void_p), ("eval", ctypes.c_void_p), ("work", ctypes.c_void_p),
                ("n_in", ctypes.c_int), ("n_out", ctypes.c_int)]


class _Bound(ctypes.Structure):
    """The fixed arguments of a control-loop call (``gsfric_bound`` in ``batch.c``)."""

    _fields_ = [("fn", ctypes.POINTER(_Fn)), ("fixed", ctypes.c_void_p),
                ("in_stride", ctypes.c_void_p), ("out_stride", ctypes.c_void_p),
                ("index", ctypes.c_int), ("n_threads", ctypes.c_int)]


class FlagSpec(ctypes.Structure):
    """Settings of the step flags computed in C (``gsfric_flags`` in ``batch.c``)."""

    _fields_ = [("d", ctypes.c_int), ("s2", ctypes.c_int), ("h", ctypes.c_int),
                ("has_stroke", ctypes.c_int), ("stroke_lo", ctypes.c_double),
                ("stroke_hi", ctypes.c_double), ("universal_limit", ctypes.c_double),
                ("singular_limit", ctypes.c_double), ("x_size", ctypes.c_longlong),
                ("cc", ctypes.c_int), ("f0", ctypes.c_int), ("coupling_tol", ctypes.c_double)]


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
                 motion=None) -> dict:
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

        Returns
        -------
        dict of output name -> ndarray (N, size).
        """
        arrays, n = [], None
        parts = None
        if motion is not None:
            parts = _motion_arrays(self.name, motion)
            n = parts[0].shape[0]
        for (name, size), value in zip(self.inputs, inputs):
            if value is None and parts is not None:
                arrays.append(None)
                continue
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
        in_ptrs = (ctypes.c_void_p * len(arrays))(
            *[None if a is None else a.ctypes.data for a in arrays])
        in_strides = (ctypes.c_longlong * len(arrays))(
            *[24 if a is None else a.shape[1] if a.ndim == 2 else 0 for a in arrays])
        motion_ptrs = None if parts is None else \
            (ctypes.c_void_p * 6)(*[a.ctypes.data for a in parts])
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
                                      None if flags is None else ctypes.byref(flags), flag_ptr,
                                      motion_ptrs)
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
        fn = ctypes.byref(self._fn)
        out_strides, name, threads = self._out_strides, self.name, int(n_threads)
        by_object = _objects_readable(self._lib)
        run_one = self._lib.gsfric_run_one_objects if by_object else self._lib.gsfric_run_one
        bound, bound_ref, tuples = self._bound_struct(fixed_ptrs, in_strides, index, threads,
                                                      by_object)
        run_tuple = self._lib.gsfric_bound_states

        def call(x: np.ndarray, out: np.ndarray) -> np.ndarray:
            if (x.dtype != np.float64 or x.ndim != 2 or x.shape[1] != size_x
                    or not x.flags.c_contiguous or out.dtype != np.float64
                    or out.shape != (x.shape[0], size_out) or not out.flags.c_contiguous):
                raise GsfricError(f"{name}: x must be C-contiguous float64 (N, {size_x}) "
                                  f"and out (N, {size_out})")
            if tuples:
                run_tuple(bound_ref, (x, out), x.shape[0])
            elif by_object:
                run_one(fn, fixed_ptrs, in_strides, out_strides, x, index, out, x.shape[0],
                        threads)
            else:
                run_one(fn, fixed_ptrs, in_strides, out_strides, x.ctypes.data, index,
                        out.ctypes.data, x.shape[0], threads)
            return out

        call.keep = (fixed, fixed_ptrs, in_strides, bound, self)  # alive with the callable
        return call

    def _bound_struct(self, fixed_ptrs, in_strides, index: int, threads: int, by_object: bool):
        """The fixed arguments of a bound call in one ``_Bound`` (kept alive by the caller),
        a reference to it, and whether the call may pass its arrays in one tuple; ``(None,
        None, False)`` when it may not (the struct is only read by the tuple calls)."""
        if not (by_object and _tuples_readable(self._lib)):
            return None, None, False
        bound = _Bound(ctypes.pointer(self._fn), ctypes.cast(fixed_ptrs, ctypes.c_void_p),
                       ctypes.cast(in_strides, ctypes.c_void_p),
                       ctypes.cast(self._out_strides, ctypes.c_void_p), index, threads)
        return bound, ctypes.byref(bound), True

    def bound_motion(self, constants: list[np.ndarray], output: str, n_threads: int = 1):
        """``bound``'s callable from a motion's arrays: ``f(position, rotation, velocity,
        omega, acceleration, alpha, out=None)``, shapes (N, 3) and rotation (N, 3, 3); arrays
        that are not C-contiguous float64 are converted; ``out`` (N, size) is allocated when
        not given. The states are laid out in C."""
        fixed = [np.ascontiguousarray(c, dtype=np.float64) for c in constants]
        n_in = len(self.inputs)
        if self.inputs[0][1] != 24:
            raise GsfricError(f"{self.name}: input 0 is not a motion's state")
        fixed_ptrs = (ctypes.c_void_p * n_in)(0, *[c.ctypes.data for c in fixed])
        in_strides = (ctypes.c_longlong * n_in)(24, *([0] * (n_in - 1)))
        index = self._index[output]
        size_out = self.outputs[index][1]
        fn = ctypes.byref(self._fn)
        out_strides, name, threads = self._out_strides, self.name, int(n_threads)
        f64 = np.float64
        by_object = _objects_readable(self._lib)
        run = self._lib.gsfric_run_one_motion_objects if by_object else \
            self._lib.gsfric_run_one_motion
        bound, bound_ref, tuples = self._bound_struct(fixed_ptrs, in_strides, index, threads,
                                                      by_object)
        run_tuple = self._lib.gsfric_bound_motion
        empty = np.empty

        def call(position, rotation, velocity, omega, acceleration, alpha, out=None):
            p = np.ascontiguousarray(position, dtype=f64)
            T = np.ascontiguousarray(rotation, dtype=f64)
            v = np.ascontiguousarray(velocity, dtype=f64)
            w = np.ascontiguousarray(omega, dtype=f64)
            a = np.ascontiguousarray(acceleration, dtype=f64)
            al = np.ascontiguousarray(alpha, dtype=f64)
            n = p.shape[0] if p.ndim == 2 else -1
            three = (n, 3)
            if (p.shape, v.shape, w.shape, a.shape, al.shape, T.shape) != \
                    (three, three, three, three, three, (n, 3, 3)):
                raise GsfricError(f"{name}: position, velocity, omega, acceleration, alpha "
                                  "must be (N, 3) and rotation (N, 3, 3) with the same N; got "
                                  f"{[x.shape for x in (p, T, v, w, a, al)]}")
            if out is None:
                out = empty((n, size_out))
            elif out.dtype != f64 or out.shape != (n, size_out) or not out.flags.c_contiguous:
                raise GsfricError(f"{name}: out must be C-contiguous float64 ({n}, {size_out})")
            if tuples:
                run_tuple(bound_ref, (p, T, v, w, a, al, out), n)
            elif by_object:
                run(fn, fixed_ptrs, in_strides, out_strides, p, T, v, w, a, al, index, out, n,
                    threads)
            else:
                run(fn, fixed_ptrs, in_strides, out_strides, p.ctypes.data, T.ctypes.data,
                    v.ctypes.data, w.ctypes.data, a.ctypes.data, al.ctypes.data, index,
                    out.ctypes.data, n, threads)
            return out

        call.keep = (fixed, fixed_ptrs, in_strides, bound, self)  # alive with the callable
        return call


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


_MOTION_SHAPES = ((3,), (3, 3), (3,), (3,), (3,), (3,))
_MOTION_NAMES = ("position", "rotation", "velocity", "omega", "acceleration", "alpha")


def _motion_arrays(name: str, motion) -> list[np.ndarray]:
    """The six arrays of a motion, C-contiguous float64 with one N, else ``GsfricError``."""
    parts = [np.ascontiguousarray(a, dtype=np.float64) for a in motion]
    if len(parts) != 6:
        raise GsfricError(f"{name}: a motion is 6 arrays, got {len(parts)}")
    n = parts[0].shape[0] if parts[0].ndim else 0
    for part, shape, label in zip(parts, _MOTION_SHAPES, _MOTION_NAMES):
        if part.shape != (n,) + shape:
            raise GsfricError(f"{name}: {label} has shape {part.shape}, expected "
                              f"{(n,) + shape}")
    return parts


def state_of(motion) -> np.ndarray:
    """The (N, 24) state array of a motion's six arrays (p, T row-major, v, omega, a,
    alpha): the one layout in Python (``evaluation.state_array``, the CasADi fallback), the
    same as ``layout_states`` in ``batch.c``."""
    parts = _motion_arrays("motion", motion)
    n = parts[0].shape[0]
    return np.concatenate([p.reshape(n, -1) for p in parts], axis=1)


class CasadiFunction:
    """The same interface, evaluated by CasADi from the serialized functions (no compiler)."""

    def __init__(self, f, name: str) -> None:
        meta = function(name)
        self.name = name
        self.inputs = [(i["name"], i["size"]) for i in meta["inputs"]]
        self.outputs = [(o["name"], o["size"], tuple(o["shape"])) for o in meta["outputs"]]
        self._f = f

    def __call__(self, inputs, outputs=None, n_threads: int = 1, select=None,
                 motion=None) -> dict:
        if motion is not None:
            inputs = [state_of(motion), *list(inputs)[1:]]
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

    def bound_motion(self, constants: list[np.ndarray], output: str, n_threads: int = 1):
        """``CompiledFunction.bound_motion``'s interface, evaluated by CasADi."""
        def call(position, rotation, velocity, omega, acceleration, alpha, out=None):
            x = state_of((position, rotation, velocity, omega, acceleration, alpha))
            value = self([x] + list(constants), n_threads=n_threads, select=(output,))[output]
            if out is None:
                return value
            out[...] = value
            return out

        return call


def check_generated() -> None:
    """Warn when generated/ is stale against derive/; fail when its files were altered."""

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
    try:
        lib = ctypes.CDLL(str(path))
    except OSError as exc:
        raise LibraryError(f"{path}: cannot load the compiled library ({exc}); delete "
                           f"{path.parent} to rebuild it, and check the compiler (CC)") from None
    lib.gsfric_run.restype = ctypes.c_longlong
    lib.gsfric_run.argtypes = [ctypes.POINTER(_Fn), ctypes.c_void_p, ctypes.c_void_p,
                               ctypes.c_void_p, ctypes.c_void_p, ctypes.c_longlong, ctypes.c_int,
                               ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
    lib.gsfric_run_one.restype = ctypes.c_longlong
    lib.gsfric_run_one.argtypes = [ctypes.POINTER(_Fn), ctypes.c_void_p, ctypes.c_void_p,
                                   ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int,
                                   ctypes.c_void_p, ctypes.c_longlong, ctypes.c_int]
    lib.gsfric_run_one_motion.restype = ctypes.c_longlong
    lib.gsfric_run_one_motion.argtypes = [ctypes.POINTER(_Fn), ctypes.c_void_p, ctypes.c_void_p,
                                          ctypes.c_void_p, *([ctypes.c_void_p] * 6),
                                          ctypes.c_int, ctypes.c_void_p, ctypes.c_longlong,
                                          ctypes.c_int]
    objects = [ctypes.POINTER(_Fn), ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
    lib.gsfric_run_one_objects.restype = ctypes.c_longlong
    lib.gsfric_run_one_objects.argtypes = objects + [ctypes.py_object, ctypes.c_int,
                                                     ctypes.py_object, ctypes.c_longlong,
                                                     ctypes.c_int]
    lib.gsfric_run_one_motion_objects.restype = ctypes.c_longlong
    lib.gsfric_run_one_motion_objects.argtypes = objects + [ctypes.py_object] * 6 + [
        ctypes.c_int, ctypes.py_object, ctypes.c_longlong, ctypes.c_int]
    for bound in (lib.gsfric_bound_states, lib.gsfric_bound_motion):
        bound.restype = ctypes.c_longlong
        bound.argtypes = [ctypes.c_void_p, ctypes.py_object, ctypes.c_longlong]
    lib.gsfric_tuple_item.restype = ctypes.c_longlong
    lib.gsfric_tuple_item.argtypes = [ctypes.py_object, ctypes.c_int]
    lib.gsfric_array_data.restype = ctypes.c_longlong
    lib.gsfric_array_data.argtypes = [ctypes.py_object]
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
