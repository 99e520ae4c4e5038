"""Starting without a previous pose: the global search of the first frame and of a recovery.

Candidates: root orientations from the foreground's point cloud times arm poses
(:data:`ARM_POSES`), placed so the model's extent along its long axis matches the
foreground's and shifted along that axis, scored in one batch; the best
:attr:`StartSettings.shortlist` are refined on the root, the best
:attr:`StartSettings.finalists` on every joint (and, for "ep" / "hc+ep", associated with the
frame's part detections), and the lowest energy plus the heading prior wins.

With the part recogniser on (:class:`~.settings.ProposalSettings`), poses fitted to its
joint proposals join the candidates and always reach the shortlist -- a start in any
orientation, lying or upside down -- and every finalist's score also counts the share of the
trunk proposals it disagrees with (:func:`~.proposals.disagreement`).

With :attr:`StartSettings.bends` the grid is also tried bent at the hips
(:data:`BEND_POSES`), each bent body turned so that its chord from feet to head lies along
the axes the straight body's trunk lies along; the bent candidates get their own shortlist
and finalists, so they change the result only where one of them scores best. They are
searched after the straight search, and only when its best finalist leaves more than
:attr:`StartSettings.bend_gate` of the observation unexplained or the recogniser's proposals
fold the body at the hips (:attr:`StartSettings.bend_hip_angle`).
"""
from __future__ import annotations

import numpy as np

from ..body.rotations import matrix_to_rotvec, rotation_about, rotvec_to_matrix
from ..body.skeleton import MODEL_FORWARD, MODEL_UP, POSE_INDEX
from ..contract import JOINT_INDEX
from ..errors import InputError
from ..motion.retarget import rotation_between
from .energy import unexplained
from .observation import robust_points
from .propagate import associate_stage
from .proposals import disagreement, frame_proposals, proposal_candidates, proposal_hip_angle
from .search import climb

#: Arm poses tried by the global search: (shoulder rx, left shoulder rz) in radians
#: (the right shoulder mirrors rz).
ARM_POSES = {"relaxed": (0.0, 0.0), "t-pose": (0.0, -1.13), "raised": (0.0, -2.6),
             "overhead": (-1.0, -2.4), "forward": (-1.4, 0.0), "down": (0.0, 0.35)}
#: Leg poses a recovery's global search also tries (:attr:`StartSettings.legs`), each on
#: every candidate of the grid: a hip's (pose slot, radians), the leg raised forward or out
#: to the side. The grid's legs hang down; a kick's raised leg reached the search only
#: through the recogniser's proposals, whose sides are at chance, and there a wrong-facing
#: fit won (dev 90_05, a jump kick: README, "The tracker").
LEG_POSES = {"left forward": ("l_hip_rx", -1.2), "right forward": ("r_hip_rx", -1.2),
             "left out": ("l_hip_rz", 0.9), "right out": ("r_hip_rz", -0.9)}
#: Bent bodies the global search also tries (:attr:`StartSettings.bends`), each on every
#: candidate of the grid: pose slots and radians. The grid's bodies are straight, so a
#: body folded at the hips (a forward fold, a yoga "down dog", hands and feet on the floor)
#: or sitting was reached only through the recogniser's proposals, which are poorest on
#: exactly those poses; the climb from a straight body did not bend it far enough (train
#: 144_30, sun salutation: a start 85 cm off, energy 450 above a fit to the true joints).
BEND_POSES = {"pike": (("l_hip_rx", -1.6), ("r_hip_rx", -1.6)),
              "seated": (("l_hip_rx", -1.6), ("r_hip_rx", -1.6), ("l_knee_rx", 1.6),
                         ("r_knee_rx", 1.6))}
#: Pose slots the arm poses set: both shoulders' rx and rz.
ARM_SLOTS = [POSE_INDEX[n] for n in ("l_shoulder_rx", "l_shoulder_rz", "r_shoulder_rx",
                                     "r_shoulder_rz")]


def initial_orientations(points, up):
    """Candidate root rotations ``(K, 3, 3)`` for a foreground cloud ``points (M, 3)``.

    The body's long axis (head direction) along ``up`` (standing), along +- the cloud's
    first and second principal axes (a body with its limbs spread, as in a cartwheel, may
    be wider than long), and along +- the first laid parallel to the floor (lying, where
    the visible surface is foreshortened), each turned about the axis in 45 degree steps.
    """
    up = np.asarray(up, dtype=np.float64)
    centred = points - points.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    flat = vt[0] - np.dot(vt[0], up) * up
    options = [up, vt[0], -vt[0], vt[1], -vt[1]]
    if np.linalg.norm(flat) > 0.2:
        flat = flat / np.linalg.norm(flat)
        options += [flat, -flat]
    axes = []
    for a in options:
        if all(np.dot(a, b) < 0.97 for b in axes):
            axes.append(a)
    out = []
    for axis in axes:
        base = rotation_between(MODEL_UP, axis)
        for k in range(8):
            out.append(rotation_about(axis, k * np.pi / 4) @ base)
    return np.array(out)


