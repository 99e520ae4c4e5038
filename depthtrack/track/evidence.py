"""Evidence propagation: MAP pose from one part detection, linearised with the unscented transform.

The ToF paper's "probabilistic inverse kinematics": a detection ``p_j`` of body part i is
modelled as ``p_j ~ N(p_i(x_t), O)``, and ``x_t = x_{t-1} (+) v_t`` with the Gaussian prior
``v_t ~ N(m, Sigma)``. The part position is a non-linear function ``p_i(v)`` of the velocity
of the kinematic chain from the root to the part. It is linearised by *statistical linear
regression* through sigma points (the unscented transform), the linear-Gaussian MAP is
solved in closed form, and the linearisation is redone about the new estimate until it
converges: the iterated posterior-linearisation measurement update (an iterated UKF update,
Garcia-Fernandez et al. 2015), which equals the exact MAP when ``p_i`` is linear.

Generic math (:func:`sigma_points`, :func:`statistical_linearisation`,
:func:`iterated_unscented_update`) is pure numpy over any batched function
``f : (S, n) -> (S, m)``. :class:`PartModel` and :func:`propagate_evidence` apply it to the
body: the sigma points are velocities of the chain's pose parameters, propagated through
batched forward kinematics.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..motion.prior import apply_velocity

#: Skeleton joint carrying each part, and the joints of its chain from the root.
PART_JOINT = {"head": "neck", "l_hand": "l_wrist", "r_hand": "r_wrist",
              "l_foot": "l_ankle", "r_foot": "r_ankle"}
#: Joints that may also be parts at their centre (the recogniser's joint proposals): a
#: joint-centre part is named after its skeleton joint.
CENTRE_JOINTS = ("l_shoulder", "r_shoulder", "l_elbow", "r_elbow", "l_wrist", "r_wrist",
                 "l_hip", "r_hip", "l_knee", "r_knee", "l_ankle", "r_ankle")


# ---------------------------------------------------------------------- generic unscented math
def sigma_points(mean, cov, alpha: float = 1.0, beta: float = 0.0, kappa: float = 0.0):
    """Scaled unscented-transform sigma points and weights (van der Merwe).

    Parameters
    ----------
    mean : (n,) float
    cov : (n, n) float
        Symmetric positive semi-definite.
    alpha, beta, kappa : float
        Spread ``sqrt(n + lambda)`` with ``lambda = alpha^2 (n + kappa) - n``; the defaults
        give the cubature rule (2n points at ``+-sqrt(n)`` standard deviations, centre weight 0).

    Returns
    -------
    points : (2n+1, n) float
        The mean, then ``mean + columns`` and ``mean - columns`` of ``sqrt((n+lambda) cov)``.
    wm, wc : (2n+1,) float
        Weights for means and covariances.
    """
    mean = np.asarray(mean, dtype=np.float64)
    cov = np.asarray(cov, dtype=np.float64)
    n = mean.shape[0]
    lam = alpha * alpha * (n + kappa) - n
    scale = n + lam
    # Cholesky fails on singular covariances; the symmetric square root does not.
    w, V = np.linalg.eigh(0.5 * (cov + cov.T))
    root = V * np.sqrt(np.clip(w, 0.0, None) * scale)
    points = np.concatenate([mean[None], mean + root.T, mean - root.T])
    wm = np.full(2 * n + 1, 0.5 / scale)
    wc = wm.copy()
    wm[0] = lam / scale
    wc[0] = lam / scale + (1.0 - alpha * alpha + beta)
    return points, wm, wc


def statistical_linearisation(f, mean, cov, **sigma_kwargs):
    """Best linear fit ``f(x) ~ A x + b + e, e ~ N(0, Omega)`` of ``f`` under ``N(mean, cov)``.

    Parameters
    ----------
    f : callable ``(S, n) -> (S, m)``
        Batched over sigma points.
    mean : (n,) float
    cov : (n, n) float
    **sigma_kwargs
        ``alpha, beta, kappa`` of :func:`sigma_points`.

    Returns
    -------
    A : (m, n) float
    b : (m,) float
    omega : (m, m) float
        Covariance of the linearisation error (positive semi-definite).
    """
    X, wm, wc = sigma_points(mean, cov, **sigma_kwargs)
    Y = np.asarray(f(X), dtype=np.float64)
    y_mean = wm @ Y
    dX = X - mean
    dY = Y - y_mean
    cross = (wc[:, None] * dX).T @ dY              # (n, m) cov(x, y)
    y_cov = (wc[:, None] * dY).T @ dY              # (m, m)
    A = np.linalg.lstsq(cov, cross, rcond=None)[0].T if cov.size else np.zeros((Y.shape[1], 0))
    b = y_mean - A @ mean
    omega = y_cov - A @ cov @ A.T
    w, V = np.linalg.eigh(0.5 * (omega + omega.T))
    omega = (V * np.clip(w, 0.0, None)) @ V.T
    return A, b, omega


@dataclass
class UnscentedUpdate:
    """Result of :func:`iterated_unscented_update`.

    Attributes
    ----------
    mean : (n,) float
        Posterior mode (MAP) of the linear-Gaussian approximation at convergence.
    cov : (n, n) float
        Its posterior covariance.
    iterations : int
    converged : bool
    residual : (m,) float
        ``z - f(mean)``.
    """

    mean: np.ndarray
    cov: np.ndarray
    iterations: int
    converged: bool
    residual: np.ndarray


def iterated_unscented_update(f, prior_mean, prior_cov, z, obs_cov, start=None,
                              max_iterations: int = 12, tol: float = 1e-3, **sigma_kwargs):
    """MAP of ``x ~ N(prior_mean, prior_cov)``, ``z ~ N(f(x), obs_cov)`` by iterated statistical linearisation.

    Each iteration fits ``f ~ A x + b (+ N(0, Omega))`` by the unscented transform under the
    current posterior approximation ``N(m_k, P_k)`` and applies the Kalman update to the
    *prior* with that fit::

        S = A Sigma A^T + O + Omega,  K = Sigma A^T S^-1
        m_{k+1} = m0 + K (z - A m0 - b),  P_{k+1} = Sigma - K S K^T

    It stops when the step ``m_{k+1} - m_k`` is below ``tol`` in prior standard deviations.
    For linear ``f`` the first iteration is exact (the Kalman / linear-Gaussian MAP). Far
    from the mode a step is halved until the exact negative log-posterior decreases, so
    the iteration never diverges or oscillates.

    Parameters
    ----------
    f : callable ``(S, n) -> (S, m)``
    prior_mean : (n,) float
    prior_cov : (n, n) float
    z : (m,) float
    obs_cov : (m, m) float
    start : (n,) float, optional
        First linearisation point (default ``prior_mean``).
    max_iterations : int
    tol : float

    Returns
    -------
    UnscentedUpdate
    """
    m0 = np.asarray(prior_mean, dtype=np.float64)
    P0 = np.asarray(prior_cov, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    R = np.asarray(obs_cov, dtype=np.float64)
    std = np.sqrt(np.clip(np.diag(P0), 1e-300, None))
    P0_inv = np.linalg.pinv(P0)
    R_inv = np.linalg.inv(R)

    def objective(x):
        r = z - np.asarray(f(x[None]), dtype=np.float64)[0]
        d = x - m0
        return 0.5 * d @ P0_inv @ d + 0.5 * r @ R_inv @ r

    m = m0.copy() if start is None else np.asarray(start, dtype=np.float64).copy()
    J = objective(m)
    P = P0.copy()
    converged = False
    it = 0
    for it in range(1, max_iterations + 1):
        A, b, omega = statistical_linearisation(f, m, P, **sigma_kwargs)
        S = A @ P0 @ A.T + R + omega
        K = np.linalg.solve(S, A @ P0).T            # (n, m) = P0 A^T S^-1 (S symmetric)
        target = m0 + K @ (z - A @ m0 - b)
        P = P0 - K @ S @ K.T
        P = 0.5 * (P + P.T)
        # Far from the mode a linearisation can overshoot: halve the step until the exact
        # negative log-posterior decreases (a no-op in the linear case).
        step = target - m
        for _ in range(6):
            J_new = objective(m + step)
            if J_new <= J:
                break
            step = 0.5 * step
        else:
            # no step along the linearised update lowers the exact objective: a local mode
            converged = True
            break
        m, J = m + step, J_new
        if (np.max(np.abs(step) / std) if len(m) else 0.0) < tol:
            converged = True
            break
    residual = z - np.asarray(f(m[None]), dtype=np.float64)[0]
    return UnscentedUpdate(m, P, it, converged, residual)


# ---------------------------------------------------------------------- body parts
def _chain_parameters(parents, j: int):
    """``(k,) int`` pose-parameter indices moving joint ``j``'s frame: the root translation,
    then the rotation of every joint from the root down to ``j`` (included)."""
    chain = []
    while j >= 0:
        chain.append(j)
        j = int(parents[j])
    idx = [0, 1, 2]
    for k in reversed(chain):
        idx += [3 + 3 * k, 4 + 3 * k, 5 + 3 * k]
    return np.array(idx)


@dataclass(frozen=True)
class PartModel:
    """Where the detectable parts sit on a body, and the chains that move them.

    The five surface parts (``head, l_hand, r_hand, l_foot, r_foot``, the geodesic
    detector's classes) come first, then any joint-centre parts (:data:`CENTRE_JOINTS`,
    the recogniser's proposals): offset and radius 0, since a proposal is a joint centre
    already pushed behind the surface.

    Attributes
    ----------
    names : tuple of str
        ``head, l_hand, r_hand, l_foot, r_foot``, then the joint-centre parts.
    joint : (P,) int
        Skeleton joint whose frame carries each part.
    offset : (P, 3) float
        The part centre in that joint's frame (metres).
    radius : (P,) float
        Half the part's thickness: a detection on the visible surface lies this much nearer
        the camera than the centre.
    chains : dict {str: (k,) int}
        Pose-parameter indices from the root to the part (root translation and rotation,
        then every joint on the way; the part's own joint only when it moves the part, i.e.
        not for a joint-centre part).
    """

    names: tuple
    joint: np.ndarray
    offset: np.ndarray
    radius: np.ndarray
    chains: dict

    @classmethod
    def from_body(cls, body, centres=()) -> "PartModel":
        """Part centres measured on ``body``'s mesh: head centre, hand centroid, and the
        centroid of the upper half of the foot (what a camera in front sees of it); then
        the joint-centre parts named in ``centres`` (of :data:`CENTRE_JOINTS`)."""
        names = tuple(PART_JOINT)
        joint_ids = {n: i for i, n in enumerate(body.joint_names)}
        parents = np.asarray(body.parents)
        world = np.asarray(body.world_transforms(np.zeros(body.dof)))
        rest = np.asarray(body.rest_vertices)
        mesh = body.mesh
        dominant = np.asarray(mesh.joints)[np.arange(len(mesh.joints)), np.asarray(mesh.weights).argmax(1)]
        joints, offsets, radii, chains = [], [], [], {}
        for name in names:
            j = joint_ids[PART_JOINT[name]]
            if name == "head":
                offset = np.asarray(body.head_offset, dtype=np.float64)
                verts = rest[dominant == j]
                radius = 0.5 * float(np.ptp(verts[:, 0])) if len(verts) else 0.09
            else:
                verts = rest[dominant == j] - world[j, :3, 3]
                if len(verts) == 0:
                    offset, radius = np.zeros(3), 0.03
                else:
                    if name.endswith("foot"):
                        # seen from the front a foot shows its upper half (instep)
                        verts = verts[verts[:, 1] <= np.median(verts[:, 1])]
                    offset = verts.mean(axis=0)
                    radius = 0.5 * float(np.ptp(verts, axis=0).min())
            joints.append(j)
            offsets.append(offset)
            radii.append(radius)
            chains[name] = _chain_parameters(parents, j)
        for name in centres:
            if name not in CENTRE_JOINTS:
                raise ValueError(f"not a joint-centre part: {name!r}")
            j = joint_ids[name]
            joints.append(j)
            offsets.append(np.zeros(3))
            radii.append(0.0)
            # the joint's own rotation does not move its centre: the chain stops at its parent
            chains[name] = _chain_parameters(parents, int(parents[j]))
        names = names + tuple(centres)
        return cls(names, np.array(joints), np.array(offsets).reshape(-1, 3), np.array(radii), chains)

    def index(self, name: str) -> int:
        return self.names.index(name)

    def positions(self, body, poses, surface: bool = True):
        """Part positions for a batch of poses.

        Parameters
        ----------
        body : BodyModel
        poses : (N, 48) float
        surface : bool
            Move each centre toward the camera by the part's radius (where a detection on
            the visible surface lies).

        Returns
        -------
        (N, P, 3) float, camera frame.
        """
        world = np.asarray(body.world_transforms(np.atleast_2d(poses)))
        T = world[:, self.joint]                                  # (N, 5, 4, 4)
        p = np.einsum("npij,pj->npi", T[..., :3, :3], self.offset) + T[..., :3, 3]
        if surface:
            p = p - self.radius[:, None] * p / np.linalg.norm(p, axis=-1, keepdims=True)
        return p


# ---------------------------------------------------------------------- the tracker's EP step
@dataclass
class EvidenceResult:
    """Outcome of :func:`propagate_evidence`.

    Attributes
    ----------
    pose : (48,) float
        The posterior mode ``x = base (+) v``, clipped to the joint limits.
    velocity : (48,) float
        The posterior-mode velocity relative to the base pose.
    update : UnscentedUpdate
        The chain's posterior (mean/covariance over the chain's parameters).
    part_error : float
        Distance from the part at ``pose`` to the detection (m).
    """

    pose: np.ndarray
    velocity: np.ndarray
    update: UnscentedUpdate
    part_error: float


def propagate_evidence(body, parts: PartModel, part: str, target, base_pose, prior_mean, prior_std,
                       obs_std: float = 0.04, start_velocity=None, surface: bool = True,
                       max_iterations: int = 25, tol: float = 1e-3) -> EvidenceResult:
    """MAP pose given one correspondence (part ``part`` <-> detection at ``target``).

    Parameters
    ----------
    body : BodyModel
    parts : PartModel
    part : str
        One of ``parts.names``.
    target : (3,) float
        Detected position, camera frame.
    base_pose : (48,) float
        ``x_{t-1}`` (or another anchor): velocities are relative to it.
    prior_mean, prior_std : (48,) float
        Gaussian prior ``v ~ N(prior_mean, diag(prior_std^2))``.
    obs_std : float
        Standard deviation of the detection per axis (m).
    start_velocity : (48,) float, optional
        Linearisation start; also supplies every parameter outside the part's chain
        (default ``prior_mean``).
    surface : bool
        Compare the detection with the part's visible surface point (see :meth:`PartModel.positions`).

    Returns
    -------
    EvidenceResult
    """
    base_pose = np.asarray(base_pose, dtype=np.float64)
    prior_mean = np.asarray(prior_mean, dtype=np.float64)
    prior_std = np.asarray(prior_std, dtype=np.float64)
    start = prior_mean if start_velocity is None else np.asarray(start_velocity, dtype=np.float64)
    chain = parts.chains[part]
    k = parts.index(part)

    def part_position(chain_velocities):
        v = np.repeat(start[None], len(chain_velocities), axis=0)
        v[:, chain] = chain_velocities
        poses = apply_velocity(base_pose, v)
        return parts.positions(body, poses, surface=surface)[:, k]

    update = iterated_unscented_update(
        part_position, prior_mean[chain], np.diag(prior_std[chain] ** 2),
        np.asarray(target, dtype=np.float64), np.eye(3) * obs_std ** 2,
        start=start[chain], max_iterations=max_iterations, tol=tol)
    velocity = start.copy()
    velocity[chain] = update.mean
    pose = body.clip(apply_velocity(base_pose, velocity))
    error = float(np.linalg.norm(parts.positions(body, pose[None], surface=surface)[0, k] - target))
    return EvidenceResult(pose, velocity, update, error)
