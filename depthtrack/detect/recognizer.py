"""Per-pixel body-part recognition and joint proposals from one depth frame.

After Shotton et al., "Real-time human pose recognition in parts from single depth
images" (CVPR 2011): randomized decision trees over depth-invariant depth-difference
features (:mod:`.features`) label every person pixel with one of :data:`BODY_PARTS`
(:mod:`.recognizer_parts`); mean shift over the back-projected pixels, weighted by the
part's probability times the pixel's surface area, finds each part's modes, and each mode
pushed a learned depth behind the surface proposes a joint. The shipped trees also split
on each pixel's offset from the centre of the person's points (``meta["extras"] ==
"centroid"``, :func:`~depthtrack.detect.features.centroid_features`).

An optional first stage (not in the shipped model, see the README): regression trees
estimate the body's axes (where the torso faces, where its head is) from every pixel,
averaged over the frame, and the part trees also split on those axes and each pixel's
coordinates along them (:func:`~depthtrack.detect.features.body_frame_features`), meant
to tell front from back, and so left from right.

* :func:`recognize` ``(depth, mask, camera) -> (labels (H, W) int8, probs (H, W, C) float32)``
* :func:`joint_proposals` ``(depth, probs, camera, k=3) -> JointProposals`` -- up to ``k``
  3D proposals with confidences for each of the 15 contract joints.
* :func:`body_orientation` ``(depth, mask, camera) -> (forward (3,), up (3,))`` (with the
  optional first stage only)

The trees ship as ``depthtrack/data/recognizer.npz`` (``tools/train_recognizer.py``),
evaluated with numpy alone.
"""
from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from ..contract import JOINT_NAMES
from ..errors import InputError
from .features import body_frame_features, centroid_features, pair_features, probe_image, side_features
from .recognizer_parts import BODY_PARTS, JOINT_PARTS, PART_ID

FORMAT = "depthtrack-recognizer/1"
#: Mean-shift bandwidth (m) and the least part probability a pixel needs to vote (Shotton's b_c, lambda_c).
BANDWIDTH = 0.065
MIN_PROBABILITY = 0.14


def default_path() -> Path:
    return Path(str(resources.files("depthtrack") / "data" / "recognizer.npz"))


class Trees:
    """Decision trees stored as flat numpy arrays (several trees in one set of arrays).

    Attributes
    ----------
    feature : (n,) int32
        Input of each split node: an index into the offset pairs, or ``K + e`` for the
        e-th per-pixel extra input (:data:`~depthtrack.detect.features.BODY_FRAME_NAMES`).
    threshold : (n,) float32
        A pixel goes left when its input is ``<= threshold``.
    left : (n,) int32
        Left child, -1 for leaves.
    right : (n,) int32
        Right child; for leaves, the row of ``leaf_values``.
    roots : (T,) int32
    leaf_values : (L, V) float32
        Class distribution (classifier) or target vector (regressor) of each leaf.
    """

    def __init__(self, feature, threshold, left, right, roots, leaf_values):
        self.feature = np.asarray(feature, np.int32)
        self.threshold = np.asarray(threshold, np.float32)
        self.left = np.asarray(left, np.int32)
        self.right = np.asarray(right, np.int32)
        self.roots = np.asarray(roots, np.int32)
        self.leaf_values = np.asarray(leaf_values, np.float32)

    def arrays(self, prefix: str) -> dict:
        return {f"{prefix}feature": self.feature.astype(np.int16), f"{prefix}threshold": self.threshold.astype(np.float16),
                f"{prefix}left": self.left, f"{prefix}right": self.right, f"{prefix}roots": self.roots}

    @classmethod
    def from_arrays(cls, z, prefix: str, leaf_values) -> "Trees":
        return cls(z[f"{prefix}feature"], z[f"{prefix}threshold"], z[f"{prefix}left"], z[f"{prefix}right"],
                   z[f"{prefix}roots"], leaf_values)

    def predict(self, image, rows, cols, offsets, fx: float, fy: float, extras=None) -> np.ndarray:
        """Mean leaf value over the trees for each pixel.

        Parameters
        ----------
        image : (H, W) float32
            :func:`~depthtrack.detect.features.probe_image` of the frame.
        rows, cols : (N,) int
            Person pixels.
        offsets : (K, 4) float32
        fx, fy : float
        extras : (N, E) float32 or None
            Per-pixel extra inputs (needed when the trees split on them).

        Returns
        -------
        (N, V) float32
        """
        n, trees, k = len(rows), len(self.roots), len(offsets)
        if n == 0:
            return np.zeros((0, self.leaf_values.shape[1]), np.float32)
        node = np.repeat(self.roots, n)
        pix = np.tile(np.arange(n), trees)
        r = np.asarray(rows, np.float32)
        c = np.asarray(cols, np.float32)
        d = image[np.asarray(rows), np.asarray(cols)].astype(np.float32)
        active = np.flatnonzero(self.left[node] >= 0)
        while active.size:         # one level of every tree per pass, only pixels not yet at a leaf
            at = node[active]
            i = pix[active]
            fid = self.feature[at]
            f = pair_features(image, r[i], c[i], d[i], offsets[np.minimum(fid, k - 1)], fx, fy)
            if extras is not None:
                ext = fid >= k
                f[ext] = extras[i[ext], fid[ext] - k]
            nxt = np.where(f <= self.threshold[at], self.left[at], self.right[at])
            node[active] = nxt
            active = active[self.left[nxt] >= 0]
        return self.leaf_values[self.right[node]].reshape(trees, n, -1).mean(axis=0)


