"""The hash of the derivation's sources (no SymPy needed, so the runtime can check staleness).

Only the modules that generate code are hashed: editing the errata modules (printed.py,
printed_legs.py), which generate nothing, leaves generated/ current. tests/test_derivation.py
checks that ``GENERATING`` is exactly the set of derive/ modules that ``derive.build`` imports.
"""

import hashlib
from pathlib import Path

DERIVE = Path(__file__).resolve().parent

GENERATING = ("build.py", "bushing.py", "chain.py", "conditioning.py", "coupled.py",
              "effects.py", "envelope.py", "friction.py", "kinematics.py", "leg_frames.py",
              "legs.py", "mechanics.py", "model.py", "platform.py", "prismatic.py", "simd.py",
              "sources.py", "vectors.py")
"""The derive/ modules whose content determines generated/ (``derive.build`` and its imports)."""

RUNTIME_GENERATING = ("gsfric/compiled/instructions.py",)
"""The runtime modules that derive/ prints code with (paths from the repository's root): the
C text of CasADi's operations, shared with ``gsfric export``."""


def source_hash(directory: Path = DERIVE) -> str:
    """SHA-256 over the code-generating sources (names and contents, in name order): derive/'s
    ``GENERATING`` and the ``RUNTIME_GENERATING`` modules beside it.

    Parameters
    ----------
    directory : Path
        The derive/ directory (the runtime modules are read from its parent).

    Returns
    -------
    str
        64 hexadecimal digits; line endings are normalised, so a checkout with CRLF agrees.
    """
    h = hashlib.sha256()
    for name in sorted(GENERATING):
        path = Path(directory) / name
        h.update(name.encode())
        h.update(b"\0")
        h.update(path.read_bytes().replace(b"\r\n", b"\n") if path.exists() else b"")
        h.update(b"\0")
    for name in RUNTIME_GENERATING:
        path = Path(directory).parent / name
        h.update(name.encode())
        h.update(b"\0")
        h.update(path.read_bytes().replace(b"\r\n", b"\n") if path.exists() else b"")
        h.update(b"\0")
    return h.hexdigest()