def floor_up(foreground, points):
    """Unit 'up' vector ``(3,)``: the floor normal toward the person, else camera -y."""
    plane = getattr(foreground, "floor_plane", None)
    if plane is None:
        return np.array([0.0, -1.0, 0.0])
    plane = np.asarray(plane, dtype=np.float64)
    norm = np.linalg.norm(plane[:3])
    n, d = plane[:3] / norm, plane[3] / norm
    return n if float(np.mean(points @ n) + d) > 0 else -n


def start_up(foreground):
    """:func:`floor_up` of a segmented frame, as the global search reads it."""
    return floor_up(foreground, robust_points(foreground.points))


def facing_penalty(poses, kappa: float, up=None, heading=None):
    """Initial-heading prior ``kappa (1 - cos theta) / 2`` for poses ``(N, 48) -> (N,)``.

    ``theta``: angle between the body's forward direction and the direction from the pelvis
    to the camera (a start) or ``heading (3,)`` (or one per pose, ``(N, 3)``), the last
    tracked forward direction (a recovery: bodies keep their heading); plus the same term for
    the angle between the head direction and ``up`` (upside-down bodies are rare). A depth
    image barely tells a body's front from its back; people mostly face the camera when a
    capture starts, so among fits of nearly equal likelihood the one facing the camera wins.
    ``kappa`` is :attr:`StartSettings.facing_prior` times the foreground's pixel count.
    """
    poses = np.atleast_2d(poses)
    R = rotvec_to_matrix(poses[:, 3:6])
    forward = R @ MODEL_FORWARD
    head = R @ MODEL_UP
    if heading is None:
        reference = -poses[:, 0:3] / np.linalg.norm(poses[:, 0:3], axis=1, keepdims=True)
    else:
        reference = np.asarray(heading, dtype=np.float64).reshape(-1, 3)   # (1 or N, 3)
    cos_face = np.sum(forward * reference, axis=1)
    cos_up = head @ up if up is not None else np.ones(len(poses))
    return kappa * 0.5 * ((1.0 - cos_face) + (1.0 - cos_up))


def _away_from_camera(poses):
    """``(N, 3)``: the unit direction from the camera to each pose's pelvis."""
    t = np.atleast_2d(poses)[:, 0:3]
    return t / np.linalg.norm(t, axis=1, keepdims=True)


#: The other side of each told facing.
OTHER_SIDE = {"camera": "away", "away": "camera"}


def wrong_side(poses, facing: str, up, margin_deg: float = 0.0) -> np.ndarray:
    """``(N,) bool``: which poses ``(N, 48)`` face the other side than the user's ``facing``
    (:attr:`StartSettings.facing`); none for ``"auto"``.

    A pose's forward direction and the direction from its pelvis to the camera, both
    flattened onto the floor (normal ``up (3,)``), make an angle; for ``"camera"`` a pose is
    on the wrong side beyond ``90 + margin_deg`` degrees, for ``"away"`` below ``90 -
    margin_deg``. Within ``margin_deg`` of profile a pose counts as either side.
    """
    poses = np.atleast_2d(poses)
    if facing == "auto":
        return np.zeros(len(poses), dtype=bool)
    up = np.asarray(up, dtype=np.float64)
    forward = rotvec_to_matrix(poses[:, 3:6]) @ MODEL_FORWARD
    to_camera = -poses[:, 0:3]
    forward = forward - (forward @ up)[:, None] * up
    to_camera = to_camera - (to_camera @ up)[:, None] * up
    cosine = np.sum(forward * to_camera, axis=1) / np.maximum(
        np.linalg.norm(forward, axis=1) * np.linalg.norm(to_camera, axis=1), 1e-12)
    band = np.sin(np.radians(margin_deg))
    return cosine < -band if facing == "camera" else cosine > band


def clearly_facing(pose, facing: str, up, margin_deg: float) -> bool:
    """Whether ``pose (48,)`` faces the told side by more than ``margin_deg`` from profile
    (then its twin turned about the vertical is on the wrong side)."""
    return bool(wrong_side(pose, OTHER_SIDE[facing], up, margin_deg)[0])