class PartForest:
    """The recogniser's two forests and what proposals need.

    Attributes
    ----------
    offsets : (K, 4) float32
        Candidate offset pairs ``u_x, u_y, v_x, v_y`` (m) that split nodes index.
    orient : Trees or None
        Optional first stage (``train_recognizer.py --orientation``; the shipped model has
        none): regression trees giving per pixel the body's ``forward`` and ``up`` axes
        (camera frame, 6 values), averaged over the person to one estimate per frame.
    parts : Trees
        Classification trees over the offset pairs (and, after an orientation stage, the
        body-frame inputs): the :data:`BODY_PARTS` distribution per pixel.
    side : Trees or None
        Optional side stage (``train_recognizer.py --extras centroid+side``): regression trees
        giving per pixel the camera x and y of the subject's left axis, averaged over the
        person to one estimate per frame, which the part trees then split on.
    push_back : (15,) float32
        Metres a joint lies behind its part's surface mode (camera z).
    meta : dict
        How the forest was trained; ``meta["extras"]`` names the per-pixel extra inputs.
    """

    def __init__(self, offsets, orient: Trees | None, parts: Trees, push_back, meta=None, side: Trees | None = None):
        self.offsets = np.asarray(offsets, np.float32)
        self.side = side
        self.orient = orient
        self.parts = parts
        self.push_back = np.asarray(push_back, np.float32)
        self.meta = dict(meta or {})
        if self.extras not in ("none", "centroid", "centroid+side") or (self.extras == "centroid+side") != (side is not None):
            raise ValueError(f"unknown per-pixel extras {self.extras!r}")
        if parts.leaf_values.shape[1] != len(BODY_PARTS) \
                or (orient is not None and orient.leaf_values.shape[1] != 6) \
                or self.push_back.shape != (len(JOINT_NAMES),):
            raise ValueError("forest does not match BODY_PARTS / the contract joints")

    @property
    def extras(self) -> str:
        """Per-pixel inputs the part trees split on besides the offset pairs (without an
        orientation stage): ``"none"``, ``"centroid"`` (:func:`~depthtrack.detect.features.centroid_features`),
        or ``"centroid+side"`` (and :func:`~depthtrack.detect.features.side_features` from :attr:`side`)."""
        return self.meta.get("extras", "none")

    # ------------------------------------------------------------------ files
    def save(self, path) -> None:
        """Write the forest to ``path`` (.npz) atomically; part distributions as uint8."""
        from ..io.atomic import atomic_path

        meta = {**self.meta, "format": FORMAT, "parts": list(BODY_PARTS), "joints": list(JOINT_NAMES)}
        orient = {} if self.orient is None else {**self.orient.arrays("orient_"),
                                                 "orient_values": self.orient.leaf_values.astype(np.float16)}
        if self.side is not None:
            orient.update(self.side.arrays("side_"), side_values=self.side.leaf_values.astype(np.float16))
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as fh:
                np.savez_compressed(
                    fh, offsets=self.offsets.astype(np.float16), **orient, **self.parts.arrays("parts_"),
                    parts_values=np.rint(self.parts.leaf_values * 255).astype(np.uint8),
                    push_back=self.push_back, meta=json.dumps(meta))

    @classmethod
    def load(cls, path) -> "PartForest":
        """Read a forest written by :meth:`save`; a one-line error for anything else."""
        try:
            with np.load(path, allow_pickle=False) as z:
                meta = json.loads(str(z["meta"]))
                if meta.get("format") != FORMAT or meta.get("parts") != list(BODY_PARTS):
                    raise InputError(path, f"not a {FORMAT} model for these body parts")
                probs = z["parts_values"].astype(np.float32) / 255.0
                probs /= np.maximum(probs.sum(axis=1, keepdims=True), 1e-6)
                orient = Trees.from_arrays(z, "orient_", z["orient_values"]) if "orient_values" in z else None
                side = Trees.from_arrays(z, "side_", z["side_values"]) if "side_values" in z else None
                return cls(z["offsets"], orient, Trees.from_arrays(z, "parts_", probs), z["push_back"], meta, side)
        except (OSError, KeyError, ValueError) as exc:
            raise InputError(path, f"cannot read the recogniser model ({exc})") from None

    # ------------------------------------------------------------------ inference
    def orientation(self, image, rows, cols, fx: float, fy: float, max_pixels: int = 800):
        """The body's ``forward`` and ``up`` unit axes (camera frame), from evenly thinned pixels;
        NaN without an orientation stage or pixels."""
        if self.orient is None or not len(rows):
            return np.full(3, np.nan), np.full(3, np.nan)
        step = max(1, int(np.ceil(len(rows) / max_pixels)))
        v = self.orient.predict(image, rows[::step], cols[::step], self.offsets, fx, fy).mean(axis=0)
        forward = v[:3] / max(np.linalg.norm(v[:3]), 1e-9)
        up = v[3:] - (v[3:] @ forward) * forward
        return forward, up / max(np.linalg.norm(up), 1e-9)

    def side_axis(self, image, rows, cols, fx: float, fy: float, max_pixels: int = 800) -> np.ndarray:
        """(2,) camera x, y of the subject's left axis from evenly thinned pixels (side stage;
        zeros without one)."""
        if self.side is None or not len(rows):
            return np.zeros(2, np.float32)
        step = max(1, int(np.ceil(len(rows) / max_pixels)))
        return self.side.predict(image, rows[::step], cols[::step], self.offsets, fx, fy).mean(axis=0)

    def predict(self, image, rows, cols, points, fx: float, fy: float, orientation=None):
        """Part probabilities ``(N, C)`` of pixels, and the ``(forward, up)`` used.

        Parameters
        ----------
        image : (H, W) float32
        rows, cols : (N,) int
        points : (N, 3) float
            The pixels' camera-frame points.
        fx, fy : float
        orientation : (forward (3,), up (3,)) or None
            Default: estimated with :meth:`orientation`.
        """
        if self.orient is None:
            extras = None
            if self.extras != "none":
                extras = centroid_features(points, points.mean(axis=0))
            if self.side is not None:
                extras = np.hstack([extras, side_features(extras, self.side_axis(image, rows, cols, fx, fy))])
            return self.parts.predict(image, rows, cols, self.offsets, fx, fy, extras), None
        if orientation is None:
            orientation = self.orientation(image, rows, cols, fx, fy)
        extras = body_frame_features(points, points.mean(axis=0), *orientation)
        return self.parts.predict(image, rows, cols, self.offsets, fx, fy, extras), orientation


