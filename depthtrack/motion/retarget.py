"""Retarget BVH motion capture onto our body model, and resample pose sequences in time.

Method (bone-direction retargeting, twist from the BVH):

1. A *reference pose* of the BVH: its rest pose (all channels zero) when that is a
   standing skeleton (CMU, DeepMimic, Daz files), otherwise (Reallusion files, whose
   zero pose has every bone along its parent's local axes, and a Z-up root) the
   frame of the motion that stands most upright with the straightest legs
   (:func:`reference_frame`). Its own left, up and forward axes are mapped to our
   model frame's (+x, -y, -z) by a rotation ``A``; the BVH world is mapped to a world
   with our axes by ``B`` (:func:`canonical_axes`: ``B = A`` for a rest pose; for a
   reference frame, up is the world's +y so the floor stays level). The BVH joint
   world rotations relative to the reference, seen in our world,
   ``W~_j = B W_j W_j,ref^T A^T``, are the identity at a rest-pose reference, like ours
   at rest (for a frame reference they hold the reference's lean and heading).
2. Each of our joints j takes the world orientation of the BVH joint that drives the
   same body part, corrected once for the different rest poses (A-pose vs T-pose vs
   arms down): ``G_j = W~_drv K_j`` with ``K_j`` the rotation taking our rest bone
   direction to the BVH rest bone direction (a best-fit rotation for the chest, which
   carries three bones; the identity for pelvis and feet, whose rests agree).
3. Where the bone ends at a contract point (limbs, head), ``G_j`` is turned by the
   smallest rotation that makes our bone point exactly where the BVH bone points
   now, so differing skeleton layouts still give the right directions.
4. Local rotations ``G_parent^T G_j`` are our pose; our hip centre follows the BVH's,
   its trajectory scaled by the height ratio, placed by a world->camera transform.

Frame-rate conversion slerps every joint rotation (never Euler angles) and
interpolates the pelvis position linearly.
"""
from __future__ import annotations

import numpy as np

from ..body.rotations import matrix_to_rotvec, rotvec_to_matrix, slerp
from ..contract import JOINT_INDEX as C

