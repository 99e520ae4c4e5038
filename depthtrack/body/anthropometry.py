"""The default body's proportions, its implicit surface and its skinning weights.

Proportions follow Winter's anthropometric segment ratios (D. A. Winter,
*Biomechanics and Motor Control of Human Movement*, fig. 4.1), as fractions of
the standing height H: shoulder 0.818 H, chin 0.870 H, elbow 0.630 H (arm hanging),
wrist 0.485 H, hip joint 0.530 H, knee 0.285 H, ankle 0.039 H, head 0.130 H,
biacromial width 0.259 H, hand 0.108 H, foot 0.152 H x 0.055 H.

The surface is a smooth union of capsules, tapered capsules and ellipsoids laid
along the bones of the zero (A-) pose; ``tools/make_body_mesh.py`` polygonises it.
The skinning weights are a function of position only (:func:`skin_weights`), so any
triangulation of the surface gets consistent weights.

Everything here is in the model frame (y down, facing -z, left = +x, pelvis at the
origin) for a body of height :data:`REFERENCE_HEIGHT`, in metres.
"""
from __future__ import annotations

import numpy as np

from .skeleton import JOINTS, JOINT_ID, NUM_JOINTS, PARENTS, children_of

REFERENCE_HEIGHT = 1.75
#: Arm abduction of the rest A-pose, degrees from hanging straight down.
ARM_ABDUCTION_DEG = 25.0
#: Height of the pelvis joint above the floor, fraction of H.
PELVIS_LEVEL = 0.56

# Winter's ratios (fraction of H)
_UPPER_ARM = 0.818 - 0.630   # shoulder to elbow, arm hanging
_FOREARM = 0.630 - 0.485
_HAND = 0.108
_THIGH = 0.530 - 0.285
_SHANK = 0.285 - 0.039
_FOOT = 0.152


def _point(level, x=0.0, z=0.0, height=REFERENCE_HEIGHT):
    """Model-frame point from a height above the floor (fraction of H), x and z in metres."""
    return np.array([x, -(level - PELVIS_LEVEL) * height, z])


def rest_joint_positions(height=REFERENCE_HEIGHT):
    """Joint positions of the zero pose ``(J, 3)`` and the head centre ``(3,)``, metres."""
    h = height
    s = h / REFERENCE_HEIGHT
    a = np.radians(ARM_ABDUCTION_DEG)
    p = np.zeros((NUM_JOINTS, 3))
    p[JOINT_ID["pelvis"]] = _point(PELVIS_LEVEL, height=h)
    p[JOINT_ID["spine"]] = _point(0.655, z=0.0 * s, height=h)
    p[JOINT_ID["neck"]] = _point(0.835, z=0.01 * s, height=h)
    for side, m in (("l", 1.0), ("r", -1.0)):
        arm = np.array([m * np.sin(a), np.cos(a), 0.0])
        sh = _point(0.812, x=m * 0.108 * h, z=0.01 * s, height=h)
        p[JOINT_ID[f"{side}_shoulder"]] = sh
        p[JOINT_ID[f"{side}_elbow"]] = sh + _UPPER_ARM * h * arm
        p[JOINT_ID[f"{side}_wrist"]] = sh + (_UPPER_ARM + _FOREARM) * h * arm
        p[JOINT_ID[f"{side}_hip"]] = _point(0.530, x=m * 0.050 * h, height=h)
        p[JOINT_ID[f"{side}_knee"]] = _point(0.285, x=m * 0.056 * h, z=-0.005 * s, height=h)
        p[JOINT_ID[f"{side}_ankle"]] = _point(0.039, x=m * 0.060 * h, z=0.01 * s, height=h)
    head = _point(0.936, z=-0.005 * s, height=h)
    return p, head


def rest_offsets(height=REFERENCE_HEIGHT):
    """Bone offsets ``(J, 3)`` (joint minus parent, root = 0) and head offset from the neck ``(3,)``."""
    p, head = rest_joint_positions(height)
    off = np.zeros_like(p)
    off[1:] = p[1:] - p[PARENTS[1:]]
    return off, head - p[JOINT_ID["neck"]]


# ----------------------------------------------------------------------------- primitives
# Each primitive: (kind, joint that owns it, parameters). Kinds:
#   "cone": tapered capsule from a to b with radii ra, rb, cross-section scaled by `squash`
#           (x, y, z factors applied to the offset from the axis before measuring).
#   "ellipsoid": centre c, semi-axes e (x, y, z), optional rotation R (3x3).

