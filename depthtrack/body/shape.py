"""Body shape beyond height: relative segment lengths, breadths and girths.

A :class:`BodyShape` holds eleven relative scales (1 = the default body's proportions):

=================  ==========================================================  ===========
field              what it scales                                              range
=================  ==========================================================  ===========
``upper_arm``      shoulder to elbow (both arms)                               0.88 - 1.12
``forearm``        elbow to wrist                                              0.88 - 1.12
``thigh``          hip to knee                                                 0.88 - 1.12
``shin``           knee to ankle                                               0.88 - 1.12
``torso``          vertical extent of the trunk (hips to shoulders and neck)   0.88 - 1.12
``neck_head``      neck joint to the head (centre and crown)                   0.88 - 1.12
``shoulder_width`` distance between the shoulder joints (and chest breadth)    0.86 - 1.14
``hip_width``      distance between the hip joints (and pelvis breadth)        0.85 - 1.18
``foot``           foot length                                                 0.88 - 1.12
``limb_girth``     arm and leg cross-sections about the bone axis              0.80 - 1.30
``torso_girth``    trunk cross-section (breadth and depth)                     0.82 - 1.35
=================  ==========================================================  ===========

Sources of the ranges. The default body follows the segment-length ratios of D. A. Winter,
*Biomechanics and Motor Control of Human Movement* (4th ed., 2009, fig. 4.1), see
:mod:`depthtrack.body.anthropometry`. How far people stray from those ratios is taken from
the adult body-dimension tables of ANSUR II (Gordon et al., *2012 Anthropometric Survey of
U.S. Army Personnel*, 2014) and NASA-STD-3000 (*Man-Systems Integration Standards*, vol. I,
sec. 3.2): segment lengths vary with a coefficient of variation of about 4.5-5.5 % and
correlate with stature at r = 0.7-0.85, so *relative to stature* they vary by about 3-4 %
(s.d.); shoulder (biacromial) breadth about 4.5 %, hip breadth about 6 %; circumferences
(chest, waist, thigh, upper arm) 8-12 %. The ranges above are about +-3 s.d. of those ratios
(rounded), and :data:`LOG_SD` holds the s.d. used by :func:`random_shape`.

Every field is a *relative* scale: a body built with ``BodyModel.default(height=H,
shape=S)`` is rescaled as a whole afterwards so that its standing height is still ``H``.

How a shape deforms the skinned body (:func:`surface_maps`): every joint ``j`` gets a
linear map ``L_j (3, 3)`` of the model frame about the joint, applied to the surface it
moves (in the skin matrices ``world @ scale @ L @ inverse_bind``, so the renderer and
:meth:`BodyModel.posed_vertices` follow without a new vertex buffer), and every bone is
moved the same way: ``offset_c = L_parent(c) @ base_offset_c``, so a joint stays where the
surface around it went. A limb joint's map stretches along its bone and scales the
cross-section (``girth``) about the bone axis: ``L = f d d^T + g (I - d d^T)``. The pelvis
and spine maps are axis-aligned: ``diag(width * torso_girth, torso, torso_girth)``. The
neck stretches along the neck-to-head direction, the ankle along the foot (model -z).
Hands keep their size.
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import numpy as np

from ..contract import JOINT_NAMES
from ..errors import InputError
from .mesh import linear_blend_skinning
from .skeleton import DOF, JOINT_ID, NUM_JOINTS, PARENTS, forward_kinematics

#: Shape fields in a fixed order (the parameter vector of :meth:`BodyShape.as_array`).
SHAPE_FIELDS = ("upper_arm", "forearm", "thigh", "shin", "torso", "neck_head", "shoulder_width",
                "hip_width", "foot", "limb_girth", "torso_girth")
#: Length fields (the rest are girths).
LENGTH_FIELDS = SHAPE_FIELDS[:9]
#: Documented plausible range of every field (module docstring).
SHAPE_RANGES = {
    "upper_arm": (0.88, 1.12), "forearm": (0.88, 1.12), "thigh": (0.88, 1.12),
    "shin": (0.88, 1.12), "torso": (0.88, 1.12), "neck_head": (0.88, 1.12),
    "shoulder_width": (0.86, 1.14), "hip_width": (0.85, 1.18), "foot": (0.88, 1.12),
    "limb_girth": (0.80, 1.30), "torso_girth": (0.82, 1.35),
}
#: Standard deviation of the log of each field across adults (ratios to stature; sources
#: in the module docstring).
LOG_SD = np.array([0.035, 0.035, 0.035, 0.035, 0.03, 0.035, 0.045, 0.055, 0.035, 0.08, 0.10])
#: Standing height of :func:`random_person`: log-normal about 1.72 m (men and women pooled),
#: clipped to this range (metres).
HEIGHT_RANGE = (1.50, 2.00)
HEIGHT_LOG_MEAN, HEIGHT_LOG_SD = np.log(1.72), 0.055


def _correlation() -> np.ndarray:
    """Correlation of the log fields (in :data:`SHAPE_FIELDS` order), stature held fixed.

    Limb lengths go together (long-limbed people: r = 0.5 among the limb segments and
    foot), and against the torso (at a given stature, long legs mean a short trunk:
    r = -0.35, the sitting-height ratio); the two breadths correlate (0.4) and go with the
    girths (0.3); limb and trunk girth correlate strongly (0.7: body mass shows in both).
    """
    n = len(SHAPE_FIELDS)
    C = np.eye(n)
    idx = {f: i for i, f in enumerate(SHAPE_FIELDS)}

    def put(a, b, r):
        C[idx[a], idx[b]] = C[idx[b], idx[a]] = r

    limbs = ("upper_arm", "forearm", "thigh", "shin", "foot")
    for i, a in enumerate(limbs):
        for b in limbs[i + 1:]:
            put(a, b, 0.5)
        put(a, "torso", -0.35)
    put("shoulder_width", "hip_width", 0.4)
    for w in ("shoulder_width", "hip_width"):
        for g in ("limb_girth", "torso_girth"):
            put(w, g, 0.3)
    put("limb_girth", "torso_girth", 0.7)
    return C


#: Correlation matrix of :func:`random_shape` (positive definite; see :func:`_correlation`).
SHAPE_CORRELATION = _correlation()


def read_json_source(source, what: str):
    """JSON from a file path, from JSON text or an already parsed dict.

    Returns
    -------
    (data, path) : the parsed value and the file's Path (None for text or a dict).

    Raises
    ------
    InputError
        An unreadable file or invalid JSON, naming the file.
    """
    if isinstance(source, dict):
        return source, None
    path, text = None, source
    if isinstance(source, Path) or (isinstance(source, str) and not source.lstrip().startswith("{")):
        path = Path(source)
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise InputError(path, f"cannot read {what}: {getattr(exc, 'strerror', None) or exc}") from None
    try:
        return json.loads(text), path
    except json.JSONDecodeError as exc:
        raise InputError(path, f"not valid JSON: {exc.msg} (line {exc.lineno})") from None


@dataclass(frozen=True)
class BodyShape:
    """Relative body proportions (1 = the default body); fields and ranges in the module docstring."""

    upper_arm: float = 1.0
    forearm: float = 1.0
    thigh: float = 1.0
    shin: float = 1.0
    torso: float = 1.0
    neck_head: float = 1.0
    shoulder_width: float = 1.0
    hip_width: float = 1.0
    foot: float = 1.0
    limb_girth: float = 1.0
    torso_girth: float = 1.0

    def __post_init__(self):
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) \
                    or not np.isfinite(v) or v <= 0:
                raise ValueError(f"shape field {f.name!r} must be a positive number, got {v!r}")
            object.__setattr__(self, f.name, float(v))

    # ------------------------------------------------------------------ conversions
    def as_array(self) -> np.ndarray:
        """``(11,)`` float64 in :data:`SHAPE_FIELDS` order."""
        return np.array([getattr(self, f) for f in SHAPE_FIELDS])

    @classmethod
    def from_array(cls, values) -> "BodyShape":
        values = np.asarray(values, dtype=np.float64).reshape(-1)
        if len(values) != len(SHAPE_FIELDS):
            raise ValueError(f"a shape vector has {len(SHAPE_FIELDS)} values, got {len(values)}")
        return cls(**dict(zip(SHAPE_FIELDS, values.tolist())))

    @property
    def is_average(self) -> bool:
        return bool(np.allclose(self.as_array(), 1.0, atol=1e-12))

    def clipped(self) -> "BodyShape":
        """The shape with every field clipped to :data:`SHAPE_RANGES`."""
        lo = np.array([SHAPE_RANGES[f][0] for f in SHAPE_FIELDS])
        hi = np.array([SHAPE_RANGES[f][1] for f in SHAPE_FIELDS])
        return BodyShape.from_array(np.clip(self.as_array(), lo, hi))

    def out_of_range(self) -> list:
        """Names of the fields outside :data:`SHAPE_RANGES`."""
        return [f for f in SHAPE_FIELDS
                if not SHAPE_RANGES[f][0] - 1e-9 <= getattr(self, f) <= SHAPE_RANGES[f][1] + 1e-9]

    def to_dict(self) -> dict:
        return {k: float(v) for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, data, path=None) -> "BodyShape":
        """From a dict of (some of) the fields; missing fields are 1. Raises InputError."""
        if not isinstance(data, dict):
            raise InputError(path, "a body shape must be a JSON object of relative scales")
        unknown = sorted(set(data) - set(SHAPE_FIELDS))
        if unknown:
            raise InputError(path, f"unknown body shape field(s) {', '.join(unknown)}; "
                                   f"known: {', '.join(SHAPE_FIELDS)}")
        try:
            return cls(**data)
        except (TypeError, ValueError) as exc:
            raise InputError(path, str(exc)) from None

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=1) + "\n"

    @classmethod
    def from_json(cls, source) -> "BodyShape":
        """From JSON text or a file path: the fields, or an object with a ``shape`` block
        (a track's ``body.json``, or a sequence's ``synth`` block)."""
        data, path = read_json_source(source, "body shape")
        if isinstance(data, dict) and isinstance(data.get("shape"), dict):
            data = data["shape"]
        return cls.from_dict(data, path)


AVERAGE = BodyShape()


# ---------------------------------------------------------------------- sampling
def random_shape(rng) -> BodyShape:
    """A plausible adult's proportions: log fields ~ N(0, diag(LOG_SD) C diag(LOG_SD)),
    C = :data:`SHAPE_CORRELATION`, each clipped to :data:`SHAPE_RANGES`."""
    cov = SHAPE_CORRELATION * np.outer(LOG_SD, LOG_SD)
    z = rng.multivariate_normal(np.zeros(len(SHAPE_FIELDS)), cov, method="cholesky")
    return BodyShape.from_array(np.exp(z)).clipped()


def random_person(seed: int):
    """``(height_m, BodyShape)`` of a plausible adult drawn with ``numpy.random.default_rng(seed)``.

    Height log-normal (:data:`HEIGHT_LOG_MEAN`, :data:`HEIGHT_LOG_SD`) clipped to
    :data:`HEIGHT_RANGE`; taller people are built a little broader (girths scale with
    height^0.5 relative to the mean, the allometry of body mass ~ height^2.5 at constant
    proportions would give more; measured populations show less).
    """
    rng = np.random.default_rng(int(seed))
    height = float(np.clip(np.exp(rng.normal(HEIGHT_LOG_MEAN, HEIGHT_LOG_SD)), *HEIGHT_RANGE))
    shape = random_shape(rng)
    girth = (height / np.exp(HEIGHT_LOG_MEAN)) ** 0.5
    values = shape.as_array()
    values[SHAPE_FIELDS.index("limb_girth")] *= girth
    values[SHAPE_FIELDS.index("torso_girth")] *= girth
    return round(height, 4), BodyShape.from_array(values).clipped()


# ---------------------------------------------------------------------- deformation
def _axis_map(direction, along: float, across: float) -> np.ndarray:
    n = np.linalg.norm(direction)
    if n == 0:
        return np.eye(3) * across
    d = np.asarray(direction, float) / n
    dd = np.outer(d, d)
    return along * dd + across * (np.eye(3) - dd)


def surface_maps(shape: BodyShape, base_offsets, base_head_offset) -> np.ndarray:
    """Per-joint linear maps ``L (J, 3, 3)`` of the model frame (module docstring).

    Parameters
    ----------
    shape : BodyShape
    base_offsets : (J, 3) float
        Bone offsets of the unshaped skeleton (model frame = rest frames).
    base_head_offset : (3,) float
        Head centre in the neck's frame.
    """
    s = shape
    J = JOINT_ID
    off = np.asarray(base_offsets, float)
    L = np.tile(np.eye(3), (NUM_JOINTS, 1, 1))
    L[J["pelvis"]] = np.diag([s.hip_width * s.torso_girth, s.torso, s.torso_girth])
    L[J["spine"]] = np.diag([s.shoulder_width * s.torso_girth, s.torso, s.torso_girth])
    L[J["neck"]] = _axis_map(base_head_offset, s.neck_head, 1.0)
    for side in ("l", "r"):
        L[J[f"{side}_shoulder"]] = _axis_map(off[J[f"{side}_elbow"]], s.upper_arm, s.limb_girth)
        L[J[f"{side}_elbow"]] = _axis_map(off[J[f"{side}_wrist"]], s.forearm, s.limb_girth)
        L[J[f"{side}_hip"]] = _axis_map(off[J[f"{side}_knee"]], s.thigh, s.limb_girth)
        L[J[f"{side}_knee"]] = _axis_map(off[J[f"{side}_ankle"]], s.shin, s.limb_girth)
        L[J[f"{side}_ankle"]] = _axis_map([0.0, 0.0, -1.0], s.foot, 1.0)
    return L


def shaped_offsets(maps, base_offsets, base_head_offset, parents):
    """Bone offsets ``(J, 3)`` and head offset ``(3,)`` moved by the parents' maps:
    ``offset_c = L_parent(c) @ base_offset_c`` (the head by the neck's map)."""
    off = np.asarray(base_offsets, float).copy()
    for c, p in enumerate(parents):
        if p >= 0:
            off[c] = maps[p] @ off[c]
    head = maps[JOINT_ID["neck"]] @ np.asarray(base_head_offset, float)
    return off, head


# ---------------------------------------------------------------------- measurements
def segment_lengths(body) -> dict:
    """The body's segment lengths in metres (means of left and right), at the zero pose.

    ``upper_arm, forearm, thigh, shin``: joint to joint; ``torso``: hip centre to shoulder
    centre; ``neck_head``: neck joint to head centre; ``shoulder_width``, ``hip_width``:
    between the joints; ``foot``: extent along the foot (model z) of the surface the ankle
    moves (dominant skin weight), on the body's reference mesh.
    """
    p = np.asarray(body.joint_positions(np.zeros(DOF)))
    q = {n: p[i] for i, n in enumerate(JOINT_NAMES)}

    def both(a, b):
        return 0.5 * (np.linalg.norm(q[f"l_{a}"] - q[f"l_{b}"]) + np.linalg.norm(q[f"r_{a}"] - q[f"r_{b}"]))

    hips = 0.5 * (q["l_hip"] + q["r_hip"])
    shoulders = 0.5 * (q["l_shoulder"] + q["r_shoulder"])
    out = {
        "upper_arm": both("elbow", "shoulder"), "forearm": both("wrist", "elbow"),
        "thigh": both("knee", "hip"), "shin": both("ankle", "knee"),
        "torso": float(np.linalg.norm(shoulders - hips)),
        "neck_head": float(np.linalg.norm(q["head"] - q["neck"])),
        "shoulder_width": float(np.linalg.norm(q["l_shoulder"] - q["r_shoulder"])),
        "hip_width": float(np.linalg.norm(q["l_hip"] - q["r_hip"])),
        "foot": foot_length(body),
    }
    return {k: round(float(v), 5) for k, v in out.items()}


def foot_length(body) -> float:
    """Length (m) of the feet at the zero pose: z extent of the vertices whose dominant joint
    is an ankle, mean of both feet, on the body's reference mesh."""
    m = body.reference_mesh
    skin = forward_kinematics(np.zeros((1, DOF)), body.offsets, PARENTS) @ (body.bone_scale @ m.inverse_bind)
    v = linear_blend_skinning(m.vertices, m.joints, m.weights, skin)[0]
    dom = m.dominant_joint()
    out = []
    for side in ("l", "r"):
        z = v[dom == JOINT_ID[f"{side}_ankle"], 2]
        out.append(np.ptp(z) if len(z) else np.nan)
    return float(np.nanmean(out))


def length_errors(fitted: dict, truth: dict) -> dict:
    """``{segment: fitted - truth}`` (m) for the segments both know."""
    return {k: round(float(fitted[k]) - float(truth[k]), 5) for k in LENGTH_FIELDS
            if k in fitted and k in truth and fitted[k] is not None and truth[k] is not None}


__all__ = ["BodyShape", "AVERAGE", "SHAPE_FIELDS", "LENGTH_FIELDS", "SHAPE_RANGES", "LOG_SD",
           "SHAPE_CORRELATION", "HEIGHT_RANGE", "random_shape", "random_person", "surface_maps",
           "shaped_offsets", "segment_lengths", "foot_length", "length_errors"]
