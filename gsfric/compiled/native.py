"""The generated functions by name, compiled on first use: ``get("eval")``, ``is_compiled()``.

The first ``get`` checks generated/ against derive/ (``check_generated``), then compiles, or
finds in the cache, the shared library of the generated C code and the batch driver
(``gsfric.compiled.build``) and loads it with ctypes (``gsfric.compiled.functions``).

Without a working C compiler (not found, failing, timed out), the functions are evaluated by
CasADi itself from the serialized copy in generated/, with a warning: the same numbers, much
slower. ``GSFRIC_NO_COMPILE=1`` forces that fallback.
"""

from __future__ import annotations

import ctypes
import functools
import os
import warnings

from gsfric._optional import optional
from gsfric.compiled.build import BuildError, LibraryError, build_library
from gsfric.compiled.functions import CasadiFunction, CompiledFunction, declare
from gsfric.compiled.manifest import BASENAME, generated_dir, manifest, staleness
from gsfric.errors import GsfricError


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
    return declare(lib)


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
def get(name: str):
    """The evaluator of generated function ``name`` (e.g. "eval", "actuator", "jacobian")."""
    lib = _library()
    if lib is not None:
        return CompiledFunction(lib, name)
    return CasadiFunction(_serialized()[f"{BASENAME}_{name}"], name)


def is_compiled() -> bool:
    """True when the compiled library is in use (False: CasADi fallback)."""
    return _library() is not None
