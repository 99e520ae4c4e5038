"""The other hypotheses a track is checked against: its twins.

A depth image barely tells a body's front from its back, or which leg is which where they
overlap. Each such doubt has a twin pose, the same joints reached another way: the body
turned half a turn (:func:`turned_pose`), or facing the other way with every joint left
where it is and left and right exchanged (:func:`swapped_twin`, :func:`swapped_twins`), or
with only the legs' or the arms' sides exchanged (:func:`limb_swapped_twins`). A twin is
fitted to its exchanged joints by a batched Levenberg-Marquardt (:func:`fit_joints`) in
milliseconds. Which twin wins is decided elsewhere: the start's front/back check and the
rechecks while tracking (:mod:`.heading`), a heading switch's carry-back
(:mod:`.carry_back`), the recogniser's fits (:mod:`.proposals`).
"""
from __future__ import annotations

import numpy as np

from ..body.rotations import matrix_to_rotvec, rotation_about, rotvec_to_matrix
from ..body.skeleton import MODEL_FORWARD, MODEL_UP
from ..contract import JOINT_INDEX, JOINT_NAMES
from .settings import TWIN_STARTS, TWIN_SWAPS


def turned_pose(pose):
    """``pose (48,)`` turned half a turn about the body's long axis through the pelvis:
    the same silhouette seen from the other side (front and back swapped)."""
    x = np.array(pose, dtype=np.float64)
    R = rotvec_to_matrix(x[3:6])
    axis = R @ MODEL_UP
    x[3:6] = matrix_to_rotvec((rotation_about(axis, np.pi) @ R)[None])[0]
    return x


#: Contract joint order with left and right exchanged.
SIDES_SWAPPED = [JOINT_INDEX[n.replace("l_", "#").replace("r_", "l_").replace("#", "r_")]
                 for n in JOINT_NAMES]


def _sides_swapped_for(kinds):
    """Contract joint order with left and right exchanged for the joints of ``kinds``
    (names without their ``l_`` / ``r_``)."""
    return [SIDES_SWAPPED[j] if name[2:] in kinds else j for j, name in enumerate(JOINT_NAMES)]


#: Joint orders with only the legs' / only the arms' sides exchanged (the recogniser's
#: sides are at chance: :func:`~.proposals.proposal_candidates` tries each); the hips and
#: shoulders stay, being rigid with the trunk.
LEGS_SWAPPED = _sides_swapped_for(("knee", "ankle"))
ARMS_SWAPPED = _sides_swapped_for(("elbow", "wrist"))


def swapped_twin(body, pose):
    """``pose (48,)``'s twin with the joints left where they are and left and right
    exchanged: the body facing the other way, its limbs where the image put them.

    The twin of a mirrored track: a body seen from behind explains the depth image of one
    facing the camera with each limb taken by the other side's (hips and shoulders bent
    backwards where needed). Turning the pose (:func:`turned_pose`) would also turn every
    limb away from where the image shows it; exchanging the sides keeps them.
    """
    return swapped_twins(body, pose, ("turned",))[0]


#: Joints that fix the root of a pose fitted to joint positions (Kabsch): the trunk's.
TRUNK_ROOT_JOINTS = [JOINT_INDEX[n] for n in ("head", "neck", "pelvis", "l_shoulder",
                                              "r_shoulder", "l_hip", "r_hip")]


#: The heading twins' joint orders (:attr:`HeadingSettings.twin_swaps`): every side
#: exchanged; every side but the legs' (knees and ankles stay: the body turned with its legs
#: where they are, for a track facing the wrong way with its thighs crossed to put the legs
#: right). No arms' counterpart: an elbow kept on its side while the shoulders exchange
#: theirs is out of an upper arm's reach.
TWIN_ORDERS = {"all": SIDES_SWAPPED,
               "all_but_legs": _sides_swapped_for(("shoulder", "elbow", "wrist", "hip"))}


def swapped_twins(body, pose, starts=TWIN_STARTS, swaps=("all",)):
    """``(K, 48)``: :func:`swapped_twin` fitted from each of ``starts`` (:data:`TWIN_STARTS`),
    for each joint order of ``swaps`` (:data:`TWIN_ORDERS`; ``K = len(swaps) * len(starts)``,
    order by order).

    ``"turned"`` starts from the pose turned about its long axis (:func:`swapped_twin`),
    ``"rest"`` from the rest pose placed by Kabsch on the trunk joints. The turned start
    keeps the pose's joint angles, and a wrong-facing pose's twists and bends, carried over,
    contort the twin: its joints land where they should, with the neck and spine bent and
    the shoulders twisted, and the climb cannot undo that. The rest start fits the same
    joints with every angle pulled toward zero.
    """
    pose = np.asarray(pose, dtype=np.float64)
    joints = np.asarray(body.joint_positions(pose))
    out = []
    for swap in swaps:
        if swap not in TWIN_ORDERS:
            raise ValueError(f"unknown twin swap {swap!r}; choose from {', '.join(TWIN_SWAPS)}")
        out.extend(twins_to(body, pose, joints[TWIN_ORDERS[swap]], starts))
    return np.array(out).reshape(-1, len(pose))


