"""The compiled model: the generated functions by name, ``get("eval")``.

The generated C code is compiled when the package is built (meson.build), never at run time,
into extension modules of this package, each holding the per-step CasADi functions, the
SIMD-over-steps functions for one instruction set and the batch driver (``batch.c``):

- ``_model``: the architecture's baseline (on x86-64, any x86-64 CPU: the per-step functions
  only; elsewhere with the SIMD-over-steps code, one step at a time);
- on x86-64, ``_model_x86_64_v3`` (AVX2 and FMA: 4 steps per vector) and ``_model_x86_64_v4``
  (AVX-512: 8 steps per vector).

The first ``get`` checks generated/ against derive/ (``check_generated``), asks the baseline
build which of them the CPU runs, and loads the widest with ctypes (``GSFRIC_ISA`` names one
instead: ``baseline``, ``x86-64-v3`` or ``x86-64-v4``). Every build gives the same results to
rounding (tests/test_lanes.py).
"""

from __future__ import annotations

import ctypes
import functools
import importlib.util
import os
import warnings
from pathlib import Path

from gsfric._optional import optional
from gsfric.compiled.functions import CompiledFunction, declare
from gsfric.compiled.manifest import BASENAME, generated_dir, manifest, staleness
from gsfric.errors import GsfricError, InputError, LibraryError

BUILDS = {"baseline": "_model", "x86-64-v3": "_model_x86_64_v3", "x86-64-v4": "_model_x86_64_v4"}
"""Instruction set -> extension module of gsfric.compiled (meson.build's variants)."""
LEVELS = {"baseline": 0, "x86-64-v3": 3, "x86-64-v4": 4}
"""Instruction set -> the level ``gsfric_cpu_level`` (batch.c) reports for a CPU that runs it."""
REINSTALL = ("reinstall gsfric (`pip install --force-reinstall gsfric`, or `make install` in a "
             "source checkout)")


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


def build_path(isa: str) -> Path | None:
    """The file of the build for instruction set ``isa`` (a key of ``BUILDS``), or None when
    this install has none (another architecture)."""
    spec = importlib.util.find_spec(f"{__package__}.{BUILDS[isa]}")
    return None if spec is None or spec.origin is None else Path(spec.origin)


def _load(isa: str) -> ctypes.CDLL:
    path = build_path(isa)
    if path is None:
        raise LibraryError(f"the compiled model {__package__}.{BUILDS[isa]} is missing from "
                           f"this install of gsfric; {REINSTALL}")
    try:
        return declare(ctypes.CDLL(str(path)))
    except (OSError, AttributeError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise LibraryError(f"{path}: the compiled model cannot be loaded ({reason}); "
                           f"{REINSTALL}") from None


def lanes(lib: ctypes.CDLL) -> int:
    """Steps per vector of a loaded build's SIMD-over-steps code; 0 when it has none (the
    per-step functions only)."""
    return lib.gsfric_simd_lanes()


def cpu_builds() -> tuple[str, ...]:
    """The builds this install has and this CPU runs, the widest first."""
    level = _load("baseline").gsfric_cpu_level()
    return tuple(isa for isa in sorted(BUILDS, key=LEVELS.get, reverse=True)
                 if LEVELS[isa] <= level and build_path(isa) is not None)


def chosen_build() -> str:
    """The build loaded: ``$GSFRIC_ISA`` when set, else the widest this CPU runs."""
    isa = os.environ.get("GSFRIC_ISA", "")
    if not isa:
        return cpu_builds()[0]
    if isa not in BUILDS:
        raise InputError(f"GSFRIC_ISA={isa!r}: expected one of {', '.join(BUILDS)}")
    if isa not in cpu_builds():
        raise InputError(f"GSFRIC_ISA={isa!r}: this CPU cannot run that build, or this "
                          f"install has none (builds it can run: {', '.join(cpu_builds())})")
    return isa


@functools.lru_cache(maxsize=None)
def library(isa: str | None = None) -> ctypes.CDLL:
    """The loaded build for instruction set ``isa`` (default: ``chosen_build()``)."""
    check_generated()
    return _load(chosen_build() if isa is None else isa)


@functools.lru_cache(maxsize=None)
def _serialized() -> dict:
    casadi = optional("casadi")
    path = generated_dir() / f"{BASENAME}.casadi"
    if not path.exists():
        raise GsfricError(f"{path} is missing: run `gsfric derive`")
    des = casadi.FileDeserializer(str(path))
    out = {}
    for _ in manifest()["functions"]:
        f = des.unpack()
        out[f.name()] = f
    return out


def serialized(name: str):
    """CasADi's function ``gsfric_model_<name>`` as serialized in generated/ (a
    ``casadi.Function``; needs casadi): for building other functions from it."""
    found = _serialized().get(f"{BASENAME}_{name}")
    if found is None:
        raise GsfricError(f"generated/{BASENAME}.casadi has no function {BASENAME}_{name}; "
                          "run `gsfric derive`")
    return found


@functools.lru_cache(maxsize=None)
def get(name: str, isa: str | None = None) -> CompiledFunction:
    """The evaluator of generated function ``name`` (e.g. "eval", "actuator", "jacobian") in
    the build for ``isa`` (default: ``chosen_build()``)."""
    return CompiledFunction(library(isa), name)
