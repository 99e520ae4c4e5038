"""The patch classifier that labels geodesic extrema as head, hand, foot or other.

Features of one extremum (:func:`extremum_features`):

* a **depth patch**: a ``PATCH_CELLS x PATCH_CELLS`` grid covering ``PATCH_SIZE`` metres
  square on the person (scale-normalised by depth: the pixel spacing is
  ``PATCH_SIZE / PATCH_CELLS * f / z``), rotated so that its first axis follows the
  extremum's direction projected into the image (the limb always points "up" the
  patch), reaching ``PATCH_LEAD`` metres beyond the extremum. Each cell holds the
  box-filtered foreground depth minus the extremum's depth, clipped to
  +-``PATCH_CLIP`` m, or ``BACKGROUND`` where the cell is off the person;
* **geometry**: the extremum's and its cap centre's height above the floor as a
  fraction of the person's height span, the direction's cosine with "up", the
  geodesic reach from the body centre (m), the cap areas (m^2), and the extremum's rank.

The model is a random forest trained by ``tools/train_part_classifier.py`` with
scikit-learn and exported to plain arrays (``depthtrack/data/part_classifier.npz``);
:class:`PartClassifier` evaluates it in numpy, so no pickles and no scikit-learn at run time.
The file also holds, per class, how far along the extremum direction the reported
position sits from the cap centre (fitted to the tracker's part centres).
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from ..errors import InputError

DEFAULT_PATH = Path(__file__).resolve().parents[1] / "data" / "part_classifier.npz"

#: Patch geometry (metres) and encoding.
PATCH_SIZE = 0.48
PATCH_CELLS = 12
PATCH_LEAD = 0.08
PATCH_CLIP = 0.30
BACKGROUND = 0.60

#: Class names in the model's output order.
CLASSES = ("head", "hand", "foot", "other")

GEOMETRY_FEATURES = ("tip_height", "centre_height", "direction_up", "reach", "cap_area_half",
                     "cap_area", "rank", "distance")
FEATURE_NAMES = tuple(f"patch_{i}_{j}" for i in range(PATCH_CELLS) for j in range(PATCH_CELLS)) \
    + GEOMETRY_FEATURES


def _box_mean(values, weights, radius):
    """Weighted box filter of an image ``(H, W)``; ``radius`` pixels either side (0 = none)."""
    if radius <= 0:
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(weights > 0, values, np.nan)
    k = 2 * radius + 1

    def box(a):
        c = np.cumsum(np.cumsum(np.pad(a, ((radius + 1, radius), (radius + 1, radius))), 0), 1)
        return c[k:, k:] - c[:-k, k:] - c[k:, :-k] + c[:-k, :-k]

    w = box(weights)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(w > 0, box(values * weights) / w, np.nan)


def up_and_heights(foreground, points):
    """Heights of ``points (n, 3)`` as fractions of the person's height span, and the up vector.

    Height is measured along the floor normal from the floor (camera -y from the
    person's lowest point when there is no floor), divided by the person's top height.

    Returns
    -------
    heights : (n,) float
    up : (3,) float
    """
    plane = getattr(foreground, "floor_plane", None)
    fg_points = np.asarray(foreground.points, float)
    if plane is not None:
        plane = np.asarray(plane, float)
        norm = np.linalg.norm(plane[:3])
        up, offset = plane[:3] / norm, plane[3] / norm
        base = -offset
    else:
        up = np.array([0.0, -1.0, 0.0])
        base = float(np.percentile(fg_points @ up, 1)) if len(fg_points) else 0.0
    top = float(np.percentile(fg_points @ up, 99)) - base if len(fg_points) else 1.0
    return (np.asarray(points, float) @ up - base) / max(top, 0.3), up


def extremum_features(depth, camera, extrema, foreground) -> np.ndarray:
    """Feature vectors of geodesic extrema (see the module docstring).

    Parameters
    ----------
    depth : (H, W) float
        Camera z, metres (0 = no reading).
    camera : Camera
    extrema : Extrema
    foreground : Foreground

    Returns
    -------
    (K, len(FEATURE_NAMES)) float32
    """
    K = len(extrema)
    out = np.zeros((K, len(FEATURE_NAMES)), np.float32)
    if K == 0:
        return out
    z = np.asarray(depth, float)
    mask = np.asarray(foreground.mask, bool)
    tips = np.asarray(extrema.positions, float)
    dirs = np.asarray(extrema.directions, float)
    zt = tips[:, 2]
    cell = PATCH_SIZE / PATCH_CELLS
    # one smoothing radius for the frame: about a cell at the median extremum depth
    radius = int(max(0, round(0.5 * cell * camera.fx / float(np.median(zt)) - 0.5)))
    smooth = _box_mean(np.where(mask, z, 0.0), mask.astype(float), radius)
    # image-plane axes of each patch: "along" follows the projected direction
    uv_tip = camera.project(tips)
    uv_ahead = camera.project(tips + 0.1 * dirs)
    along = uv_ahead - uv_tip
    n = np.linalg.norm(along, axis=1, keepdims=True)
    fallback = np.tile([0.0, -1.0], (K, 1))               # image up when the limb points at the camera
    along = np.where((n > 1e-6) & np.isfinite(n), along / np.where(n > 1e-6, n, 1.0), fallback)
    across = np.stack([-along[:, 1], along[:, 0]], axis=1)
    step = cell * camera.fx / zt                           # (K,) pixels per cell
    offsets = (np.arange(PATCH_CELLS) - (PATCH_CELLS - 1) / 2.0) * 1.0
    # patch rows run from PATCH_LEAD beyond the tip back along the limb
    centre = uv_tip + along * ((PATCH_LEAD - PATCH_SIZE / 2) * camera.fx / zt)[:, None]
    grid_a, grid_b = np.meshgrid(offsets[::-1], offsets, indexing="ij")   # row 0 = ahead of the tip
    uv = centre[:, None, None, :] + step[:, None, None, None] * (
        grid_a[None, ..., None] * along[:, None, None, :] + grid_b[None, ..., None] * across[:, None, None, :])
    u = np.rint(uv[..., 0]).astype(int)
    v = np.rint(uv[..., 1]).astype(int)
    inside = (u >= 0) & (u < camera.width) & (v >= 0) & (v < camera.height)
    sample = np.full(u.shape, np.nan)
    sample[inside] = smooth[v[inside], u[inside]]
    rel = np.clip(sample - zt[:, None, None], -PATCH_CLIP, PATCH_CLIP)
    rel = np.where(np.isfinite(sample), rel, BACKGROUND)
    out[:, :PATCH_CELLS * PATCH_CELLS] = rel.reshape(K, -1)
    heights, up = up_and_heights(foreground, np.vstack([tips, extrema.centres]))
    g = out[:, PATCH_CELLS * PATCH_CELLS:]
    g[:, 0] = heights[:K]
    g[:, 1] = heights[K:]
    g[:, 2] = dirs @ up
    g[:, 3] = extrema.reach
    g[:, 4] = extrema.cap_areas[:, 0]
    g[:, 5] = extrema.cap_areas[:, 1]
    g[:, 6] = np.arange(K)
    g[:, 7] = extrema.distances
    return out


class PartClassifier:
    """A random forest over :func:`extremum_features`, evaluated in numpy.

    Parameters
    ----------
    feature : (T, N) int
        Split feature per tree node (-1 at leaves).
    threshold : (T, N) float
        Go left when ``x[feature] <= threshold``.
    left, right : (T, N) int
        Child node indices (-1 at leaves).
    value : (T, N, C) float
        Class probabilities at each node (used at leaves).
    depth : int
        Largest tree depth (number of descent steps).
    position_offset : (C,) float
        Metres along the extremum direction from the cap centre to the reported position.
    classes : tuple of str
    """

    def __init__(self, feature, threshold, left, right, value, depth, position_offset=None,
                 classes=CLASSES, meta=None):
        self.feature = np.asarray(feature, np.int32)
        self.threshold = np.asarray(threshold, np.float64)
        self.left = np.asarray(left, np.int32)
        self.right = np.asarray(right, np.int32)
        self.value = np.asarray(value, np.float32)
        self.depth = int(depth)
        self.classes = tuple(classes)
        C = len(self.classes)
        self.position_offset = (np.zeros(C) if position_offset is None
                                else np.asarray(position_offset, float))
        self.meta = dict(meta or {})

    # ------------------------------------------------------------------ evaluation
    def predict_proba(self, X) -> np.ndarray:
        """Class probabilities ``(n, C)`` of feature rows ``X (n, F)`` (mean over trees)."""
        X = np.asarray(X, np.float32)
        n = len(X)
        T = len(self.feature)
        node = np.zeros((n, T), np.int64)
        trees = np.arange(T)[None, :]
        rows = np.arange(n)[:, None]
        for _ in range(self.depth):
            f = self.feature[trees, node]
            leaf = f < 0
            x = X[rows, np.where(leaf, 0, f)]
            go_left = x <= self.threshold[trees, node]
            child = np.where(go_left, self.left[trees, node], self.right[trees, node])
            node = np.where(leaf, node, child)
        return self.value[trees, node].mean(axis=1)

    def classify(self, depth, camera, extrema, foreground):
        """Labels, probabilities and positions of extrema.

        Returns
        -------
        labels : (K,) str
        scores : (K,) float
            Probability of the chosen class.
        positions : (K, 3) float
            Cap centre moved ``position_offset[class]`` along the extremum direction.
        """
        X = extremum_features(depth, camera, extrema, foreground)
        if len(X) == 0:
            return np.zeros(0, object), np.zeros(0), np.zeros((0, 3))
        p = self.predict_proba(X)
        k = np.argmax(p, axis=1)
        labels = np.array(self.classes, dtype=object)[k]
        positions = extrema.centres + self.position_offset[k][:, None] * extrema.directions
        return labels, p[np.arange(len(k)), k], positions

    # ------------------------------------------------------------------ files
    def save(self, path) -> None:
        """Write the arrays to ``path`` (.npz, compressed, atomically)."""
        import json

        from ..io.atomic import atomic_path

        with atomic_path(path) as tmp:
            with open(tmp, "wb") as fh:
                small = self.feature.max() < np.iinfo(np.int16).max
                np.savez_compressed(fh, feature=self.feature.astype(np.int16 if small else np.int32),
                                    threshold=self.threshold, left=self.left, right=self.right,
                                    value=self.value.astype(np.float16), depth=np.array(self.depth),
                                    position_offset=self.position_offset, classes=np.array(self.classes),
                                    feature_names=np.array(FEATURE_NAMES),
                                    meta=np.array(json.dumps(self.meta)))

    @classmethod
    def load(cls, path) -> "PartClassifier":
        """Read a classifier written by :meth:`save`; InputError when it does not fit this version."""
        import json

        try:
            with np.load(path, allow_pickle=False) as data:
                names = tuple(str(s) for s in data["feature_names"])
                if names != FEATURE_NAMES:
                    raise InputError(path, "part classifier was trained on other features; "
                                           "re-run tools/train_part_classifier.py")
                return cls(data["feature"], data["threshold"], data["left"], data["right"],
                           data["value"].astype(np.float32), int(data["depth"]), data["position_offset"],
                           tuple(str(s) for s in data["classes"]), json.loads(str(data["meta"])))
        except (OSError, KeyError, ValueError) as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(path, f"cannot read part classifier ({exc})") from None

    @classmethod
    def from_sklearn(cls, forest, position_offset=None, meta=None) -> "PartClassifier":
        """Export a fitted ``sklearn.ensemble.RandomForestClassifier`` (classes 0..C-1)."""
        trees = [est.tree_ for est in forest.estimators_]
        N = max(t.node_count for t in trees)
        T = len(trees)
        C = forest.n_classes_
        feature = np.full((T, N), -1, np.int32)
        threshold = np.zeros((T, N), np.float64)
        left = np.full((T, N), -1, np.int32)
        right = np.full((T, N), -1, np.int32)
        value = np.zeros((T, N, C), np.float32)
        for i, t in enumerate(trees):
            n = t.node_count
            leaf = t.children_left[:n] < 0
            feature[i, :n] = np.where(leaf, -1, t.feature[:n])
            threshold[i, :n] = t.threshold[:n]
            left[i, :n] = t.children_left[:n]
            right[i, :n] = t.children_right[:n]
            v = t.value[:n, 0, :]
            value[i, :n] = v / np.maximum(v.sum(axis=1, keepdims=True), 1e-12)
        depth = max(est.get_depth() for est in forest.estimators_)
        return cls(feature, threshold, left, right, value, depth, position_offset,
                   classes=CLASSES[:C], meta=meta)


@lru_cache(maxsize=1)
def _load_default(path: str):
    return PartClassifier.load(path)


def default_classifier():
    """The shipped classifier (``depthtrack/data/part_classifier.npz``), or None when none ships."""
    if not DEFAULT_PATH.is_file():
        return None
    return _load_default(str(DEFAULT_PATH))
