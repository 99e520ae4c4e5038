"""The swimmer thesis: 14-joint stick figure, 2D-marker reconstruction, stroke cycles, evaluation.

Public names: the stick figure (:data:`SWIM_JOINTS`, :func:`joints_to_angles`,
:func:`angles_to_joints`), mocap input (:func:`load_swim_mocap`), cycles
(:func:`detect_cycle_starts`, :func:`build_training_cycles`), the model
(:func:`train_motion_model`), reconstruction (:func:`reconstruct_single_view`,
:func:`reconstruct_two_views`, :func:`read_markings`) and the evaluation
(:func:`prepare`, :func:`run_evaluation`).
"""
from .cycles import TrainingCycles, build_training_cycles, cycle_phase, detect_cycle_starts
from .experiment import prepare, run_particle_filter, run_ukf
from .markings import read_markings, reconstruct_markings, write_markings
from .mocap import SwimMocap, load_swim_mocap
from .reconstruct import complete_other_half, reconstruct_single_view, reconstruct_two_views, sync_offset
from .report import run_evaluation, write_report
from .tracking import run_rbpf, run_ukf_tuned
from .stickfigure import (ANGLE_NAMES, SWIM_JOINTS, SWIM_PARENTS, angle_error_sq, angles_to_joints,
                          joints_to_angles)
from .training import train_motion_model

__all__ = ["ANGLE_NAMES", "SWIM_JOINTS", "SWIM_PARENTS", "SwimMocap", "TrainingCycles", "angle_error_sq",
           "angles_to_joints", "build_training_cycles", "complete_other_half", "cycle_phase",
           "detect_cycle_starts", "joints_to_angles", "load_swim_mocap", "prepare", "read_markings",
           "reconstruct_markings", "reconstruct_single_view", "reconstruct_two_views", "run_evaluation",
           "run_particle_filter", "run_rbpf", "run_ukf", "run_ukf_tuned", "sync_offset", "train_motion_model",
           "write_markings", "write_report"]
