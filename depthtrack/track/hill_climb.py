"""Model-based hill climbing (the ToF paper's "HC"): coarse-to-fine, down the kinematic chain.

The search moves in *velocity* space: a candidate is ``x (+) delta`` (see
:func:`depthtrack.motion.prior.apply_velocity`), so a rotation step turns a joint about its
own current axes and never meets a rotation-vector singularity.

Schedule. The parameters are split into groups (root translation, root rotation, spine,
neck, each shoulder / hip, each elbow / knee, each wrist / ankle), and the groups into
*blocks* that are searched one after the other from the root outwards. Groups of one block
move disjoint parts of the image (the four limbs), so they are searched *together*: one
batch holds the moves of every active group of the block, each group keeps its best move,
and the improving moves are combined into one candidate whose energy is checked before it
is taken (the best single move is taken when the combination is worse). Each group has its
own coarse-to-fine ladder of step sizes: a group whose best move does not lower the energy
drops to the next finer step; a group that moved tries the same step again; a group leaves
the search when its finest step fails. Moves are +-step along each parameter of the group,
plus, for the rotation groups, the four diagonal moves in the plane of the first two axes,
and for the pelvis and the spine the same rotations with the children counter-rotated
(:attr:`SearchGroup.compensate`), and optionally the pelvis turned alone, the chest and the
legs kept (:attr:`SearchGroup.isolate`). Compensation with ``-R_c^T delta``: the parent's world
rotation becomes ``W_p R(delta)``; a child c keeps ``W_c = W_p R_c`` when its local rotation
becomes ``R(-delta) R_c = R_c R(-R_c^T delta)``, i.e. the local velocity ``-R_c^T delta``.

Everything is batched: one call of the energy function per iteration of a block (plus one
for the combined move), ``(N, 48) -> (N,)``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..body.rotations import rotvec_to_matrix
from ..body.skeleton import JOINT_ID
from ..motion.prior import apply_velocity
from .energy import spine_twist


@dataclass(frozen=True)
class SearchGroup:
    """Pose parameters searched together, with their coarsest step.

    Attributes
    ----------
    name : str
    params : tuple of int
        Indices into the pose / velocity vector.
    step : float
        Coarsest step (metres for translation, radians for rotations).
    diagonals : bool
        Also try the +-step, +-step moves in the plane of the first two parameters.
    compensate : tuple of int
        Child joints (skeleton indices) whose world orientation a second set of moves keeps:
        the +-step rotations of this joint are repeated with the inverse rotation given to
        these children, so the chest can turn under arms that stay where they are (a ridge
        of the likelihood that single-joint moves cannot follow).
    isolate : tuple of int
        Further children kept, with ``compensate``'s, in a third set of +-step rotations:
        with all its children kept, the joint's own segment alone turns (the pelvis between
        a chest and legs that stay, the hip sockets carried round). The likelihood barely
        sees that segment, so a track can leave it twisted against the chest; a single-joint
        or half-compensated move turns the chest or the legs with it and is refused.
    untwist : tuple of float
        For the pelvis: one more move per fraction ``f``, the pelvis turned alone (the chest
        and ``compensate``'s children kept) about its own vertical by ``f`` times the
        chest's twist against it (:func:`~.energy.spine_twist`), so that twist shrinks by
        that fraction in one step, however large it has grown.
    """

    name: str
    params: tuple
    step: float
    diagonals: bool = False
    compensate: tuple = ()
    isolate: tuple = ()
    untwist: tuple = ()

    def moves(self, step: float, pose=None, dof: int = 48) -> np.ndarray:
        """(M, dof) velocity moves at ``step`` from ``pose (dof,)``: +-step along each parameter,
        the diagonals, and the compensated rotations (these need ``pose``)."""
        k = len(self.params)
        unit = np.concatenate([np.eye(k), -np.eye(k)])
        if self.diagonals and k >= 2:
            d = np.zeros((4, k))
            d[:, :2] = np.array([[1, 1], [1, -1], [-1, 1], [-1, -1]]) / np.sqrt(2.0)
            unit = np.concatenate([unit, d])
        out = np.zeros((len(unit), dof))
        out[:, list(self.params)] = unit * step
        if pose is None or k != 3:
            return out
        sets = [self.compensate] if self.compensate else []
        if self.isolate:
            sets.append(self.compensate + self.isolate)
        for kept in sets:
            out = np.concatenate([out, self.compensated(out[:2 * k], kept, pose)])
        if self.untwist:
            twist = float(spine_twist(pose)[0])
            turns = np.zeros((len(self.untwist), dof))
            turns[:, self.params[1]] = np.asarray(self.untwist, dtype=np.float64) * twist
            out = np.concatenate([out, self.compensated(turns, self.compensate + (SPINE,), pose)])
        return out

    def compensated(self, unit_moves, kept, pose) -> np.ndarray:
        """``unit_moves (M, dof)`` (rotations of this joint) with every child in ``kept``
        given the inverse rotation, so it keeps its world rotation."""
        base = unit_moves.copy()
        delta = base[:, list(self.params)]                          # (M, 3) rotation steps
        for c in kept:
            R_c = rotvec_to_matrix(np.asarray(pose, dtype=np.float64)[3 + 3 * c: 6 + 3 * c])
            # child's local velocity -R_c^T delta keeps its world rotation (module docstring)
            base[:, 3 + 3 * c: 6 + 3 * c] = -delta @ R_c
        return base


def _rot(joint: int):
    return (3 + 3 * joint, 4 + 3 * joint, 5 + 3 * joint)




#: Skeleton index of the spine (the chest), a child of the pelvis.
SPINE = JOINT_ID["spine"]


def default_blocks(step_scale: float = 1.0, diagonals: bool = True, pelvis_alone: bool = False,
                   untwist=()):
    """The root-to-limbs schedule: a list of blocks, each a list of :class:`SearchGroup`.

    Coarsest steps (at 25 fps, times ``step_scale``): pelvis 6 cm and 0.12 rad, spine 0.12
    rad, neck 0.2, shoulders and hips 0.3, elbows and knees 0.35, wrists and ankles 0.4 rad.
    ``pelvis_alone``: the pelvis also turns alone, the chest kept with the legs
    (:attr:`SearchGroup.isolate`); ``untwist``: fractions of the chest's twist the pelvis
    may turn back by in one move (:attr:`SearchGroup.untwist`).
    """
    s = float(step_scale)

    def g(name, step, diag=True, compensate=(), isolate=(), untwist=()):
        return SearchGroup(name, _rot(JOINT_ID[name]), step * s, diag and diagonals,
                           tuple(JOINT_ID[c] for c in compensate),
                           tuple(JOINT_ID[c] for c in isolate), tuple(float(f) for f in untwist))

    return [
        [SearchGroup("pelvis_t", (0, 1, 2), 0.06 * s, diagonals)],
        [g("pelvis", 0.12, compensate=("l_hip", "r_hip"),
           isolate=("spine",) if pelvis_alone else (), untwist=untwist)],
        [g("spine", 0.12, compensate=("neck", "l_shoulder", "r_shoulder"))],
        [g("neck", 0.2), g("l_shoulder", 0.3), g("r_shoulder", 0.3), g("l_hip", 0.3), g("r_hip", 0.3)],
        [g("l_elbow", 0.35), g("r_elbow", 0.35), g("l_knee", 0.35), g("r_knee", 0.35)],
        [g("l_wrist", 0.4, False), g("r_wrist", 0.4, False), g("l_ankle", 0.4, False),
         g("r_ankle", 0.4, False)],
    ]


def restrict_blocks(blocks, names):
    """The blocks with only the groups named in ``names`` (empty blocks dropped)."""
    names = set(names)
    out = [[g for g in block if g.name in names] for block in blocks]
    return [b for b in out if b]


@dataclass
class ClimbResult:
    """Outcome of :meth:`HillClimber.climb`.

    Attributes
    ----------
    pose : (48,) float
    energy : float
    evaluations : int
        Candidates scored.
    calls : int
        Calls of the energy function.
    """

    pose: np.ndarray
    energy: float
    evaluations: int = 0
    calls: int = 0


@dataclass
class HillClimber:
    """Coarse-to-fine, block-parallel coordinate search (see the module docstring).

    Parameters
    ----------
    blocks : list of list of SearchGroup
        Searched in order (default :func:`default_blocks`).
    levels : int
        Rungs of each group's step ladder: ``step, step/2, ..., step/2^(levels-1)``.
    max_iterations : int
        Most batches per block.
    clip : callable or None
        ``(N, 48) -> (N, 48)`` projection onto the joint limits (``body.clip``).
    shrink : float
        Factor between rungs.
    """

    blocks: list = field(default_factory=default_blocks)
    levels: int = 3
    max_iterations: int = 8
    clip: object = None
    shrink: float = 0.5

    def climb(self, pose, energy, start_energy=None, blocks=None, levels=None, passes: int = 1,
              level_offset: int = 0) -> ClimbResult:
        """Lower ``energy`` from ``pose`` by the block schedule.

        Parameters
        ----------
        pose : (48,) float
        energy : callable ``(N, 48) -> (N,)``
            Lower is better; called with batches.
        start_energy : float, optional
            ``energy(pose)`` when already known.
        blocks : list of list of SearchGroup, optional
            Overrides ``self.blocks`` (e.g. only the chain of one limb).
        levels : int, optional
            Overrides ``self.levels``.
        passes : int
            Times to run the whole schedule (later passes start one rung finer).
        level_offset : int
            First rung of the ladder (0 = coarsest step).

        Returns
        -------
        ClimbResult
        """
        x = np.asarray(pose, dtype=np.float64).copy()
        evaluations = calls = 0
        if start_energy is None:
            e = float(energy(x[None])[0])
            evaluations += 1
            calls += 1
        else:
            e = float(start_energy)
        blocks = self.blocks if blocks is None else blocks
        n_levels = self.levels if levels is None else levels
        for p in range(passes):
            first = min(level_offset + p, n_levels - 1)
            for block in blocks:
                x, e, n_eval, n_call = self._climb_block(x, e, block, energy, n_levels, first)
                evaluations += n_eval
                calls += n_call
        return ClimbResult(x, e, evaluations, calls)

    def _climb_block(self, x, e, block, energy, n_levels, first_level):
        level = np.full(len(block), first_level)
        evaluations = calls = 0
        for _ in range(self.max_iterations):
            active = np.flatnonzero(level < n_levels)
            if len(active) == 0:
                break
            moves = [block[i].moves(block[i].step * self.shrink ** level[i], x) for i in active]
            owner = np.concatenate([np.full(len(m), k) for k, m in enumerate(moves)])
            deltas = np.concatenate(moves)
            candidates = apply_velocity(x, deltas)
            if self.clip is not None:
                candidates = self.clip(candidates)
            energies = np.asarray(energy(candidates), dtype=np.float64)
            evaluations += len(candidates)
            calls += 1
            improved = []
            for k, gi in enumerate(active):
                mine = np.flatnonzero(owner == k)
                best = mine[np.argmin(energies[mine])]
                if energies[best] < e - 1e-12:
                    improved.append(best)
                else:
                    level[gi] += 1
            if not improved:
                continue
            best_single = min(improved, key=lambda i: energies[i])
            if len(improved) == 1:
                x, e = candidates[best_single], float(energies[best_single])
                continue
            combined = apply_velocity(x, deltas[improved].sum(axis=0))
            if self.clip is not None:
                combined = self.clip(combined[None])[0]
            e_combined = float(energy(combined[None])[0])
            evaluations += 1
            calls += 1
            if e_combined <= energies[best_single]:
                x, e = combined, e_combined
            else:
                x, e = candidates[best_single], float(energies[best_single])
        return x, e, evaluations, calls
