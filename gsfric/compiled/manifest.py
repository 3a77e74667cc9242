"""The manifest of generated/: functions, their inputs and outputs, the effect catalog.

Read once, on first use. The generated files are package data of ``gsfric._generated``: the
build maps the repository's top-level generated/ folder there (pyproject.toml), so a wheel holds
them in ``gsfric/_generated/`` and an editable install reads the checkout's generated/; both are
found with ``importlib.resources``. ``GSFRIC_GENERATED`` points to another generated/ directory.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.resources
import importlib.util
import json
import os
from pathlib import Path

from gsfric.errors import GsfricError

BASENAME = "gsfric_model"


PACKAGE = "gsfric._generated"


def generated_dir() -> Path:
    """The directory of the generated files.

    ``$GSFRIC_GENERATED`` when set; else the resources of the ``gsfric._generated`` package
    (``gsfric/_generated/`` of an installed wheel, found with ``importlib.resources``); else the
    generated/ folder beside the package, which is where a source checkout and an editable
    install keep it (setuptools' editable finder does not import a mapped folder without an
    ``__init__.py``, so there the checkout's folder is read directly).
    """
    env = os.environ.get("GSFRIC_GENERATED")
    if env:
        return Path(env)
    return _packaged_dir()


@functools.lru_cache(maxsize=None)
def _packaged_dir() -> Path:

    try:
        folder = importlib.resources.files(PACKAGE)
    except ModuleNotFoundError:
        folder = None
    if folder is not None:
        candidate = folder / "manifest.json"
        if candidate.is_file():
            return Path(str(candidate)).parent
    return Path(__file__).resolve().parents[2] / "generated"


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