def primitives(height=REFERENCE_HEIGHT):
    """The implicit body as a list of dicts (see module source for the fields)."""
    s = height / REFERENCE_HEIGHT
    h = height
    p, head = rest_joint_positions(height)
    J = JOINT_ID
    prims = []

    def cone(owner, a, b, ra, rb, squash=(1.0, 1.0, 1.0)):
        prims.append(dict(kind="cone", owner=J[owner], a=np.asarray(a, float), b=np.asarray(b, float),
                          ra=ra * s, rb=rb * s, squash=np.asarray(squash, float)))

    def ellipsoid(owner, c, e, rot=None):
        prims.append(dict(kind="ellipsoid", owner=J[owner], c=np.asarray(c, float),
                          e=np.asarray(e, float) * s, rot=np.eye(3) if rot is None else rot))

    # trunk: one lofted surface of elliptic cross-sections (owned by the pelvis below the
    # spine joint and by the spine above), then the shoulder girdle
    levels = TRUNK_PROFILE[:, 0]
    prims.append(dict(kind="trunk", owner=J["pelvis"], owner_above=J["spine"],
                      split_y=p[J["spine"], 1],
                      y=-(levels - PELVIS_LEVEL) * h, half_width=TRUNK_PROFILE[:, 1] * s,
                      half_depth=TRUNK_PROFILE[:, 2] * s, centre_z=TRUNK_PROFILE[:, 3] * s))
    for side, m in (("l", 1.0), ("r", -1.0)):
        sh = p[J[f"{side}_shoulder"]]
        cone("spine", _point(0.800, x=0.0, z=0.01 * s, height=h), sh + np.array([0, 0.01 * s, 0]),
             0.075, 0.055, squash=(1.0, 1.0, 1.0))
    # neck and head
    cone("neck", p[J["neck"]] + np.array([0, 0.02 * s, 0]), _point(0.885, z=0.005 * s, height=h),
         0.058, 0.052)
    ellipsoid("neck", head, (0.076, 0.114, 0.097))
    ellipsoid("neck", head + np.array([0, 0.055, -0.055]) * s, (0.045, 0.04, 0.035))  # jaw
    ellipsoid("neck", head + np.array([0, 0.012, -0.094]) * s, (0.012, 0.024, 0.016))  # nose
    # arms and hands
    a = np.radians(ARM_ABDUCTION_DEG)
    for side, m in (("l", 1.0), ("r", -1.0)):
        arm = np.array([m * np.sin(a), np.cos(a), 0.0])
        sh, el, wr = p[J[f"{side}_shoulder"]], p[J[f"{side}_elbow"]], p[J[f"{side}_wrist"]]
        ellipsoid(f"{side}_shoulder", sh + np.array([m * 0.012, 0.01, 0]) * s, (0.058, 0.06, 0.058))  # deltoid
        cone(f"{side}_shoulder", sh, el, 0.052, 0.040)
        cone(f"{side}_elbow", el, wr, 0.043, 0.028, squash=(1.0, 1.0, 0.85))
        # hand: flat mitten, palm facing the thigh (normal along the abduction plane)
        side_axis = np.array([np.cos(a), -m * np.sin(a), 0.0])
        rot = np.stack([side_axis, arm, np.array([0.0, 0.0, 1.0])], axis=1)
        ellipsoid(f"{side}_wrist", wr + 0.45 * _HAND * h * arm, (0.017, 0.5 * _HAND * h / s * 1.02, 0.044), rot)
    # legs and feet
    for side, m in (("l", 1.0), ("r", -1.0)):
        hip, kn, an = p[J[f"{side}_hip"]], p[J[f"{side}_knee"]], p[J[f"{side}_ankle"]]
        cone(f"{side}_hip", hip + np.array([m * 0.015, -0.02, 0.0]) * s, kn, 0.088, 0.052)
        cone(f"{side}_knee", kn, an, 0.052, 0.034)
        ellipsoid(f"{side}_knee", kn + (an - kn) * 0.3 + np.array([0, 0, 0.02]) * s, (0.048, 0.09, 0.05))  # calf
        heel = an + np.array([0.0, 0.0, 0.03 * s])
        heel[1] = _point(0.034, height=h)[1]
        toe = an + np.array([m * 0.015 * s, 0.0, -(_FOOT * h - 0.06 * s - 0.028 * s)])
        toe[1] = _point(0.024, height=h)[1]
        cone(f"{side}_ankle", heel, toe, 0.034, 0.024, squash=(0.75, 1.0, 1.0))
        cone(f"{side}_ankle", an, heel + (toe - heel) * 0.35, 0.036, 0.034, squash=(0.8, 1.0, 1.0))
    return prims


