"""Output places checked before any work, and the marker file that says who wrote one.

Every command calls :func:`check_output` on each output right after parsing its
arguments, so a bad output place is refused in one line before minutes of work:

* the parent must be a writable directory (or creatable: no file on the way);
* the output must not be one of the inputs, inside one, or hold one;
* a file output must not be an existing directory, a directory output not a file;
* an existing non-empty directory is only replaced when it holds an earlier output of
  the same command (its marker file, :data:`MARKER`, says so) or with ``--force``.

The check also cleans the temporaries that killed runs left beside the output
(:func:`depthtrack.io.atomic.clean_stale`) and records the command, so that
:func:`depthtrack.io.atomic.atomic_path` writes the marker into the new directory.
"""
from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

from ..errors import InputError

#: Marker file in every directory a command writes: ``{"format", "command", "version"}``.
MARKER = ".depthtrack-output.json"
MARKER_FORMAT = "depthtrack-output/1"

#: Outputs planned by :func:`check_output` in this process: {resolved path: command}.
_PLANNED: dict = {}


def _resolve(path) -> Path:
    return Path(os.path.abspath(os.fspath(path))).resolve()


def _inside(a: Path, b: Path) -> bool:
    """Whether ``a`` is ``b`` or lies inside it (both resolved)."""
    return a == b or b in a.parents


def _version() -> str:
    try:
        from importlib.metadata import version
        return version("depthtrack")
    except Exception:                        # running from a checkout that is not installed
        return "0.1.0"


def read_marker(directory):
    """The marker of ``directory`` as a dict, or ``None`` when absent or unreadable."""
    try:
        data = json.loads((Path(directory) / MARKER).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) and data.get("format") == MARKER_FORMAT else None


def write_marker(directory, command: str) -> None:
    """Write the marker naming ``command`` into ``directory`` (a directory being built)."""
    data = {"format": MARKER_FORMAT, "command": command, "version": _version()}
    (Path(directory) / MARKER).write_text(json.dumps(data) + "\n", encoding="utf-8")


def planned_command(path):
    """The command that planned ``path`` as its output in this process, or ``None``."""
    return _PLANNED.get(_resolve(path))


def _check_parent(path: Path, shown: Path) -> None:
    """The nearest existing ancestor must be a directory we can create files in."""
    ancestor = path.parent
    while not os.path.lexists(ancestor) and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise InputError(shown, f"cannot be created: {ancestor} is a file, not a directory")
    try:                                       # the only sure test (read-only mounts, ACLs, root)
        fd, probe = tempfile.mkstemp(prefix=".depthtrack-probe.", dir=ancestor)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        from .atomic import describe_os_error
        raise InputError(shown, f"cannot write in {ancestor} ({describe_os_error(exc)})") from None


def check_output(path, inputs=(), kind: str = "dir", force: bool = False, command: str = "track",
                 option: str | None = None) -> Path:
    """Refuse a bad output place before any work; plan the output for the marker.

    Parameters
    ----------
    path : path-like
        The output the user named.
    inputs : iterable of path-like
        Files and directories the command reads (the output may not be, be inside, or
        hold any of them); ``None`` entries are skipped.
    kind : {"dir", "file"}
    force : bool
        Replace an existing non-empty directory that holds no earlier output of ``command``.
    command : str
        The command's name as in its marker (``track``, ``eval``, ``synth``, ...).
    option : str or None
        The option that named the output (``--report``), for the messages.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    InputError
        One line naming the output and the problem.
    """
    from .atomic import clean_stale

    if kind not in ("dir", "file"):
        raise ValueError(f"kind must be 'dir' or 'file', not {kind!r}")
    shown = Path(path)
    if not os.fspath(path).strip():
        raise InputError(None, f"{option or 'output'}: empty path")
    real = _resolve(path)
    if len(os.fsencode(real.name)) > 255 - 40 or len(os.fsencode(real)) > 4000:
        raise InputError(shown, "name too long for the file system (with room for the temporary name)")
    what = f"the output ({option}) " if option else "the output "
    for inp in inputs:
        if inp is None:
            continue
        src = _resolve(inp)
        if real == src:
            raise InputError(shown, f"{what}is the input {inp}; choose another place")
        if _inside(real, src):
            raise InputError(shown, f"{what}lies inside the input {inp}; choose another place")
        if _inside(src, real):
            raise InputError(shown, f"{what}would replace a directory holding the input {inp}")
    _check_parent(real, shown)
    if os.path.lexists(real):
        if kind == "file" and real.is_dir():
            raise InputError(shown, f"{what}is an existing directory; give a file name")
        if kind == "dir" and not real.is_dir():
            raise InputError(shown, f"{what}exists and is not a directory")
        if kind == "dir":
            clean_stale(real)
            try:
                entries = [e for e in os.listdir(real) if e != MARKER]
            except OSError as exc:
                from .atomic import describe_os_error
                raise InputError(shown, f"cannot list ({describe_os_error(exc)})") from None
            marker = read_marker(real)
            ours = marker is not None and marker.get("command") == command
            if entries and not ours and not force:
                whose = (f"an output of `depthtrack {marker.get('command')}`" if marker is not None
                         else f"not an earlier output of `depthtrack {command}`")
                raise InputError(shown, f"{what}is a non-empty directory, {whose}; choose a new "
                                        f"place or pass --force to replace it")
    clean_stale(real)
    _PLANNED[real] = command
    return shown


__all__ = ["check_output", "read_marker", "write_marker", "planned_command",
           "MARKER"]
