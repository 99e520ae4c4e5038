"""What a result was computed with, beside the rasteriser (:func:`.render.context.gl_info`).

A track's outcome can follow the last bits of a floating-point result: the test sequences,
synthesized and tracked again by the same code on a fresh install (other versions of the
numeric libraries), came out as before to the digit on some tracks and up to nine points
within 10 cm apart on others (README, "Benchmark"). So every ``summary.json`` names the
versions it was computed with (``software``), and two figures can be told apart by them.

The same versions on two machines did not agree either: OpenBLAS picks its matrix kernels by
the CPU it finds (``SkylakeX`` on one with AVX-512, ``Haswell`` or ``Zen`` on one with
AVX2 only), and the kernels sum in different orders. A start's score on one cartwheel
sequence came out 29837.3 with the first and 29828.9 with the others, and whole tracks
ended apart by up to 17 points within 10 cm (README, "The same figures on another machine"). So
:func:`pin_blas_kernels`, called by ``depthtrack/__init__.py`` before numpy is first
imported, asks OpenBLAS for its Haswell kernels on every x86-64 CPU that runs them, and
``summary.json`` names the kernels a track was computed with (``blas``,
:func:`blas_kernels`).
"""
from __future__ import annotations

import os
import platform
import sys
from importlib import metadata

#: OpenBLAS's kernel family asked for on x86-64 (``OPENBLAS_CORETYPE``): Haswell's run on
#: every x86-64 CPU with AVX2 and FMA (2013 on), and are what OpenBLAS itself picks on
#: those without AVX-512; the README's cartwheel tracks of 2026-11-29 to 2026-12-01 reproduce
#: with them (README, "The same figures on another machine").
BLAS_CORE = "Haswell"

#: Why the kernels are or are not :data:`BLAS_CORE`'s, set by :func:`pin_blas_kernels`:
#: "pinned", "OPENBLAS_CORETYPE set" (the user's choice stands), "DEPTHTRACK_BLAS=native"
#: (the user's opt-out), "numpy imported first" (too late: OpenBLAS has chosen), "CPU not
#: read" (not Linux: OpenBLAS chooses) or "no AVX2 and FMA" (another CPU: OpenBLAS chooses).
BLAS_PIN = "not called"

#: ``summary.json`` key -> the distributions that provide it, first found wins (OpenCV
#: comes under several names).
DISTRIBUTIONS = {
    "depthtrack": ("depthtrack",),
    "numpy": ("numpy",),
    "scipy": ("scipy",),
    "scikit-learn": ("scikit-learn",),
    "opencv": ("opencv-python-headless", "opencv-python", "opencv-contrib-python-headless",
               "opencv-contrib-python"),
    "moderngl": ("moderngl",),
    "trimesh": ("trimesh",),
}


def software_versions() -> dict:
    """``{"python": "3.11.7", "numpy": "2.4.6", ...}``: Python's version and each of
    :data:`DISTRIBUTIONS`' installed version (None where none of its names is installed)."""
    out = {"python": platform.python_version()}
    for key, names in DISTRIBUTIONS.items():
        out[key] = next((v for v in map(_version, names) if v is not None), None)
    return out


def _version(name: str):
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return None


def pin_blas_kernels(environ=None, modules=None, cpu_flags=None) -> str:
    """Ask OpenBLAS for :data:`BLAS_CORE`'s kernels, so that a track is the same number on
    every x86-64 machine; returns why it did or did not (kept in :data:`BLAS_PIN` when it
    acted on this process).

    It sets ``OPENBLAS_CORETYPE``, which OpenBLAS reads once, when it is loaded: only before
    numpy's first import, and only where neither that variable nor ``DEPTHTRACK_BLAS=native``
    is set. Child processes (a Dask worker, a tool's subprocess) inherit the variable.
    ``environ``, ``modules`` and ``cpu_flags`` (a set of /proc/cpuinfo flags) default to
    this process's; the tests pass their own.
    """
    global BLAS_PIN
    own = environ is None
    environ = os.environ if environ is None else environ
    modules = sys.modules if modules is None else modules
    if "OPENBLAS_CORETYPE" in environ:
        reason = "OPENBLAS_CORETYPE set"
    elif environ.get("DEPTHTRACK_BLAS", "").lower() == "native":
        reason = "DEPTHTRACK_BLAS=native"
    elif "numpy" in modules:
        reason = "numpy imported first"
    elif (flags := _cpu_flags() if cpu_flags is None else set(cpu_flags)) is None:
        reason = "CPU not read"
    elif not {"avx2", "fma"} <= flags:
        reason = "no AVX2 and FMA"
    else:
        environ["OPENBLAS_CORETYPE"] = BLAS_CORE
        reason = "pinned"
    if own:
        BLAS_PIN = reason
    return reason


def _cpu_flags():
    """The CPU's feature flags from /proc/cpuinfo (a set; empty on a CPU that is not x86-64),
    or None where they cannot be read without loading a library (not Linux): no pin there."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return set()
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as f:
            for line in f:
                if line.startswith("flags"):
                    return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return None


def blas_kernels() -> dict:
    """``{"pin": BLAS_PIN, "coretype": ..., "libraries": [{"library", "version",
    "architecture", "threads"}, ...]}``: the BLAS libraries loaded in this process (numpy's OpenBLAS,
    and scipy's once scipy.linalg is loaded) and the kernels each chose."""
    from threadpoolctl import threadpool_info
    libraries = [{"library": os.path.basename(lib.get("filepath", "")),
                  "version": lib.get("version"), "architecture": lib.get("architecture"),
                  "threads": lib.get("num_threads")}
                 for lib in threadpool_info() if lib.get("user_api") == "blas"]
    return {"pin": BLAS_PIN, "coretype": os.environ.get("OPENBLAS_CORETYPE"),
            "libraries": libraries}
