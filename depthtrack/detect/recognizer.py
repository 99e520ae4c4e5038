"""Per-pixel body-part recognition and joint proposals from one depth frame.

After Shotton et al., "Real-time human pose recognition in parts from single depth
images" (CVPR 2011): a randomized decision forest over depth-invariant depth-difference
features (:mod:`.features`) labels every person pixel with one of :data:`BODY_PARTS`
(:mod:`.recognizer_parts`); mean shift over the back-projected pixels, weighted by the
part's probability times the pixel's surface area, finds each part's modes, and each mode
pushed a learned depth behind the surface proposes a joint.

* :func:`recognize` ``(depth, mask, camera) -> (labels (H, W) int8, probs (H, W, C) float32)``
* :func:`joint_proposals` ``(depth, probs, camera, k=3) -> JointProposals`` -- up to ``k``
  3D proposals with confidences for each of the 15 contract joints.

The forest ships as ``depthtrack/data/recognizer.npz`` (``tools/train_recognizer.py``),
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
from .features import pair_features, probe_image
from .recognizer_parts import BODY_PARTS, JOINT_PARTS, PART_ID

FORMAT = "depthtrack-recognizer/1"
#: Mean-shift bandwidth (m) and the least part probability a pixel needs to vote (Shotton's b_c, lambda_c).
BANDWIDTH = 0.065
MIN_PROBABILITY = 0.14


def default_path() -> Path:
    return Path(str(resources.files("depthtrack") / "data" / "recognizer.npz"))


class PartForest:
    """A depth-difference decision forest stored as flat numpy arrays.

    Attributes
    ----------
    offsets : (K, 4) float32
        Candidate offset pairs ``u_x, u_y, v_x, v_y`` (m) the split nodes index.
    feature : (n,) int32
        Offset pair of each node (split nodes).
    threshold : (n,) float32
        A pixel goes left when its feature is ``<= threshold``.
    left : (n,) int32
        Left child, -1 for leaves.
    right : (n,) int32
        Right child; for leaves, the row of ``leaf_probs``.
    roots : (T,) int32
        Root node of each tree.
    leaf_probs : (L, C) float32
        Class distribution of each leaf.
    push_back : (15,) float32
        Metres a joint lies behind its part's surface mode (camera z).
    meta : dict
        How the forest was trained.
    """

    def __init__(self, offsets, feature, threshold, left, right, roots, leaf_probs, push_back, meta=None):
        self.offsets = np.asarray(offsets, np.float32)
        self.feature = np.asarray(feature, np.int32)
        self.threshold = np.asarray(threshold, np.float32)
        self.left = np.asarray(left, np.int32)
        self.right = np.asarray(right, np.int32)
        self.roots = np.asarray(roots, np.int32)
        self.leaf_probs = np.asarray(leaf_probs, np.float32)
        self.push_back = np.asarray(push_back, np.float32)
        self.meta = dict(meta or {})
        if self.leaf_probs.shape[1] != len(BODY_PARTS) or self.push_back.shape != (len(JOINT_NAMES),):
            raise ValueError("forest does not match BODY_PARTS / the contract joints")

    # ------------------------------------------------------------------ files
    def save(self, path) -> None:
        """Write the forest to ``path`` (.npz) atomically; leaf distributions as uint8."""
        from ..io.atomic import atomic_path

        meta = {**self.meta, "format": FORMAT, "parts": list(BODY_PARTS), "joints": list(JOINT_NAMES)}
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as fh:
                np.savez_compressed(
                    fh, offsets=self.offsets.astype(np.float16), feature=self.feature.astype(np.int16),
                    threshold=self.threshold.astype(np.float16), left=self.left, right=self.right,
                    roots=self.roots, leaf_probs=np.rint(self.leaf_probs * 255).astype(np.uint8),
                    push_back=self.push_back, meta=json.dumps(meta))

    @classmethod
    def load(cls, path) -> "PartForest":
        """Read a forest written by :meth:`save`; a one-line error for anything else."""
        try:
            with np.load(path, allow_pickle=False) as z:
                meta = json.loads(str(z["meta"]))
                if meta.get("format") != FORMAT or meta.get("parts") != list(BODY_PARTS):
                    raise InputError(path, f"not a {FORMAT} model for these body parts")
                probs = z["leaf_probs"].astype(np.float32) / 255.0
                probs /= np.maximum(probs.sum(axis=1, keepdims=True), 1e-6)
                return cls(z["offsets"], z["feature"], z["threshold"], z["left"], z["right"], z["roots"],
                           probs, z["push_back"], meta)
        except (OSError, KeyError, ValueError) as exc:
            raise InputError(path, f"cannot read the recogniser model ({exc})") from None

    # ------------------------------------------------------------------ inference
    def predict(self, image, rows, cols, fx: float, fy: float) -> np.ndarray:
        """Class probabilities of pixels, averaged over the trees.

        Parameters
        ----------
        image : (H, W) float32
            :func:`~depthtrack.detect.features.probe_image` of the frame.
        rows, cols : (N,) int
            Person pixels.
        fx, fy : float

        Returns
        -------
        (N, C) float32
        """
        n, trees = len(rows), len(self.roots)
        node = np.repeat(self.roots, n)
        r = np.tile(np.asarray(rows, np.float32), trees)
        c = np.tile(np.asarray(cols, np.float32), trees)
        d = image[np.asarray(rows), np.asarray(cols)].astype(np.float32)
        d = np.tile(d, trees)
        active = np.flatnonzero(self.left[node] >= 0)
        while active.size:         # one level of every tree per pass, only pixels not yet at a leaf
            at = node[active]
            f = pair_features(image, r[active], c[active], d[active], self.offsets[self.feature[at]], fx, fy)
            nxt = np.where(f <= self.threshold[at], self.left[at], self.right[at])
            node[active] = nxt
            active = active[self.left[nxt] >= 0]
        probs = self.leaf_probs[self.right[node]].reshape(trees, n, -1)
        return probs.mean(axis=0)


@functools.lru_cache(maxsize=4)
def _load_default(path: str) -> PartForest:
    return PartForest.load(path)


def load_forest(path=None) -> PartForest:
    """The shipped forest (cached), or the one at ``path``."""
    return _load_default(str(default_path() if path is None else Path(path)))


def recognize(depth, mask, camera, forest: PartForest | None = None, probabilities: bool = True):
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
        p = forest.predict(image, rows, cols, camera.fx, camera.fy)
        labels[rows, cols] = p.argmax(axis=1)
        if probabilities:
            probs[rows, cols] = p
    return labels, probs


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
        Summed weight of the points nearest (within the bandwidth) to each mode.
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
    # support: the weight of the points within the bandwidth of each mode, each point counted once
    d = np.linalg.norm(x[:, None, :] - modes[None], axis=2)
    near = d.argmin(1)
    support = np.bincount(near, weights=w * (d.min(1) < bandwidth * 2), minlength=len(modes))
    order = np.argsort(-support)
    return modes[order], support[order]


def joint_proposals(depth, probs, camera, k: int = 3, forest: PartForest | None = None,
                    bandwidth: float = BANDWIDTH, min_probability: float = MIN_PROBABILITY,
                    max_points: int = 200) -> JointProposals:
    """3D joint proposals from the parts' probabilities (Shotton et al., section 3.4).

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

    Returns
    -------
    JointProposals
    """
    forest = load_forest() if forest is None else forest
    depth = np.asarray(depth, np.float64)
    positions = np.full((len(JOINT_NAMES), k, 3), np.nan)
    confidence = np.zeros((len(JOINT_NAMES), k))
    valid = depth > 0
    for j, name in enumerate(JOINT_NAMES):
        p = probs[..., [PART_ID[c] for c in JOINT_PARTS[name]]].sum(axis=-1)
        rows, cols = np.nonzero(valid & (p > min_probability))
        if not len(rows):
            continue
        step = max(1, int(np.ceil(len(rows) / max_points)))
        rows, cols = rows[::step], cols[::step]
        z = depth[rows, cols]
        pts = camera.backproject(z, np.stack([cols, rows], axis=1).astype(float))
        w = p[rows, cols] * camera.pixel_area(z) * step
        modes, support = mean_shift(pts, w, bandwidth)
        q = min(k, len(modes))
        positions[j, :q] = modes[:q]
        positions[j, :q, 2] += forest.push_back[j]
        confidence[j, :q] = support[:q]
    return JointProposals(positions, confidence)