#: For each body joint: the contract point its bone starts at and the one it ends at, or
#: None. The BVH joint that drives it is the contract joint of the same name
#: (:meth:`BvhMotion.contract_joint_indices`, any naming convention or a joint map).
_BONES = {
    "pelvis": None,
    "spine": None,   # the chest joint: found from the skeleton, see _chest_joint
    "neck": ("neck", "head"),
    "l_shoulder": ("l_shoulder", "l_elbow"), "l_elbow": ("l_elbow", "l_wrist"), "l_wrist": None,
    "r_shoulder": ("r_shoulder", "r_elbow"), "r_elbow": ("r_elbow", "r_wrist"), "r_wrist": None,
    "l_hip": ("l_hip", "l_knee"), "l_knee": ("l_knee", "l_ankle"), "l_ankle": None,
    "r_hip": ("r_hip", "r_knee"), "r_knee": ("r_knee", "r_ankle"), "r_ankle": None,
}


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def rotation_between(a, b):
    """Smallest rotations taking directions ``a`` to ``b``.

    Parameters
    ----------
    a, b : (..., 3) float
        Directions (need not be unit).

    Returns
    -------
    R : (..., 3, 3) float
        ``R @ a`` is parallel to ``b``; a half turn about an axis normal to ``a`` when
        they are opposite.
    """
    a, b = np.broadcast_arrays(_unit(a), _unit(b))
    cross = np.cross(a, b)
    sin = np.linalg.norm(cross, axis=-1)
    cos = np.sum(a * b, axis=-1)
    angle = np.arctan2(sin, cos)
    axis = cross / np.maximum(sin, 1e-12)[..., None]
    opposite = (sin < 1e-9) & (cos < 0)
    if np.any(opposite):
        helper = np.where(np.abs(a[..., :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
        normal = _unit(np.cross(a, helper))
        axis = np.where(opposite[..., None], normal, axis)
    return rotvec_to_matrix(axis * angle[..., None])


def best_rotation(source, target, weights=None):
    """Rotation ``R`` minimising ``sum w |R s_i - t_i|^2`` (Kabsch).

    Parameters
    ----------
    source, target : (..., n, 3) float
    weights : (n,) float or None

    Returns
    -------
    R : (..., 3, 3) float
    """
    s = np.asarray(source, float)
    t = np.asarray(target, float)
    w = np.ones(s.shape[-2]) if weights is None else np.asarray(weights, float)
    H = np.einsum("...ni,n,...nj->...ij", t, w, s)
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(U @ Vt))
    D = np.zeros(H.shape)
    D[..., 0, 0] = 1.0
    D[..., 1, 1] = 1.0
    D[..., 2, 2] = d
    return U @ D @ Vt


def _one_frame(motion, values):
    """A copy of ``motion`` holding the single frame ``values (C,)``."""
    from dataclasses import replace

    return replace(motion, frames=np.asarray(values, float).reshape(1, -1), _cache={})


def _rest_motion(motion):
    """A copy of ``motion`` holding one frame with every channel zero."""
    return _one_frame(motion, np.zeros(motion.frames.shape[1]))


def _stands(points) -> bool:
    """Whether contract points ``(15, 3)`` form a standing skeleton: both legs, bone by
    bone, point away from the neck within 45 degrees of the hips-to-neck axis."""
    hips = 0.5 * (points[C["l_hip"]] + points[C["r_hip"]])
    up = _unit(points[C["neck"]] - hips)
    bones = [points[C[b]] - points[C[a]] for a, b in
             (("l_hip", "l_knee"), ("l_knee", "l_ankle"), ("r_hip", "r_knee"), ("r_knee", "r_ankle"))]
    return bool(np.all(_unit(np.array(bones)) @ up < -0.7) and (points[C["head"]] - points[C["neck"]]) @ up > 0)


def reference_frame(motion):
    """The motion frame used as the reference pose, or ``None`` for the rest pose.

    ``None`` when the rest pose (every channel zero) stands (:func:`_stands`) upright in
    the BVH world (y up, the BVH convention; within 35 degrees), as in CMU, DeepMimic and
    Daz files. Otherwise (Reallusion files; a rest pose that is turned upright only by
    the root's rotation channels) the frame that best stands upright: the largest sum of
    the cosines between the hips-to-neck axis and +y and, averaged, between each leg
    bone and -y.
    """
    rest = _rest_motion(motion).contract_joint_positions()[0]
    if _stands(rest) and _axes_of(rest)[1][1] > 0.82:
        return None
    c = motion.contract_joint_positions()                                  # (F, 15, 3)
    hips = 0.5 * (c[:, C["l_hip"]] + c[:, C["r_hip"]])
    torso = _unit(c[:, C["neck"]] - hips)[:, 1]
    legs = np.mean([_unit(c[:, C[b]] - c[:, C[a]])[:, 1] for a, b in
                    (("l_hip", "l_knee"), ("l_knee", "l_ankle"), ("r_hip", "r_knee"), ("r_knee", "r_ankle"))],
                   axis=0)
    return int(np.argmax(torso - legs))


def _reference_motion(motion):
    """``(one-frame motion holding the reference pose, its frame index or None)``."""
    if "reference" not in motion._cache:
        f = reference_frame(motion)
        ref = _rest_motion(motion) if f is None else _one_frame(motion, motion.frames[f])
        motion._cache["reference"] = (ref, f)
    return motion._cache["reference"]


def _axes_of(points):
    """``(left, up, forward)`` unit vectors of a standing skeleton's contract points ``(15, 3)``.

    Up from the ankles to the head, left from the hips and the shoulders (made normal
    to up), forward = left x up.
    """
    up = _unit(points[C["head"]] - 0.5 * (points[C["l_ankle"]] + points[C["r_ankle"]]))
    left = (points[C["l_hip"]] - points[C["r_hip"]]) + (points[C["l_shoulder"]] - points[C["r_shoulder"]])
    left = _unit(left - (left @ up) * up)
    return left, up, np.cross(left, up)


def _reference_axes(motion) -> np.ndarray:
    """(3, 3) rotation from the BVH world to the reference pose's own axes (rows left, down, back)."""
    left, up, forward = _axes_of(_reference_motion(motion)[0].contract_joint_positions()[0])
    return np.stack([left, -up, -forward])


def canonical_axes(motion) -> np.ndarray:
    """(3, 3) rotation ``B`` from the BVH world to a world with our model's axes.

    Our model frame has the body's left +x, up -y and forward -z; ``B`` maps the
    reference pose's left, up and forward there. For a rest-pose reference that is
    the rest pose's own axes (up from the ankles to the head); for a reference frame
    of the motion, up is the BVH world's +y (so that the floor stays level) and left
    the reference's left made horizontal.
    """
    ref, frame = _reference_motion(motion)
    if frame is None:
        return _reference_axes(motion)
    left, _, _ = _axes_of(ref.contract_joint_positions()[0])
    up = np.array([0.0, 1.0, 0.0])
    left = _unit(left - (left @ up) * up)
    return np.stack([left, -up, -np.cross(left, up)])


def rest_span(points) -> float:
    """Vertical span ankle-to-head-centre of rest contract points ``(15, 3)`` in a y-up or y-down frame."""
    points = np.asarray(points, float)
    ankles = 0.5 * (points[C["l_ankle"]] + points[C["r_ankle"]])
    return float(np.linalg.norm(points[C["head"]] - ankles))


def subject_height(motion, body) -> float:
    """The BVH subject's standing height, metres, estimated from its reference pose.

    The ankle-to-head-centre span of the BVH reference pose (:func:`reference_frame`), scaled by the ratio of our
    body's height to its own span (the share of height below the ankle and above
    the head centre is taken from our body's proportions).
    """
    bvh_span = rest_span(_reference_motion(motion)[0].contract_joint_positions()[0])
    ours = np.asarray(body.joint_positions(np.zeros(body.dof)))
    return float(body.height) * bvh_span / rest_span(ours)


def _chest_joint(motion) -> int:
    """The BVH joint that carries both arms and the neck (Spine1, Spine2, Chest ...)."""
    def ancestors(j):
        out = []
        while j >= 0:
            out.append(j)
            j = int(motion.parents[j])
        return out

    mapping = motion.contract_joint_indices()
    chains = [ancestors(mapping[name][1]) for name in ("l_shoulder", "r_shoulder", "neck")]
    common = [j for j in chains[0] if j in chains[1] and j in chains[2]]
    # chains list a joint before its ancestors, so the first common one is the lowest.
    return common[0]


def retarget(motion, body, world_to_camera=None, scale=None) -> np.ndarray:
    """Pose sequence of our body model that reproduces a BVH motion.

    Parameters
    ----------
    motion : BvhMotion
    body : BodyModel
    world_to_camera : (4, 4) float or None
        Rigid transform from the (scaled) BVH world, metres, to the camera frame.
        ``None``: the camera looks at the rest pose's front (canonical frame) with the
        first frame's root 2.5 m in front of it.
    scale : float or None
        Factor on the root trajectory; ``None`` = body height / BVH subject height
        (:func:`subject_height`).

    Returns
    -------
    poses : (F, 48) float
        At the BVH's own frame rate (see :func:`resample_poses`).
    """
    B = canonical_axes(motion)
    if scale is None:
        scale = float(body.height) / subject_height(motion, body)
    names = list(body.joint_names)
    parents = np.asarray(body.parents)
    J = len(names)
    F = motion.n_frames

    world = motion.world_transforms()
    rest_motion, frame = _reference_motion(motion)
    # A (reference) in its own axes A, turned by W_j W_j,ref^T in the BVH world, seen
    # in our world B: B W_j W_j,ref^T A^T, the identity at the reference when A = B.
    A = B if frame is None else _reference_axes(motion)
    rel = world[..., :3, :3]
    if frame is not None:
        rel = rel @ np.swapaxes(world[frame, :, :3, :3], -1, -2)
    W = np.einsum("ij,fkjl,ml->fkim", B, rel, A)
    contract = motion.contract_joint_positions() @ B.T                 # (F, 15, 3) canonical
    rest_contract = rest_motion.contract_joint_positions()[0] @ A.T
    rest_joints = rest_motion.joint_positions()[0] @ A.T
    rest_ends = rest_motion.end_site_positions()[0] @ A.T if len(motion.end_site_parents) else None
    ours_rest = np.asarray(body.joint_positions(np.zeros(body.dof)))   # contract order
    offsets = np.asarray(body.offsets, float)

    mapping = motion.contract_joint_indices()
    G = np.empty((F, J, 3, 3))
    for j, name in enumerate(names):
        bone = _BONES[name]
        if name == "spine":
            chest = _chest_joint(motion)
            # Fit the chest's three bones (to the neck and both shoulders) at rest.
            ours = np.stack([ours_rest[C[n]] for n in ("neck", "l_shoulder", "r_shoulder")])
            ours = ours - (ours_rest[C["pelvis"]] + offsets[j])
            theirs = np.stack([rest_contract[C[n]] for n in ("neck", "l_shoulder", "r_shoulder")])
            theirs = theirs - rest_joints[chest]
            K = best_rotation(_unit(ours), _unit(theirs))
            G[:, j] = W[:, chest] @ K
            continue
        d = mapping[name][1]
        if bone is not None:
            ours_dir = ours_rest[C[bone[1]]] - ours_rest[C[bone[0]]]
            their_rest = rest_contract[C[bone[1]]] - rest_contract[C[bone[0]]]
            G0 = W[:, d] @ rotation_between(ours_dir, their_rest)
            target = contract[:, C[bone[1]]] - contract[:, C[bone[0]]]
            G[:, j] = rotation_between(G0 @ ours_dir, target) @ G0
        elif name.endswith("wrist"):
            # The hand continues the forearm in our rest pose; in the BVH it points to
            # the hand's child or end site (or continues the forearm when it has none).
            forearm = offsets[j]
            kids = motion.children(d)
            ends = np.flatnonzero(motion.end_site_parents == d)
            if kids:
                their = rest_joints[kids[0]] - rest_joints[d]
            elif len(ends):
                their = rest_ends[ends[0]] - rest_joints[d]
            else:
                their = rest_joints[d] - rest_joints[motion.parents[d]]
            if np.linalg.norm(their) < 1e-9:
                their = rest_joints[d] - rest_joints[motion.parents[d]]
            G[:, j] = W[:, d] @ rotation_between(forearm, their)
        else:
            G[:, j] = W[:, d]

    local = np.empty_like(G)
    for j in range(J):
        p = parents[j]
        local[:, j] = G[:, j] if p < 0 else np.swapaxes(G[:, p], -1, -2) @ G[:, j]

    # Pelvis joints sit at different heights in different skeletons (DeepMimic's at
    # the hip joints, ours above them), so the hip centres are matched instead: that
    # keeps the legs, and so the feet, where the BVH has them.
    hips = motion.contract_joint_positions()[:, [C["l_hip"], C["r_hip"]]].mean(axis=1) * scale
    our_hips = 0.5 * (ours_rest[C["l_hip"]] + ours_rest[C["r_hip"]]) - ours_rest[C["pelvis"]]
    if world_to_camera is None:
        world_to_camera = np.eye(4)
        world_to_camera[:3, :3] = B
        world_to_camera[:3, 3] = -B @ hips[0] + [0.0, 0.0, 2.5]
    world_to_camera = np.asarray(world_to_camera, float)
    R_wc, t_wc = world_to_camera[:3, :3], world_to_camera[:3, 3]
    local[:, 0] = R_wc @ B.T @ G[:, 0]

    poses = np.zeros((F, 6 + 3 * (J - 1)))
    poses[:, :3] = hips @ R_wc.T + t_wc - local[:, 0] @ our_hips
    poses[:, 3:] = matrix_to_rotvec(local).reshape(F, -1)
    return poses


def resample_poses(poses, src_fps: float, dst_fps: float, start: float = 0.0, duration=None):
    """Resample a pose sequence in time: slerp for rotations, linear for the pelvis position.

    Parameters
    ----------
    poses : (F, D) float
        Pose vectors at ``src_fps``; ``[0:3]`` a translation, then rotation vectors.
    src_fps, dst_fps : float
    start : float
        Seconds into the source where the first output frame lies.
    duration : float or None
        Seconds to cover; ``None`` = to the end of the source.

    Returns
    -------
    (K, D) float
        Frame k at time ``start + k / dst_fps``; only times within the source.
    """
    poses = np.asarray(poses, float)
    F, D = poses.shape
    end = (F - 1) / src_fps
    if not 0.0 <= start <= end:
        raise ValueError(f"start {start} s is outside the motion (0 to {end:.3f} s)")
    stop = end if duration is None else min(end, start + duration)
    n = int(np.floor((stop - start) * dst_fps + 1e-9)) + 1
    if duration is not None:
        n = min(n, max(1, int(round(duration * dst_fps))))
    t = (start + np.arange(n) / dst_fps) * src_fps
    i0 = np.clip(np.floor(t).astype(int), 0, F - 1)
    i1 = np.minimum(i0 + 1, F - 1)
    a = t - i0
    out = np.empty((n, D))
    out[:, :3] = (1 - a)[:, None] * poses[i0, :3] + a[:, None] * poses[i1, :3]
    r0 = poses[i0, 3:].reshape(n, -1, 3)
    r1 = poses[i1, 3:].reshape(n, -1, 3)
    out[:, 3:] = slerp(r0, r1, a[:, None]).reshape(n, -1)
    return out
