"""Synthetic time-of-flight depth sequences with ground truth, from mocap or built-in motions."""
from .generate import synthesize, synthesize_bvh, synthesize_procedural
from ..body.markers import MARKER_NAMES, marker_positions, marker_vertices
from .noise import ToFNoise, apply_tof_noise
from .procedural import PROCEDURAL_MOTIONS, procedural_motion

__all__ = ["synthesize", "synthesize_bvh", "synthesize_procedural", "MARKER_NAMES",
           "marker_positions", "marker_vertices", "ToFNoise", "apply_tof_noise",
           "PROCEDURAL_MOTIONS", "procedural_motion"]
