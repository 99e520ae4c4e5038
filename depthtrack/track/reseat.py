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

A limb over free space (:attr:`HeadingSettings.reseat_free`, :func:`free_space_limbs`) is
re-seated where it is seen (looked for every ``reseat_free_every`` frames, those the other
rechecks climb the tracked pose on), whatever ``reseat_every`` says: where most of the camera
pixels a forearm and hand (or shin and foot) cover read well behind them, the camera sees
through the limb, so it is not there. Only those limbs are tried. A limb tracked hidden
(:attr:`HeadingSettings.reseat_hidden`, :func:`.reach.hidden_limbs`: its lower segment shows
on almost none of the person's pixels, behind the body where it costs nothing) is looked for
on the same frames and re-seated alike; a limb truly hidden stays, unless a library pose
explains the image better by the margin.

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


def free_space_limbs(model_depth, labels, depth, joint_names, share: float, min_pixels: int = 5,
                     gap: float = 0.25) -> list:
    """The limbs a pose holds where the camera sees through them.

    A limb's lower segment (forearm and hand, shin and foot: the labels of its middle and
    end joint, :data:`.reach.LIMBS`) is over free space at a pixel with a reading more than
    ``gap`` metres behind the pose's surface there. Listed: the limbs with at least
    ``min_pixels`` such pixels making up at least the fraction ``share`` of the segment's
    pixels with a reading.

    Parameters
    ----------
    model_depth : (H, W) float
        The pose's rendered depth, 0 where it is not drawn.
    labels : (H, W) int
        The pose's part labels (index into ``joint_names``, -1 none).
    depth : (H, W) float
        The observed depth (m), 0 = no reading.
    joint_names : sequence of str
    share : float
    min_pixels : int
    gap : float

    Returns
    -------
    list of (limb, free share) in :data:`.reach.LIMBS` order
    """
    model_depth = np.asarray(model_depth, dtype=np.float64)
    depth = np.asarray(depth, dtype=np.float64)
    labels = np.asarray(labels)
    index = {n: i for i, n in enumerate(joint_names)}
    reading = (depth > 0) & (model_depth > 0)
    through = reading & (depth > model_depth + gap)
    out = []
    for limb, (_, mid, end) in LIMBS.items():
        segment = (labels == index[mid]) | (labels == index[end])
        n_read = np.count_nonzero(segment & reading)
        n_free = np.count_nonzero(segment & through)
        if n_free >= min_pixels and n_read and n_free >= share * n_read:
            out.append((limb, n_free / n_read))
    return out


def reseat_candidates(pose, library, clip=None, limbs=None):
    """Every limb of ``pose (48,)`` (or of ``limbs``, names of :data:`LIMB_SLOTS`) set to
    every library pose.

    Returns ``(limbs, poses)``: ``limbs`` the limb name of each candidate, ``poses (N, 48)``
    (``N = 2 * (K_arm + K_leg)`` for all four), clipped by ``clip`` (``poses -> poses``) when given.
    """
    pose = np.asarray(pose, dtype=np.float64)
    names = list(LIMB_SLOTS) if limbs is None else [n for n in LIMB_SLOTS if n in set(limbs)]
    limbs, out = [], []
    for name in names:
        slots = LIMB_SLOTS[name]
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


def best_reseat(pose, energy, climb_limb, library, climbs: int = 1, clip=None, limbs=None):
    """The best re-seat of ``pose (48,)``: every limb (or those named in ``limbs``) set to
    every library pose, scored by ``energy`` (``(N, 48) -> (N,)``, one batch), the ``climbs``
    lowest of each limb climbed by ``climb_limb`` (``(pose, limb) -> (pose, energy)``).

    Returns ``(limb, pose (48,), energy)`` of the lowest climbed.
    """
    names, candidates = reseat_candidates(pose, library, clip, limbs)
    scores = np.asarray(energy(candidates), dtype=np.float64)
    names = np.array(names)
    best = None
    for name in LIMB_SLOTS:
        own = np.flatnonzero(names == name)
        for i in own[np.argsort(scores[own], kind="stable")[:climbs]]:
            y, e_y = climb_limb(candidates[i], name)
            if best is None or float(e_y) < best[2]:
                best = (name, np.asarray(y, dtype=np.float64), float(e_y))
    return best


def reseat_limbs(pose, e_pose: float, energy, climb_limb, library, rounds: int, margin: float,
                 climbs: int = 1, clip=None, floor: float = 0.0, limbs=None):
    """Up to ``rounds`` re-seats of ``pose (48,)`` in turn: each round the best re-seat
    (:func:`best_reseat`) replaces the pose when its energy is lower than ``e_pose``'s by
    the fraction ``margin`` of the energy above ``floor`` (:func:`~.energy.relative_lead`);
    the first round that is not stops.

    ``limbs``: only those limbs (names of :data:`LIMB_SLOTS`); None = all four.

    Returns ``(pose (48,), energy, events)``: ``events`` a list of ``{"limb",
    "energy_kept", "energy_reseated"}``, one per re-seat taken.
    """
    x, e = np.asarray(pose, dtype=np.float64), float(e_pose)
    events = []
    for _ in range(int(rounds)):
        name, y, e_y = best_reseat(x, energy, climb_limb, library, climbs, clip, limbs)
        if relative_lead(e, e_y, floor) <= margin:
            break
        events.append({"limb": name, "energy_kept": round(e, 1), "energy_reseated": round(e_y, 1)})
        x, e = y, e_y
    return x, e, events


def recheck_reseat(state, pose, refit, energy, climb_limb, library, settings, clip=None,
                   floor: float = 0.0, free_limbs=None, hidden_limbs=None):
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
    free_limbs : callable ``(pose (48,)) -> list of (limb, share)`` or None
        :func:`free_space_limbs` of the frame; with :attr:`HeadingSettings.reseat_free` the
        limbs it lists are re-seated every ``reseat_free_every`` frames (only those, unless
        the periodic re-seat is due). Their entries say ``"trigger": "free"`` and the
        limb's ``"free_share"``. With :attr:`HeadingSettings.reseat_free_climbed`, where no
        library pose wins, the climbed pose (``refit``'s) replaces ``pose`` when it holds
        none of those limbs over free space (``"climbed": true``, ``"limb"`` the first listed).
    hidden_limbs : callable ``(pose (48,)) -> set of limb names`` or None
        :func:`.reach.hidden_limbs` of the frame; with :attr:`HeadingSettings.reseat_hidden`
        the limbs it lists are re-seated on the same frames as those over free space (their
        entries say ``"hidden"``: the hidden limbs; ``"trigger": "hidden"`` where none is
        over free space).

    Returns
    -------
    pose : (48,) float
        The re-seated pose when it took over, else ``pose``.
    changes : dict
        For the state (``reseats``).
    switched : bool
    """
    h = settings.heading
    limbs, trigger, free_names = None, {}, []
    if not due(state, h.reseat_every):
        looking = due(state, h.reseat_free_every)
        free = free_limbs(pose) if free_limbs is not None and h.reseat_free > 0 and looking else []
        listed_hidden = (hidden_limbs(pose) if hidden_limbs is not None and h.reseat_hidden > 0
                         and looking else set())
        free_names = [name for name, _ in free]
        hidden = [name for name in LIMB_SLOTS if name in listed_hidden and name not in free_names]
        if not free and not hidden:
            return pose, {}, False
        limbs = free_names + hidden
        trigger = {"trigger": "free" if free else "hidden"}
        if free:
            trigger["free_share"] = {name: round(float(v), 3) for name, v in free}
        if hidden:
            trigger["hidden"] = hidden
    base, e_pose = refit(pose)           # the limbs are re-seated on the climbed pose
    y, _, taken = reseat_limbs(base, e_pose, energy, climb_limb, library, 1, h.reseat_margin,
                               h.reseat_climbs, clip, floor, limbs)
    if not taken and free_names and h.reseat_free_climbed and cleared(base, free_names, free_limbs):
        e_kept = float(np.asarray(energy(np.asarray(pose, dtype=np.float64)[None]))[0])
        taken = [{"limb": free_names[0], "energy_kept": round(e_kept, 1),
                  "energy_reseated": round(float(e_pose), 1), "climbed": True}]
        y = base
    if not taken:
        return pose, {}, False
    return y, {"reseats": state.reseats + ({"frame": state.frame, **taken[0], **trigger},)}, True


def cleared(pose, limbs, free_limbs) -> bool:
    """Whether ``pose (48,)`` holds none of ``limbs`` over free space (``free_limbs``: as
    for :func:`recheck_reseat`)."""
    return not {name for name, _ in free_limbs(pose)} & set(limbs)
