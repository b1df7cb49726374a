"""Stamps of the results suite's outputs: what made a folder (the tool's bytes, the arguments, the
inputs' bytes), so that a later suite run reuses it only when it would make the same again.

A rendered sequence is always reused when its stamp matches (the renderer is deterministic); a run
of cge_slam or of ORB-SLAM2 only with --reuse, since its times are measurements of the moment it
ran. Without a matching stamp the output is made again.
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

STAMP = ".results_stamp.json"
_digests: dict[tuple[str, int, int], str] = {}


def file_digest(path: Path) -> str:
    """sha256 of a file's bytes (cached per path, size and modification time)."""
    st = path.stat()
    key = (str(path.resolve()), st.st_size, st.st_mtime_ns)
    if key not in _digests:
        h = hashlib.sha256()
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
        _digests[key] = h.hexdigest()
    return _digests[key]


def input_digest(path: Path) -> str:
    """What identifies an input: a file's bytes, or every file of a folder (its stamp aside) by relative
    path and bytes. Content, not provenance: a sequence rendered again by a changed cge_sim into the same
    bytes leaves the runs on it reusable."""
    if path.is_file():
        return file_digest(path)
    h = hashlib.sha256()
    for file in sorted(p for p in path.rglob("*") if p.is_file() and p.name != STAMP):
        h.update(str(file.relative_to(path)).encode() + b"\0" + file_digest(file).encode())
    return h.hexdigest()


def make(tool: Path, argv: list[str], inputs: list[Path], extra: dict | None = None) -> str:
    """The stamp text of one output: the tool's digest, its arguments and its inputs' digests."""
    return json.dumps({"tool": file_digest(tool), "argv": [str(a) for a in argv],
                       "inputs": {str(p): input_digest(p) for p in inputs}, "extra": extra or {}},
                      sort_keys=True, indent=1)


def matches(folder: Path, stamp: str) -> bool:
    path = folder / STAMP
    return path.is_file() and path.read_text(encoding="utf-8") == stamp


def write(folder: Path, stamp: str) -> None:
    (folder / STAMP).write_text(stamp, encoding="utf-8")