def with_leg_poses(poses) -> np.ndarray:
    """``poses (N, 48)`` followed by each of :data:`LEG_POSES` applied to all of them:
    ``(N * (1 + len(LEG_POSES)), 48)``, the legs' blocks in the dictionary's order."""
    out = [poses]
    for slot, angle in LEG_POSES.values():
        raised = poses.copy()
        raised[:, POSE_INDEX[slot]] = angle
        out.append(raised)
    return np.concatenate(out)


def head_to_feet_turn(render_body, pose) -> np.ndarray:
    """``(3, 3)``: the rotation taking ``pose``'s (root unturned) chord from the ankles'
    midpoint to the head onto the model's up axis (the identity for a straight body)."""
    joints = render_body.joint_positions(pose)
    feet = 0.5 * (joints[JOINT_INDEX["l_ankle"]] + joints[JOINT_INDEX["r_ankle"]])
    chord = joints[JOINT_INDEX["head"]] - feet
    return rotation_between(chord / np.linalg.norm(chord), MODEL_UP)


def candidate_poses(points, up, centre, render_body, settings, bend=None):
    """The scored candidates of the global search: ``(poses (N, 48), orientations K)``.

    Every arm pose (:data:`ARM_POSES`) at every orientation of :func:`initial_orientations`,
    the body straight, or with ``bend`` (a key of :data:`BEND_POSES`) bent: then the chord
    from its feet to its head, not its trunk, lies along each orientation's axis (a body
    folded over with hands and feet on the floor spans the cloud's long axis feet to head,
    its hips up in one of the eight turns about it).
    """
    g = settings.start
    rotations = initial_orientations(points, up)
    arms = np.zeros((len(ARM_POSES), render_body.dof))
    for k, (rx, rz) in enumerate(ARM_POSES.values()):
        arms[k, ARM_SLOTS] = rx, rz, rx, -rz
    turns = np.tile(np.eye(3), (len(ARM_POSES), 1, 1))
    if bend is not None:
        for slot, angle in BEND_POSES[bend]:
            arms[:, POSE_INDEX[slot]] = angle
        turns = np.array([head_to_feet_turn(render_body, a) for a in arms])
    poses = np.repeat(arms, len(rotations), axis=0)
    R0 = np.tile(rotations, (len(ARM_POSES), 1, 1))
    R = R0 @ np.repeat(turns, len(rotations), axis=0)
    poses[:, 3:6] = matrix_to_rotvec(R)
    body_axis = R0 @ MODEL_UP                # (K, 3) the feet-to-head direction
    # model vertices at pelvis = 0, then shift so the centre and the axial extent match
    verts = np.asarray(render_body.posed_vertices(poses))            # (K, V, 3)
    proj_model = np.einsum("kvi,ki->kv", verts, body_axis)
    proj_cloud = (points - centre) @ body_axis.T                     # (M, K)
    mid_model = 0.5 * (proj_model.min(axis=1) + proj_model.max(axis=1))
    lo, hi = np.percentile(proj_cloud, [2.0, 98.0], axis=0)
    mid_cloud = 0.5 * (lo + hi)
    # pelvis t = (I - a a^T)(centre - mean_model) + a (a.centre + mid_cloud - mid_model)
    offset = centre - verts.mean(axis=1)
    offset -= np.einsum("ki,ki->k", offset, body_axis)[:, None] * body_axis
    poses[:, 0:3] = offset + (body_axis @ centre + mid_cloud - mid_model)[:, None] * body_axis
    # the visible extent is foreshortened and partly hidden: also try shifts along the axis
    shifted = [poses]
    for shift in g.axial_shifts:
        if shift:
            moved = poses.copy()
            moved[:, 0:3] += shift * body_axis
            shifted.append(moved)
    return np.concatenate(shifted), len(rotations)


