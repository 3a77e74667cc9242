"""``gsfric identify``'s files: read a measured record, identify, write ``platform.toml`` and
``identification.json`` into an output folder at once (a temporary folder renamed)."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np

from gsfric.errors import InputError
from gsfric.identification.fit import identify, unflagged_steps, validate
from gsfric.identification.results import Identification
from gsfric.identification.settings import CONFIDENCE_Z, PRIOR_LOAD_RATIO
from gsfric.io.files import output_folder
from gsfric.io.readers import read_measured_columns
from gsfric.models import check_measured_forces, platform_from
from gsfric.platform.text import commented_toml
from gsfric.platform.usable import check_force_channels, check_poses
from gsfric.signal.savgol import DEFAULT_POLYORDER

OUTPUTS = ("platform.toml", "identification.json")


def file_sha256(path: str | os.PathLike[str]) -> str:
    """SHA-256 of a file's bytes, hexadecimal."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def read_record(path: str | os.PathLike[str], platform, log_format=None):
    """Motion and forces (N, 6) N of a measured file, checked against the platform's stroke
    and force range as ``discover`` checks them (the force range against the prior as a guess:
    ``PRIOR_LOAD_RATIO``), and refused, naming it, when the model flags most of its steps."""
    motion, forces, _, _ = read_measured_columns(path, None, DEFAULT_POLYORDER, log_format)
    check_poses(platform, motion.position, motion.rotation, motion.t, str(path))
    check_measured_forces(platform, motion, forces, str(path), PRIOR_LOAD_RATIO)
    unflagged_steps(platform, motion, str(path))
    return motion, forces


def identify_file(measured: str | os.PathLike[str], platform_file=None, *,
                  validate_file=None, sensors: bool = False, force_noise=None,
                  log_format=None) -> Identification:
    """Read a measured file and a validation record (both before the fit: a bad second file
    is refused at once), identify, keep the source's hash."""
    digest = file_sha256(measured)
    if validate_file is not None and file_sha256(validate_file) == digest:
        raise InputError(f"--validate: {validate_file} holds the same record as --measured "
                         f"{measured}: a validation needs a record the fit has not seen")
    prior = platform_from(platform_file)
    motion, forces = read_record(measured, prior, log_format)
    second = None if validate_file is None else read_record(validate_file, prior, log_format)
    if second is not None:
        check_force_channels(second[0].t, second[1], str(validate_file))
    result = identify(motion, forces, prior, sensors=sensors, force_noise=force_noise)
    result.source, result.source_sha256 = str(measured), digest
    if second is not None:
        result.validation = validate(result, *second, str(validate_file))
    return result


def _notes(result: Identification) -> dict[str, str]:
    """Each identified platform key's 95 % interval (or why it is the prior's), for comments."""
    notes = {}
    for name, e in result.parameters.items():
        key = name if not name.startswith("effects.") else ".".join(name.split(".")[:2])
        if e.std is not None:
            text = f"{name} = {e.value:.6g} +- {CONFIDENCE_Z * e.std:.3g} {e.unit} (95 %)"
        elif not e.moved:
            text = f"{name} not identified (the prior's value)"
        else:
            text = f"{name} not identified alone (prior {e.prior:.6g}; identification.json)"
        if key.startswith("platform.first_moment"):
            key = "platform.com"
        elif key.startswith("platform.inertia_origin"):
            key = "platform.inertia"
        notes[key] = f"{notes[key]}; {text}" if key in notes else text
    if any(n.startswith("platform.") for n in result.parameters):
        notes["platform.payload_mass"] = "folded into the platform: the motion sees the sum"
    return notes


def write_outputs(result: Identification, out_dir: str | os.PathLike[str],
                  inputs=()) -> list[Path]:
    """Write ``platform.toml`` and ``identification.json`` into ``out_dir`` (both or neither).

    Raises
    ------
    InputError
        The result is implausible (``Identification.implausible``): nothing is written.
    """
    if result.implausible:
        raise InputError("identify: implausible result, platform file not written: "
                          + "; ".join(result.implausible))
    header = ["identified by gsfric identify", f"source: {result.source}",
              f"source sha256: {result.source_sha256}",
              f"residual {np.sqrt(np.mean(result.residual ** 2)):.4g} N RMS vs noise "
              f"{np.sqrt(np.mean(result.noise ** 2)):.4g} N; intervals are 95 %"]
    text = commented_toml(result.platform, header=header, notes=_notes(result))
    with output_folder(out_dir, inputs=inputs) as tmp:
        (tmp / OUTPUTS[0]).write_text(text, encoding="utf-8")
        (tmp / OUTPUTS[1]).write_text(json.dumps(result.summary(), indent=2, allow_nan=False)
                                      + "\n", encoding="utf-8")
    return [Path(out_dir) / name for name in OUTPUTS]
