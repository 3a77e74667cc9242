"""The hash of the derivation's sources (no SymPy needed, so the runtime can check staleness)."""

import hashlib
from pathlib import Path

DERIVE = Path(__file__).resolve().parent


def source_hash(directory: Path = DERIVE) -> str:
    """SHA-256 over the derive/ sources (names and contents, sorted by name)."""
    h = hashlib.sha256()
    for path in sorted(Path(directory).glob("*.py")):
        h.update(path.name.encode())
        h.update(b"\0")
        h.update(path.read_bytes().replace(b"\r\n", b"\n"))
        h.update(b"\0")
    return h.hexdigest()