@functools.lru_cache(maxsize=4)
def _load_default(path: str) -> PartForest:
    return PartForest.load(path)


def load_forest(path=None) -> PartForest:
    """The shipped forest (cached), or the one at ``path``."""
    return _load_default(str(default_path() if path is None else Path(path)))


def recognize(depth, mask, camera, forest: PartForest | None = None, probabilities: bool = True,
              orientation=None):
    """Label every person pixel of a depth frame with a body part.

    Parameters
    ----------
    depth : (H, W) float
        Metres, 0 = no reading.
    mask : (H, W) bool
        The person (e.g. ``segment_foreground(depth, camera).mask``).
    camera : Camera
    forest : PartForest, optional
        Default: the shipped model.
    probabilities : bool
        Also return the per-pixel class probabilities.
    orientation : (forward (3,), up (3,)) or None
        The body's axes when known (e.g. from the tracked pose); default: estimated from the
        frame (:func:`body_orientation`).

    Returns
    -------
    labels : (H, W) int8
        Index into :data:`BODY_PARTS`; -1 off the person and where the person reads nothing.
    probs : (H, W, C) float32 or None
        Class probabilities (0 off the person); None unless ``probabilities``.
    """
    depth = np.asarray(depth, np.float32)
    mask = np.asarray(mask, bool)
    if depth.shape != camera.shape or mask.shape != camera.shape:
        raise InputError(None, f"depth {depth.shape} and mask {mask.shape} must match the camera "
                               f"{camera.shape}")
    forest = load_forest() if forest is None else forest
    image = probe_image(depth, mask)
    rows, cols = np.nonzero(mask & (depth > 0))
    labels = np.full(depth.shape, -1, np.int8)
    probs = np.zeros(depth.shape + (len(BODY_PARTS),), np.float32) if probabilities else None
    if len(rows):
        points = camera.backproject(depth[rows, cols], np.stack([cols, rows], axis=1).astype(float))
        p, _ = forest.predict(image, rows, cols, points, camera.fx, camera.fy, orientation)
        labels[rows, cols] = p.argmax(axis=1)
        if probabilities:
            probs[rows, cols] = p
    return labels, probs