def global_search(tracker, energy, frame, heading=None, body_axis=None, legs: bool = False,
                  bends: bool = False, grid_heard: bool = False):
    """Find the body in ``frame`` without a previous pose (module docstring).

    Parameters
    ----------
    tracker : Tracker
        Supplies render body, method, settings, climbers, detector and recorder (read only).
    energy : Energy
        Without the motion prior.
    frame : Frame
        Uploaded into the renderers.
    heading : (3,) float or None
        Last tracked forward direction (recovery), else the body is expected to face the camera.
    body_axis : (3,) float or None
        Last tracked head direction (recovery): the prior prefers it to 'up'.
    legs : bool
        Also try every grid candidate with each of :data:`LEG_POSES`.
    bends : bool
        Also try the grid with each of :data:`BEND_POSES` (feet to head along its axes,
        :func:`candidate_poses`), heard on their own shortlist and finalists
        (:attr:`StartSettings.bend_shortlist`, :attr:`StartSettings.bend_finalists`), when
        the straight search's best leaves more than :attr:`StartSettings.bend_gate` of the
        observation unexplained or the recogniser's neck, pelvis and knees make an angle
        below :attr:`StartSettings.bend_hip_angle` (``info["bend_gate"]``).
    grid_heard : bool
        Where every finalist is one of the recogniser's, also climb the grid's best
        (:attr:`StartSettings.grid_heard`); it changes nothing else (the bend gate judges
        the best of the others). Where it wins, ``info["displaced"]`` holds the start the
        search had without it: ``{"candidate", "from", "score", "pose": 48 floats}``.

    Returns
    -------
    pose : (48,) float
    energy : float
    info : dict
    """
    g = tracker.settings.start
    rec = tracker.recorder
    fg = frame.foreground
    points = robust_points(fg.points)
    if len(points) < 20:
        raise InputError(None, "no person found in the frame (foreground is empty)")
    up = floor_up(fg, points)
    centre = np.median(points, axis=0)
    # the visible surface lies in front of the body's centre: push back along the ray
    centre = centre + g.centre_push * centre / np.linalg.norm(centre)
    poses, n_rot = candidate_poses(points, up, centre, tracker.render_body, tracker.settings)
    n_legs_down = len(poses)
    if legs:
        poses = with_leg_poses(poses)
    n_grid = len(poses)
    p = tracker.settings.propose
    proposals = frame_proposals(tracker, frame)
    if proposals is not None and p.start_candidates:
        fitted = proposal_candidates(tracker.body, proposals, p.min_confidence)
        # the limbs' proposals are the least reliable: each fit also with every arm pose
        armed = np.repeat(fitted, len(ARM_POSES), axis=0)
        for k, (rx, rz) in enumerate(ARM_POSES.values()):
            armed[k::len(ARM_POSES), ARM_SLOTS] = rx, rz, rx, -rz
        poses = np.concatenate([poses, fitted, armed])
    pixels = float(np.count_nonzero(fg.mask))
    kappa = g.facing_prior * pixels
    energies = energy(poses)
    prior_up = up if body_axis is None else np.asarray(body_axis, dtype=np.float64)
    # the user's facing (a start only; a recovery keeps the tracked heading): a pose facing
    # the other side costs more than any fit could gain (the energy is at most ~1 per pixel)
    told = g.facing if heading is None else "auto"

    def heading_cost(x):
        """``(N,)``: the heading prior of poses ``x (N, 48)`` plus the user's facing."""
        reference = _away_from_camera(x) if told == "away" else heading
        return (facing_penalty(x, kappa, prior_up, reference)
                + 2.0 * pixels * wrong_side(x, told, up, g.facing_margin))

    order = np.argsort(energies + heading_cost(poses))
    shortlist = list(order[:g.shortlist])
    ours = [i for i in order if i >= n_grid]
    if ours and ours[0] not in shortlist:
        shortlist.append(ours[0])          # the recogniser's best start always gets a hearing
    climber = tracker.climbers.start
    root_blocks = climber.blocks[:g.root_blocks]

    def refine_root(candidates, starts, picks):
        """``[(energy, index, pose)]`` of ``candidates[picks]`` climbed on the root, lowest first."""
        coarse = []
        for i in picks:
            x, e = climb(energy, climber, candidates[i], rec, start_energy=starts[i],
                         blocks=root_blocks, passes=g.root_passes)
            coarse.append((e, int(i), x))
        return sorted(coarse, key=lambda c: c[0])

    coarse = refine_root(poses, energies, shortlist)
    chosen = coarse[:g.finalists]
    from_proposals = [c for c in coarse if c[1] >= n_grid]
    if from_proposals and all(c[1] < n_grid for c in chosen):
        chosen.append(from_proposals[0])     # the recogniser's best guess always gets a hearing
    if grid_heard and all(c[1] >= n_grid for c in chosen):
        # and the grid's best, on top of the finalists (it displaces none): the
        # recogniser's fits (each also with every arm pose) can fill the shortlist on their
        # energy before any climb
        from_grid = [c for c in coarse if c[1] < n_grid]
        chosen.append(from_grid[0] if from_grid else refine_root(
            poses, energies, [next(i for i in order if i < n_grid)])[0])
        heard_grid = chosen[-1][1]
    else:
        heard_grid = None
    finalists = []
    best = None
    # the best as it would be without the grid's heard best: what the bend gate judges,
    # and the start that one displaces (StartSettings.displaced_checked)
    rest = None

    def hear(e, x, tag, margin=0.0):
        """Climb a finalist on every joint (and associate it), score it, keep the best."""
        nonlocal best, rest
        x, e = climb(energy, climber, x, rec, start_energy=e, passes=g.passes)
        if tracker.method != "hc" and tracker.detector is not None:
            x, e, _ = associate_stage(tracker, energy, frame, x, e)
            x, e = climb(energy, climber, x, rec, start_energy=e, level_offset=g.associate_level)
        score = e + float(heading_cost(x[None])[0])
        if proposals is not None:
            off, _ = disagreement(tracker.body.joint_positions(x), proposals, p.min_confidence,
                                  p.distance)
            score += p.start_weight * pixels * float(off)
        kind, i = tag
        finalists.append({"candidate": int(i), "energy": round(float(e), 1),
                          "score": round(score, 1),
                          "from": "proposals" if kind == "proposals" else "grid"})
        if kind in BEND_POSES:
            finalists[-1]["bend"] = kind
        # a bent body must win clearly: on a near tie the straight start stands
        key = score + margin * abs(score)
        if best is None or key < best[0]:
            best = (key, tag, x, e)
        if tag != ("grid", heard_grid) and (rest is None or key < rest[0]):
            rest = (key, tag, x, score)

    for e, i, x in chosen:
        hear(e, x, ("proposals" if i >= n_grid else "grid", i))
    n_scored = len(poses)
    gate = None
    if bends:
        # the bent bodies are heard on their own, after the straight search (which they do
        # not change), and only when its best leaves much of the person unexplained
        share = unexplained(energy, rest[2])
        # the recogniser's opinion too: a fold it sees may be fitted by a straight body that
        # explains the silhouette well enough (train 02_05)
        hip = None if proposals is None else proposal_hip_angle(proposals)
        folded = hip is not None and hip < g.bend_hip_angle
        gate = {"unexplained": round(share, 4), "threshold": g.bend_gate,
                "hip_angle": None if hip is None else round(hip, 1),
                "hip_threshold": g.bend_hip_angle,
                "searched": bool(share > g.bend_gate or folded)}
    if gate and gate["searched"]:
        bent = np.concatenate([candidate_poses(points, up, centre, tracker.render_body,
                                               tracker.settings, bend)[0] for bend in BEND_POSES])
        bent_energies = energy(bent)
        n_scored += len(bent)
        bent_order = np.argsort(bent_energies + heading_cost(bent))
        for b, bend in enumerate(BEND_POSES):
            # candidate k of ``bent`` is of block k // n_legs_down: the straight grid, bent
            picks = [k for k in bent_order if k // n_legs_down == b][:g.bend_shortlist]
            for e, k, x in refine_root(bent, bent_energies, picks)[:g.bend_finalists]:
                hear(e, x, (bend, k), margin=g.bend_margin)
    _, (kind, i), x, e = best
    in_grid = kind != "proposals"
    info = {"candidates": int(n_scored), "orientations": int(n_rot),
            "proposal_candidates": int(len(poses) - n_grid),
            "chosen_from": "grid" if in_grid else "proposals",
            "chosen_orientation": int(i % n_rot) if in_grid else None,
            "chosen_arms": list(ARM_POSES)[(i // n_rot) % len(ARM_POSES)] if in_grid else None,
            "finalists": finalists, "facing": told}
    if legs:
        # the bent blocks are built from the straight grid, legs down
        info["chosen_legs"] = (None if not in_grid else "down" if kind != "grid"
                               else ["down", *LEG_POSES][i // n_legs_down])
    if bends:
        info["chosen_bend"] = None if not in_grid else "straight" if kind == "grid" else kind
        info["bend_gate"] = gate
    if (kind, i) == ("grid", heard_grid):
        # the grid's heard best displaced the start the search had without it, for the
        # front/back check to hear too (StartSettings.displaced_checked); its pose not
        # rounded: a start moved by 1e-6 can end in another attractor (dev: 90_05 seed 1)
        _, (rest_kind, rest_i), rest_x, rest_score = rest
        info["displaced"] = {"candidate": int(rest_i),
                             "from": "proposals" if rest_kind == "proposals" else "grid",
                             "score": round(float(rest_score), 1),
                             "pose": [float(v) for v in rest_x]}
    if told != "auto":
        # near profile the told side does not settle front and back: the check then runs
        info["facing_clear"] = clearly_facing(x, told, up, g.facing_margin)
    return x, e, info