def twins_to(body, pose, target, starts=TWIN_STARTS):
    """``(len(starts), 48)``: poses facing the other way than ``pose (48,)`` fitted to the
    joints ``target (15, 3)`` (:func:`fit_joints`) from each of ``starts`` (as for
    :func:`swapped_twins`)."""
    out = []
    for start in starts:
        if start == "turned":
            x0 = turned_pose(pose)
        elif start == "rest":
            x0 = root_from_joints(body, target, TRUNK_ROOT_JOINTS)
        else:
            raise ValueError(f"unknown twin start {start!r}; choose from {', '.join(TWIN_STARTS)}")
        out.append(fit_joints(body, target, x0))
    return np.array(out).reshape(-1, len(np.asarray(pose)))


def root_from_joints(body, target, ids):
    """A pose ``(48,)`` with every joint at zero and the root placed by Kabsch so the
    joints ``ids`` of the rest pose best match ``target[ids]`` (``target (15, 3)``)."""
    from ..motion.retarget import best_rotation

    ids = list(ids)
    rest = np.asarray(body.joint_positions(np.zeros(body.dof)))
    R = best_rotation(rest[ids] - rest[ids].mean(0), target[ids] - target[ids].mean(0))
    x0 = np.zeros(body.dof)
    x0[3:6] = matrix_to_rotvec(R[None])[0]
    x0[0:3] = target[ids].mean(0) - R @ rest[ids].mean(0)
    return x0


def fit_joints(body, target, x0, iterations: int = 15, regularisation: float = 0.01,
               weights=None):
    """Levenberg-Marquardt from ``x0 (48,)`` to a pose whose joints match ``target (15, 3)``.

    Each iteration's Jacobian is one batched call of the kinematics (finite differences),
    so a fit takes milliseconds (the recheck runs it while tracking). A pull
    ``regularisation`` toward the zero pose fixes the twists joint positions leave free.
    ``weights (15,)``: each joint's weight (0 = unknown; default all 1).
    Returns ``(48,)``, within the joint limits.
    """
    x = body.clip(np.asarray(x0, dtype=np.float64))
    n, eps, lam = len(x), 1e-4, 1e-3
    reg = np.r_[np.zeros(6), np.full(n - 6, regularisation)]
    w = np.ones(len(target)) if weights is None else np.asarray(weights, dtype=np.float64)

    def residual(poses):
        d = (np.asarray(body.joint_positions(poses)) - target) * w[:, None]   # (N, 15, 3)
        return np.concatenate([d.reshape(len(poses), -1), reg * poses], axis=1)

    r = residual(x[None])[0]
    for _ in range(iterations):
        rs = residual(x[None] + eps * np.eye(n))                   # (n, 45 + n)
        J = ((rs - r) / eps).T
        step = np.linalg.solve(J.T @ J + lam * np.eye(n), -J.T @ r)
        y = body.clip(x + step)
        ry = residual(y[None])[0]
        if ry @ ry < r @ r:
            x, r, lam = y, ry, lam * 0.3
        else:
            lam *= 10.0
    return x


#: The limb twins of the sides recheck (:func:`.heading.recheck_limb_sides`): name -> joint order.
LIMB_SWAPS = {"legs": LEGS_SWAPPED, "arms": ARMS_SWAPPED}


def limb_swapped_twins(body, pose):
    """``[(name, (48,)), ...]``: ``pose (48,)`` with the legs' (knees and ankles) or the
    arms' (elbows and wrists) sides exchanged, fitted by :func:`fit_joints` from the pose
    itself: the trunk stays, each limb reaches where the other side's was (:data:`LIMB_SWAPS`).
    """
    pose = np.asarray(pose, dtype=np.float64)
    joints = np.asarray(body.joint_positions(pose))
    return [(name, fit_joints(body, joints[order], pose)) for name, order in LIMB_SWAPS.items()]


def facing_direction(pose):
    """The body's forward direction ``(3,)`` of ``pose (48,)`` (its root's)."""
    return rotvec_to_matrix(np.asarray(pose, dtype=np.float64)[3:6]) @ MODEL_FORWARD


def long_axis(pose):
    """The body's head direction ``(3,)`` of ``pose (48,)`` (its root's)."""
    return rotvec_to_matrix(np.asarray(pose, dtype=np.float64)[3:6]) @ MODEL_UP
