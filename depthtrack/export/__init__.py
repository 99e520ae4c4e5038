"""Exports of a track for other tools: glTF/GLB, C3D, BVH with a T-pose rest, per-frame JSON.

One module per format (:mod:`.gltf`, :mod:`.c3d`, :mod:`.bvh`, :mod:`.joints_json`), the
axis conventions in :mod:`.axes`, and one registry (:mod:`.registry`: ``EXPORTERS``,
``write_exports``). The package sits above ``body``, ``motion`` and ``io``: it poses the
fitted body and writes through ``io``'s atomic writes.
"""
from .registry import EXPORTERS, parse_formats, write_exports

__all__ = ["EXPORTERS", "parse_formats", "write_exports"]
