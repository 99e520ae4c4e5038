"""Registry entries for our own formats: the ``SEQ/`` directory and the ``.npz`` file
(the readers themselves are in :mod:`depthtrack.io.sequence`)."""
from __future__ import annotations

import zipfile

from .registry import Reader
from .sequence import open_native


def _is_sequence_dir(path, head) -> bool:
    return path.is_dir() and (path / "sequence.json").is_file()


def _is_sequence_npz(path, head) -> bool:
    # The suffix claims it (so a wrong .npz gets the native reader's precise error);
    # without it, an .npz is a zip archive holding meta.npy and depth.npy.
    if path.suffix.lower() == ".npz":
        return True
    if not head.startswith(b"PK\x03\x04"):
        return False
    with zipfile.ZipFile(path) as z:
        names = set(z.namelist())
    return {"meta.npy", "depth.npy"} <= names


def _open(path, **options):
    return open_native(path)


READERS = {
    "depthtrack-directory": Reader(
        "depthtrack-directory", _open, sniff=_is_sequence_dir,
        description="depthtrack sequence directory (sequence.json + depth/*.png)"),
    "depthtrack-npz": Reader(
        "depthtrack-npz", _open, suffixes=(".npz",), sniff=_is_sequence_npz,
        description="depthtrack sequence .npz"),
}