#: Trunk cross-sections: height above the floor (fraction of H), half-width, half-depth and
#: centre z (metres, for H = 1.75 m), from the crotch to the base of the neck. Breadths after
#: adult male anthropometry: hip breadth 35 cm, waist 28 cm, chest 32 cm, chest depth 23 cm.
TRUNK_PROFILE = np.array([
    [0.470, 0.105, 0.072, 0.012],
    [0.500, 0.158, 0.097, 0.012],
    [0.530, 0.175, 0.107, 0.012],
    [0.560, 0.170, 0.106, 0.008],
    [0.600, 0.150, 0.099, 0.002],
    [0.630, 0.140, 0.096, 0.000],
    [0.680, 0.146, 0.102, -0.004],
    [0.730, 0.158, 0.113, -0.008],
    [0.770, 0.162, 0.116, -0.008],
    [0.800, 0.156, 0.106, -0.002],
    [0.822, 0.125, 0.088, 0.004],
    [0.840, 0.075, 0.062, 0.010],
])


def _trunk_sdf(x, y, half_width, half_depth, centre_z):
    """Approximate signed distance to the lofted trunk (profile sampled at model-frame ``y``)."""
    from scipy.interpolate import PchipInterpolator

    order = np.argsort(y)
    ys = y[order]
    yq = np.clip(x[:, 1], ys[0], ys[-1])
    a = PchipInterpolator(ys, half_width[order])(yq)
    b = PchipInterpolator(ys, half_depth[order])(yq)
    c = PchipInterpolator(ys, centre_z[order])(yq)
    radial = (np.hypot(x[:, 0] / a, (x[:, 2] - c) / b) - 1.0) * np.minimum(a, b)
    beyond = np.maximum(ys[0] - x[:, 1], x[:, 1] - ys[-1])  # past the crotch or the neck base
    return np.where(beyond > 0, np.hypot(np.maximum(radial, 0.0), beyond), radial)


def _cone_sdf(x, a, b, ra, rb, squash):
    """Approximate signed distance to a tapered capsule, ``x (n, 3) -> (n,)``."""
    ab = b - a
    length2 = ab @ ab
    t = np.clip(((x - a) @ ab) / length2, 0.0, 1.0)
    closest = a + t[:, None] * ab
    d = np.linalg.norm((x - closest) / squash, axis=1)
    return d - (ra + t * (rb - ra))


def _ellipsoid_sdf(x, c, e, rot):
    """Approximate signed distance to an ellipsoid (first-order, exact on the surface)."""
    local = (x - c) @ rot  # coordinates along the ellipsoid's axes
    k0 = np.linalg.norm(local / e, axis=1)
    k1 = np.linalg.norm(local / (e * e), axis=1)
    return np.where(k1 > 0, k0 * (k0 - 1.0) / np.maximum(k1, 1e-12), -e.min())


def primitive_distances(points, prims):
    """Signed distance of ``points (n, 3)`` to each primitive: ``(n, P)``."""
    x = np.asarray(points, dtype=np.float64)
    out = np.empty((len(x), len(prims)))
    for i, pr in enumerate(prims):
        if pr["kind"] == "cone":
            out[:, i] = _cone_sdf(x, pr["a"], pr["b"], pr["ra"], pr["rb"], pr["squash"])
        elif pr["kind"] == "trunk":
            out[:, i] = _trunk_sdf(x, pr["y"], pr["half_width"], pr["half_depth"], pr["centre_z"])
        else:
            out[:, i] = _ellipsoid_sdf(x, pr["c"], pr["e"], pr["rot"])
    return out


def smooth_union(d, k):
    """Exponential smooth minimum over the last axis of ``d (..., P)`` with blend radius ``k``."""
    m = d.min(axis=-1, keepdims=True)
    return (m - k * np.log(np.sum(np.exp(-(d - m) / k), axis=-1, keepdims=True)))[..., 0]


def body_sdf(points, height=REFERENCE_HEIGHT, blend=0.012):
    """Signed distance (approximate, negative inside) of the default body at ``points (n, 3)``."""
    prims = primitives(height)
    return smooth_union(primitive_distances(points, prims), blend * height / REFERENCE_HEIGHT)