def body_orientation(depth, mask, camera, forest: PartForest | None = None):
    """The person's torso axes estimated from one frame.

    Returns
    -------
    forward, up : (3,) float
        Camera-frame unit vectors: where the torso faces and its head-ward axis (NaN when
        the mask holds no reading).
    """
    depth = np.asarray(depth, np.float32)
    forest = load_forest() if forest is None else forest
    rows, cols = np.nonzero(np.asarray(mask, bool) & (depth > 0))
    if not len(rows):
        return np.full(3, np.nan), np.full(3, np.nan)
    return forest.orientation(probe_image(depth, mask), rows, cols, camera.fx, camera.fy)


@dataclass
class JointProposals:
    """Up to ``k`` proposals per contract joint, best first.

    Attributes
    ----------
    positions : (15, k, 3) float
        Camera frame, metres; NaN where a joint has fewer proposals.
    confidence : (15, k) float
        Probability-weighted surface area (m^2) of the pixels that reached the mode; 0 = none.
    """

    positions: np.ndarray
    confidence: np.ndarray

    def best(self) -> np.ndarray:
        """(15, 3) the most confident proposal per joint (NaN where none)."""
        return self.positions[:, 0].copy()


def mean_shift(points, weights, bandwidth: float, seeds: int = 40, iterations: int = 15, merge: float = 0.5):
    """Weighted Gaussian mean shift; the modes and their support.

    Parameters
    ----------
    points : (M, 3) float
    weights : (M,) float
    bandwidth : float
    seeds : int
        Starts, spread evenly over the points (every point is one when there are fewer).
    iterations : int
    merge : float
        Converged seeds closer than ``merge * bandwidth`` are one mode.

    Returns
    -------
    modes : (Q, 3) float
        Sorted by support, largest first.
    support : (Q,) float
        Summed weight of the points that belong to each mode.
    owner : (M,) int
        The mode each point belongs to (its nearest, when within two bandwidths), else -1.
    """
    x = np.asarray(points, np.float64)
    w = np.asarray(weights, np.float64)
    s = x[np.unique(np.linspace(0, len(x) - 1, min(seeds, len(x))).astype(int))].copy()
    inv = -0.5 / bandwidth ** 2
    xx = (x * x).sum(1)

    def kernel(at):
        d2 = (at * at).sum(1)[:, None] + xx[None] - 2.0 * at @ x.T
        return np.exp(np.maximum(d2, 0.0) * inv) * w[None]

    for _ in range(iterations):
        k = kernel(s)
        s_new = (k @ x) / np.maximum(k.sum(1, keepdims=True), 1e-300)
        moved = np.abs(s_new - s).max()
        s = s_new
        if moved < 1e-4:
            break
    density = kernel(s).sum(1)
    modes = []
    taken = np.zeros(len(s), bool)
    for i in np.argsort(-density):          # densest first; nearby seeds join it
        if not taken[i]:
            taken |= np.linalg.norm(s - s[i], axis=1) < merge * bandwidth
            modes.append(s[i])
    modes = np.asarray(modes)
    # each point belongs to its nearest mode when within two bandwidths of it
    d = np.linalg.norm(x[:, None, :] - modes[None], axis=2)
    owner = np.where(d.min(1) < 2 * bandwidth, d.argmin(1), -1)
    support = np.bincount(owner[owner >= 0], weights=w[owner >= 0], minlength=len(modes))
    order = np.argsort(-support, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return modes[order], support[order], np.where(owner >= 0, rank[np.maximum(owner, 0)], -1)


def joint_proposals(depth, probs, camera, k: int = 3, forest: PartForest | None = None,
                    bandwidth: float = BANDWIDTH, min_probability: float = MIN_PROBABILITY,
                    max_points: int = 200, merge_sides: bool = True) -> JointProposals:
    """3D joint proposals from the parts' probabilities (Shotton et al., section 3.4).

    Per joint, the pixels of its parts (:data:`JOINT_PARTS`) with probability above
    ``min_probability`` are back-projected and weighted by probability times surface area
    (``d^2 / (fx fy)``); weighted mean shift finds the modes, each pushed the joint's
    learned depth (``forest.push_back``) away from the camera.

    With ``merge_sides`` a left joint and its right twin share their modes: mean shift runs
    on both sides' probabilities together and each joint ranks the modes by its own side's
    weight. A depth image tells front from back only weakly, so the forest often puts the
    left elbow's pixels under ``r_elbow``; this way both elbows are among both joints'
    proposals, best-supported side first, and the caller (the tracker's likelihood) decides.

    Parameters
    ----------
    depth : (H, W) float
        Metres.
    probs : (H, W, C) float
        From :func:`recognize`.
    camera : Camera
    k : int
        Most proposals per joint.
    forest : PartForest, optional
        Gives the learned push-back per joint (default: the shipped model).
    bandwidth, min_probability : float
        Mean-shift bandwidth (m) and the least probability of a voting pixel.
    max_points : int
        Voting pixels per joint are thinned evenly to at most this many (their weights scaled up).
    merge_sides : bool

    Returns
    -------
    JointProposals
        Confidence: the summed weight (m^2) of the joint's own part at the mode.
    """
    forest = load_forest() if forest is None else forest
    depth = np.asarray(depth, np.float64)
    positions = np.full((len(JOINT_NAMES), k, 3), np.nan)
    confidence = np.zeros((len(JOINT_NAMES), k))
    valid = depth > 0
    done = set()
    for j, name in enumerate(JOINT_NAMES):
        if name in done:
            continue
        group = [name]
        if merge_sides and name[:2] in ("l_", "r_"):
            group.append(("r_" if name[:2] == "l_" else "l_") + name[2:])
        own = [probs[..., [PART_ID[c] for c in JOINT_PARTS[g]]].sum(axis=-1) for g in group]
        p = sum(own)
        done.update(group)
        rows, cols = np.nonzero(valid & (p > min_probability))
        if not len(rows):
            continue
        step = max(1, int(np.ceil(len(rows) / max_points)))
        rows, cols = rows[::step], cols[::step]
        z = depth[rows, cols]
        pts = camera.backproject(z, np.stack([cols, rows], axis=1).astype(float))
        area = camera.pixel_area(z) * step
        modes, _, owner = mean_shift(pts, p[rows, cols] * area, bandwidth)
        for g, q in zip(group, own):
            w = q[rows, cols] * area
            support = np.bincount(owner[owner >= 0], weights=w[owner >= 0], minlength=len(modes))
            order = np.argsort(-support, kind="stable")[:k]
            gi = JOINT_NAMES.index(g)
            positions[gi, :len(order)] = modes[order]
            positions[gi, :len(order), 2] += forest.push_back[gi]
            confidence[gi, :len(order)] = support[order]
    return JointProposals(positions, confidence)
