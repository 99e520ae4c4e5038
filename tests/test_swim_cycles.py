"""Cycle detection that assumes no stroke: periodicity by autocorrelation."""
import numpy as np
import pytest

from depthtrack.swim.cycles import periodic_cycle_starts, stroke_period


def test_period_and_starts_of_a_synthetic_periodic_signal():
    fps, period = 60.0, 83.0                       # 1.38 s cycles, not a whole number of frames
    t = np.arange(700)
    rng = np.random.default_rng(0)
    phase = 2 * np.pi * t / period
    angles = np.stack([1.2 + 0.5 * np.sin(phase + k) + 0.2 * np.sin(2 * phase + 2 * k) for k in range(26)], 1)
    angles += 0.02 * rng.standard_normal(angles.shape)
    p, strength = stroke_period(angles, fps)
    assert abs(p - period) <= 1 and strength > 0.9
    starts = periodic_cycle_starts(angles, fps)
    gaps = np.diff(starts)
    assert len(starts) >= 7 and np.all(np.abs(gaps - period) <= 2)


def test_period_on_the_cmu_back_stroke_matches_the_arm_up_cycles(shared_data):
    from depthtrack.swim.cycles import detect_cycle_starts
    from depthtrack.swim.mocap import load_swim_mocap
    from depthtrack.swim.stickfigure import joints_to_angles

    m = load_swim_mocap(shared_data / "cmu" / "126_01.bvh")
    arm = detect_cycle_starts(m.joints, m.fps, "back", "right")
    auto = detect_cycle_starts(m.joints, m.fps, "auto")
    p, _ = stroke_period(joints_to_angles(m.joints), m.fps)
    # the arm-up cycles of this take last 303-360 frames (120 Hz)
    assert np.min(np.diff(arm)) - 15 <= p <= np.max(np.diff(arm)) + 15
    # measured: auto 491, 724, 1063, 1360, 1722 against arm-up 722, 1065, 1368, 1728 (491: the first strokes)
    assert all(np.min(np.abs(auto - a)) <= 15 for a in arm)
