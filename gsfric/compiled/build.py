"""Compiling the generated C code and the batch driver into one cached shared library.

The C code in generated/ and the batch driver ``batch.c`` are compiled once into a shared
library, cached under ``$GSFRIC_CACHE`` (default: the user cache directory) in a folder named
after the hash of the sources, the compiler command and the CPU's instruction-set features
(``-march=native`` code is only valid on the CPU it was built for).

The cache is checked before every load: the library's size and SHA-256, recorded beside it when
it was built (``libgsfric.json``), must match; a damaged library (truncated, overwritten) is
removed and rebuilt, never loaded. A build writes to a temporary name, checks that the result is
a shared library, and renames it into place; compilers get ``GSFRIC_CC_TIMEOUT`` seconds
(default 600), after which their whole process group is killed.

A compiler that is missing, fails or times out raises ``BuildError`` (callers fall back to
CasADi); a cache that cannot be used (not a directory, not writable) or a compiler whose output
is not a shared library raises ``LibraryError`` (the CLI's exit 3) naming the path or variable.

Environment: ``CC`` (compiler, default ``cc``), ``GSFRIC_CACHE`` (cache directory),
``GSFRIC_CC_TIMEOUT`` (seconds per compiler run), ``GSFRIC_MARCH`` (target CPU, default
``native``; ``x86-64-v3`` for a library that runs on any AVX2 machine), ``GSFRIC_LANES`` (steps
per vector, default from the target: 8 with AVX-512, 4 with AVX, else 1).
"""

from __future__ import annotations

import contextlib
import fcntl
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

from platformdirs import user_cache_dir

from gsfric.compiled.manifest import BASENAME, generated_dir
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
the same results bit for bit: docs/explanation/performance.md). CasADi's per-step source keeps -O2 (it is
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
        _clear(folder, lib, record, damage)
        return _build(cc, sources, folder, lib, record)


def _clear(folder: Path, lib: Path, record: Path, damage: str) -> None:
    """Remove a damaged library (with a warning) and the temporary files of killed builds."""
    if damage != "missing":
        warnings.warn(f"{lib}: the cached compiled library is damaged ({damage}); "
                      "rebuilding it", stacklevel=4)
        lib.unlink(missing_ok=True)
        record.unlink(missing_ok=True)
    for stale in folder.glob(".libgsfric.*"):   # left by a killed build (SIGKILL)
        stale.unlink(missing_ok=True)


def _build(cc: list[str], sources: list[Path], folder: Path, lib: Path, record: Path) -> Path:
    """Compile into a temporary name, with ever fewer flags until one set works; check the
    result, record its digest and rename it to ``lib`` (under the cache's lock)."""
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
