"""The manifest of generated/: functions, their inputs and outputs, the effect catalog.

Read once, on first use. The generated files are package data: the build (meson.build)
installs the repository's top-level generated/ folder as ``gsfric/_generated/``, where an
installed package finds them; a source checkout (and its editable install) reads the checkout's
generated/ itself. ``GSFRIC_GENERATED`` points to another generated/ directory.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import json
import os
from pathlib import Path

from gsfric.errors import GsfricError

BASENAME = "gsfric_model"
PACKAGE_ROOT = Path(__file__).resolve().parents[1]


def generated_dir() -> Path:
    """The directory of the generated files: ``$GSFRIC_GENERATED`` when set, else
    ``gsfric/_generated/`` of an installed package, else the checkout's generated/ beside the
    package folder."""
    env = os.environ.get("GSFRIC_GENERATED")
    if env:
        return Path(env)
    installed = PACKAGE_ROOT / "_generated"
    return installed if installed.is_dir() else PACKAGE_ROOT.parent / "generated"


@functools.lru_cache(maxsize=None)
def manifest() -> dict:
    path = generated_dir() / "manifest.json"
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise GsfricError(f"{path} is missing: run `gsfric derive` to generate the model") from None
    except json.JSONDecodeError as exc:
        raise GsfricError(f"{path} is not valid JSON ({exc}); run `gsfric derive`") from None


def function(name: str) -> dict:
    """The manifest entry of generated function ``gsfric_model_<name>``."""
    full = f"{BASENAME}_{name}"
    for f in manifest()["functions"]:
        if f["name"] == full:
            return f
    raise GsfricError(f"generated/ has no function {full}; run `gsfric derive`")


def layout(function_name: str, input_name: str) -> list[dict]:
    """Blocks (name, offset, shape, unit, description) of one flat input vector."""
    for item in function(function_name)["inputs"]:
        if item["name"] == input_name:
            return item["layout"]
    raise GsfricError(f"function {function_name} has no input {input_name}")


def staleness() -> str | None:
    """Why generated/ does not match what it was generated from, or None.

    Checks the generated files against the hashes in the manifest and, when the derive/
    sources are beside generated/ (a source checkout), their hash against the manifest's.
    """

    folder = generated_dir()
    for name, digest in manifest().get("files", {}).items():
        path = folder / name
        if not path.exists() or hashlib.sha256(path.read_bytes()).hexdigest() != digest:
            return f"generated/{name} does not match generated/manifest.json"
    sources = folder.parent / "derive" / "sources.py"
    if sources.exists():
        spec = importlib.util.spec_from_file_location("_gsfric_derive_sources", sources)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        if module.source_hash(sources.parent) != manifest().get("source_hash"):
            return "derive/ changed since generated/ was written"
    return None


def jacobian_platform_parameters() -> tuple[str, ...]:
    """The platform parameters (of P) at the head of the generated Jacobian's theta.

    The one list is ``derive/build.py: JACOBIAN_P``, written into generated/manifest.json; the
    effect parameters follow them in theta (``jacobian_parameters`` in the manifest).

    Returns
    -------
    tuple of str
        Names of the ``PARAMETERS`` blocks, in theta's order.
    """
    try:
        return tuple(manifest()["jacobian_platform_parameters"])
    except KeyError:
        raise GsfricError(f"{generated_dir() / 'manifest.json'} has no "
                          "jacobian_platform_parameters; run `gsfric derive`") from None
