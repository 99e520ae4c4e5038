"""Re-seat a limb: try each arm and leg in the poses people hold, keep one the image prefers.

A track can settle with a limb in the wrong basin -- an arm hanging where it is raised, a
knee lifted toward the camera put down behind the other leg -- and the hill climbing, which
moves a limb a few tenths of a radian at a time, does not leave it: moving the limb across
explains the image worse on the way. On dev tracks the energy knew better: in 90_05 (a jump
kick) and 05_20 (Kinect v2 from 120 degrees) a pose fitted to the true joints and climbed
had 4 to 30 % lower energy than the tracked one on the tracker's own tiles
(``tools/heading_tiles.py SEQ TRACK F --limbs``), so these are failures of the search, not
of the energy.

The limb poses (:func:`limb_library`, ``depthtrack/data/limb_poses.npz``) are k-means
centres of the train motions' arm poses (shoulder and elbow rotations) and leg poses (hip
and knee), spread by farthest-point sampling, made by ``tools/make_limb_poses.py``; right
limbs use them mirrored. Every
:attr:`HeadingSettings.reseat_every` frames each limb of the tracked pose is set to every
library pose (one batch for all four limbs), the ``reseat_climbs`` best of each limb are
climbed over that limb's joints, and the lowest replaces the track when its energy is lower
than the tracked pose's by the fraction ``reseat_margin``. The limbs are set on the tracked
pose climbed as every recheck climbs it (without the motion prior, whole body), so a
re-seated limb competes with the pose it would replace on equal terms: set on the pose
as tracked, the limb's climb alone could not make up for the rest of the body's, and the
re-seated poses trailed by 1 to 14 % where they were right.

The automatic start can do the same once (:func:`reseat_limbs`,
:attr:`StartSettings.reseat_rounds`): the global search tries six arm poses, and a start
can keep an arm in a basin none of them leads out of (dev: 01_08 on SR4000 from 270
degrees, both arms started overhead in the dropouts of a wall at the edge of the range
while they hang in front of the trunk; the left arm re-seated, the start's energy went
3,516 -> 3,422).
"""
from __future__ import annotations

from functools import lru_cache
from importlib import resources
from pathlib import Path

import numpy as np

from ..body.skeleton import POSE_INDEX
from .energy import relative_lead
from .heading import due
from .hill_climb import restrict_blocks
from .reach import LIMBS
from .search import climb

#: Pose slots of each limb's (:data:`.reach.LIMBS`) two upper joints (rotation vectors), the
#: library's six numbers.
LIMB_SLOTS = {limb: [POSE_INDEX[f"{joint}_{axis}"] for joint in joints[:2] for axis in ("rx", "ry", "rz")]
              for limb, joints in LIMBS.items()}
#: The sagittal mirror of a limb's six numbers: a right limb's pose is a left one's with
#: the y and z components of each rotation vector negated (as the joint limits are).
MIRROR = np.array([1.0, -1.0, -1.0, 1.0, -1.0, -1.0])


def library_path() -> Path:
    """The shipped limb library, ``depthtrack/data/limb_poses.npz``."""
    return Path(str(resources.files("depthtrack") / "data" / "limb_poses.npz"))


@lru_cache(maxsize=4)
def limb_library(path=None) -> dict:
    """``{"arm": (K, 6), "leg": (K, 6)}`` left-limb poses (read once per path)."""
    with np.load(path or library_path()) as data:
        return {"arm": np.array(data["arm"], dtype=np.float64),
                "leg": np.array(data["leg"], dtype=np.float64)}


def reseat_candidates(pose, library, clip=None):
    """Every limb of ``pose (48,)`` set to every library pose.

    Returns ``(limbs, poses)``: ``limbs`` the limb name of each candidate, ``poses (N, 48)``
    (``N = 2 * (K_arm + K_leg)``), clipped by ``clip`` (``poses -> poses``) when given.
    """
    pose = np.asarray(pose, dtype=np.float64)
    limbs, out = [], []
    for name, slots in LIMB_SLOTS.items():
        side, kind = name.split("_")
        values = library[kind] * (MIRROR if side == "r" else 1.0)
        batch = np.repeat(pose[None], len(values), axis=0)
        batch[:, slots] = values
        out.append(batch)
        limbs += [name] * len(values)
    poses = np.concatenate(out)
    return limbs, (clip(poses) if clip is not None else poses)


