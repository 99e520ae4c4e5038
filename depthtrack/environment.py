"""What a result was computed with, beside the rasteriser (:func:`.render.context.gl_info`).

A track's outcome can follow the last bits of a floating-point result: the test sequences,
synthesized and tracked again by the same code on a fresh install (other versions of the
numeric libraries), came out as before to the digit on some tracks and up to nine points
within 10 cm apart on others (README, "Benchmark"). So every ``summary.json`` names the
versions it was computed with (``software``), and two figures can be told apart by them.
"""
from __future__ import annotations

import platform
from importlib import metadata

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
