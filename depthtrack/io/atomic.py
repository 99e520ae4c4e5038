"""Write outputs so that a failure or a kill never leaves a half-written file or directory.

Everything is written into a temporary sibling of the output, named
``.NAME.depthtrack-tmp.HOST.PID.XXXX`` (hidden, and recognisable with the writer's
process id). Only when the writing finished is the new output swapped in:

1. an existing output directory is renamed aside (into the temporary sibling),
2. the new output is renamed into place,
3. the temporary sibling, the old output with it, is deleted.

Renames within a directory are atomic, so a kill at any point leaves either the old
output or the new one complete at ``NAME`` — except between steps 1 and 2, where the
old one is complete inside the temporary sibling. The next write to the same output
(:func:`clean_stale`, also called by :func:`depthtrack.io.outputs.check_output`) moves
it back and deletes the temporaries of writers that are no longer alive. A file output
is replaced by a single rename (step 2), which needs no step 1.
"""
from __future__ import annotations

import contextlib
import errno
import os
import re
import shutil
import socket
import tempfile
from pathlib import Path

#: Tag in the names of temporary siblings.
TMP_TAG = "depthtrack-tmp"
#: Where, inside a temporary sibling, a replaced output waits for its deletion.
_OLD = ".old"
_NAME_LIMIT = 80                      # file names stay well under the 255-byte limit


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9-]", "-", socket.gethostname())[:24] or "host"


def _prefix(path: Path) -> str:
    """Common start of the temporary siblings' names of ``path`` (any writer)."""
    return f".{path.name[:_NAME_LIMIT]}.{TMP_TAG}."


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:                     # someone else's live process
        return True
    return True


def clean_stale(path) -> list:
    """Remove the temporary siblings of ``path`` left by killed writers on this host.

    A replaced output that a kill caught between the two renames (``path`` itself
    missing) is moved back to ``path`` first. Temporaries of live processes and of
    other hosts are left alone.

    Returns
    -------
    list of pathlib.Path
        The temporaries removed.
    """
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    prefix = _prefix(path)
    host = _host()
    removed = []
    try:
        entries = list(os.scandir(parent))
    except OSError:
        return removed
    for entry in entries:
        if not entry.name.startswith(prefix):
            continue
        fields = entry.name[len(prefix):].split(".")
        if len(fields) < 3 or fields[0] != host or not fields[1].isdigit():
            continue
        pid = int(fields[1])
        if pid == os.getpid() or _pid_alive(pid):
            continue
        stale = Path(entry.path)
        old = stale / _OLD
        if os.path.lexists(old) and not os.path.lexists(path):
            os.rename(old, path)
        shutil.rmtree(stale, ignore_errors=True)
        removed.append(stale)
    return removed


def _swap_in(new: Path, path: Path, tmp: Path) -> None:
    """Rename ``new`` onto ``path``; an existing directory goes aside into ``tmp`` first."""
    if path.is_dir() and not path.is_symlink():
        os.rename(path, tmp / _OLD)
        try:
            os.rename(new, path)
        except BaseException:
            os.rename(tmp / _OLD, path)
            raise
    else:
        os.replace(new, path)


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path``; swap it onto ``path`` on success.

    Works for files and directories alike: whatever the caller creates at the
    yielded path replaces ``path`` only if the block finishes without error (see the
    module docstring for the order of renames). A directory output gets the marker
    file of :mod:`depthtrack.io.outputs` when a command planned it with
    :func:`~depthtrack.io.outputs.check_output`.
    """
    from .outputs import planned_command, write_marker

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    clean_stale(path)
    tmp = Path(tempfile.mkdtemp(prefix=f"{_prefix(path)}{_host()}.{os.getpid()}.", dir=path.parent))
    target = tmp / path.name
    try:
        yield target
        command = planned_command(path)
        if command is not None and target.is_dir() and not target.is_symlink():
            write_marker(target, command)
        _swap_in(target, path, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def write_bytes_atomic(path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    with atomic_path(path) as tmp:
        Path(tmp).write_bytes(data)


def write_text_atomic(path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    write_bytes_atomic(path, text.encode("utf-8"))


def describe_os_error(exc: OSError) -> str:
    """A short phrase for an OSError (``no space left on device``, ``permission denied``...)."""
    if exc.errno == errno.ENOSPC:
        return "no space left on device"
    return (exc.strerror or str(exc)).lower()