def limb_climber(energy, climber, recorder, level_offset: int = 0):
    """``(pose (48,), limb) -> (pose (48,), energy)``: ``climber`` climbing ``energy`` over
    that limb's joints only (:data:`.reach.LIMBS`), from the rung ``level_offset``."""
    def run(pose, limb):
        return climb(energy, climber, pose, recorder, level_offset=level_offset,
                     blocks=restrict_blocks(climber.blocks, LIMBS[limb]))
    return run


def best_reseat(pose, energy, climb_limb, library, climbs: int = 1, clip=None):
    """The best re-seat of ``pose (48,)``: every limb set to every library pose, scored by
    ``energy`` (``(N, 48) -> (N,)``, one batch), the ``climbs`` lowest of each limb climbed
    by ``climb_limb`` (``(pose, limb) -> (pose, energy)``).

    Returns ``(limb, pose (48,), energy)`` of the lowest climbed.
    """
    limbs, candidates = reseat_candidates(pose, library, clip)
    scores = np.asarray(energy(candidates), dtype=np.float64)
    limbs = np.array(limbs)
    best = None
    for name in LIMB_SLOTS:
        own = np.flatnonzero(limbs == name)
        for i in own[np.argsort(scores[own], kind="stable")[:climbs]]:
            y, e_y = climb_limb(candidates[i], name)
            if best is None or float(e_y) < best[2]:
                best = (name, np.asarray(y, dtype=np.float64), float(e_y))
    return best


def reseat_limbs(pose, e_pose: float, energy, climb_limb, library, rounds: int, margin: float,
                 climbs: int = 1, clip=None, floor: float = 0.0):
    """Up to ``rounds`` re-seats of ``pose (48,)`` in turn: each round the best re-seat
    (:func:`best_reseat`) replaces the pose when its energy is lower than ``e_pose``'s by
    the fraction ``margin`` of the energy above ``floor`` (:func:`~.energy.relative_lead`);
    the first round that is not stops.

    Returns ``(pose (48,), energy, events)``: ``events`` a list of ``{"limb",
    "energy_kept", "energy_reseated"}``, one per re-seat taken.
    """
    x, e = np.asarray(pose, dtype=np.float64), float(e_pose)
    events = []
    for _ in range(int(rounds)):
        name, y, e_y = best_reseat(x, energy, climb_limb, library, climbs, clip)
        if relative_lead(e, e_y, floor) <= margin:
            break
        events.append({"limb": name, "energy_kept": round(e, 1), "energy_reseated": round(e_y, 1)})
        x, e = y, e_y
    return x, e, events


def recheck_reseat(state, pose, refit, energy, climb_limb, library, settings, clip=None,
                   floor: float = 0.0):
    """The re-seat recheck of one frame: keep ``pose`` or one with a limb re-seated.

    Parameters
    ----------
    state : TrackingState
        Before this frame is logged.
    pose : (48,) float
        The frame's tracked pose.
    refit : callable ``(pose (48,)) -> (pose (48,), float)``
        As for :func:`.heading.recheck_heading` (the tracked pose's climbed energy).
    energy : callable ``(N, 48) -> (N,)``
        The recheck's energy (no motion prior), one batch.
    climb_limb : callable ``(pose (48,), limb name) -> (pose (48,), float)``
        A climb over that limb's joints (:func:`limb_climber`).
    library : dict
        :func:`limb_library`.
    settings : TrackerSettings
    floor : float
        The energy every pose pays (:attr:`~.heading_settings.HeadingSettings.margins_over`);
        the margin is a fraction of the kept energy above it.

    Returns
    -------
    pose : (48,) float
        The re-seated pose when it took over, else ``pose``.
    changes : dict
        For the state (``reseats``).
    switched : bool
    """
    h = settings.heading
    if not due(state, h.reseat_every):
        return pose, {}, False
    base, e_pose = refit(pose)           # the limbs are re-seated on the climbed pose
    y, _, taken = reseat_limbs(base, e_pose, energy, climb_limb, library, 1, h.reseat_margin,
                               h.reseat_climbs, clip, floor)
    if not taken:
        return pose, {}, False
    return y, {"reseats": state.reseats + ({"frame": state.frame, **taken[0]},)}, True