# ----------------------------------------------------------------------------- skinning

def _bone_segments(joints, head):
    """Bones each joint moves, as (joint index, start (3,), end (3,)) triples."""
    J = JOINT_ID
    a = np.radians(ARM_ABDUCTION_DEG)
    segs = []
    kids = children_of(PARENTS)
    for j in range(NUM_JOINTS):
        for c in kids[j]:
            segs.append((j, joints[j], joints[c]))
    segs.append((J["neck"], joints[J["neck"]], head))
    for side, m in (("l", 1.0), ("r", -1.0)):
        arm = np.array([m * np.sin(a), np.cos(a), 0.0])
        wr = joints[J[f"{side}_wrist"]]
        segs.append((J[f"{side}_wrist"], wr, wr + 0.8 * _HAND * REFERENCE_HEIGHT * arm))
        an = joints[J[f"{side}_ankle"]]
        toe = an + np.array([m * 0.015, 0.045, -0.16])
        segs.append((J[f"{side}_ankle"], an, toe))
    return segs


def _segment_distance(x, a, b):
    ab = b - a
    t = np.clip(((x - a) @ ab) / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(x - (a + t[:, None] * ab), axis=1)


def raw_skin_weights(points, height=REFERENCE_HEIGHT, falloff=0.012):
    """Unnormalised per-joint skinning weights of surface points, ``(n, 3) -> (n, J)``.

    Each point belongs to the body part whose primitive is nearest; it may be
    influenced only by that part's joint, its parent and its children (so the
    inner thighs never follow the other leg). Among those, the weight of joint j
    is ``exp(-(d_j - d_min) / falloff)`` with d_j the distance to the bones j moves.
    """
    x = np.asarray(points, dtype=np.float64)
    s = height / REFERENCE_HEIGHT
    prims = primitives(height)
    joints, head = rest_joint_positions(height)
    nearest = np.argmin(primitive_distances(x, prims), axis=1)
    owner = np.array([pr["owner"] for pr in prims])[nearest]
    for i, pr in enumerate(prims):
        if "owner_above" in pr:  # the trunk: upper part follows the spine joint
            owner = np.where((nearest == i) & (x[:, 1] < pr["split_y"]), pr["owner_above"], owner)
    allowed = np.zeros((NUM_JOINTS, NUM_JOINTS), bool)
    kids = children_of(PARENTS)
    for j in range(NUM_JOINTS):
        allowed[j, j] = True
        if PARENTS[j] >= 0:
            allowed[j, PARENTS[j]] = True
        allowed[j, kids[j]] = True
    dist = np.full((len(x), NUM_JOINTS), np.inf)
    for j, a, b in _bone_segments(joints, head):
        dist[:, j] = np.minimum(dist[:, j], _segment_distance(x, a, b))
    dist = np.where(allowed[owner], dist, np.inf)
    dmin = dist.min(axis=1, keepdims=True)
    return np.exp(-(dist - dmin) / (falloff * s))


def top_influences(weights, influences=4):
    """Keep the strongest ``influences`` of ``weights (n, J)`` and normalise them.

    Returns
    -------
    joints : (n, influences) int32, weights : (n, influences) float32, rows summing to 1.
    """
    w = np.asarray(weights, dtype=np.float64)
    order = np.argsort(-w, axis=1, kind="stable")[:, :influences]
    wk = np.take_along_axis(w, order, axis=1)
    wk = wk / wk.sum(axis=1, keepdims=True)
    # renormalise in float32 so the stored rows sum to 1 to float32 precision
    wk32 = wk.astype(np.float32)
    wk32[:, 0] += np.float32(1.0) - wk32.sum(axis=1, dtype=np.float32)
    return order.astype(np.int32), wk32


def skin_weights(points, height=REFERENCE_HEIGHT, falloff=0.012, influences=4):
    """Top-``influences`` normalised skinning weights of surface points (see :func:`raw_skin_weights`).

    Returns
    -------
    joints : (n, influences) int32, weights : (n, influences) float32 (rows sum to 1).
    """
    return top_influences(raw_skin_weights(points, height, falloff), influences)


__all__ = ["REFERENCE_HEIGHT", "rest_joint_positions", "rest_offsets", "primitives",
           "body_sdf", "raw_skin_weights", "top_influences", "skin_weights", "JOINTS"]
