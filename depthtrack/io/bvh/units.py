"""BVH length units: given by name or number, or inferred from the skeleton and reported."""
from __future__ import annotations

import math

import numpy as np

from ...errors import InputError
from .names import CONVENTION_UNITS, detect_convention, map_joints

#: Metres per file unit for the unit names ``read_bvh(units=...)`` accepts.
UNIT_NAMES = {
    "m": 1.0,
    "cm": 0.01,
    "mm": 0.001,
    "inch": 0.0254,
    "in": 0.0254,
    "cmu": 0.0254 / 0.45,
}

#: Typical standing height of an adult, used only to infer units.
_TYPICAL_HEIGHT_M = 1.7
#: Hip-to-ankle length of a typical adult (0.245 H per segment, two segments), ~0.83 m.
_TYPICAL_LEG_M = 0.245 * _TYPICAL_HEIGHT_M * 2.0
#: A leg this long in the convention's own unit confirms that unit.
_PLAUSIBLE_LEG_M = (0.55, 1.25)


def infer_units(rest_positions, end_positions, names, parents, end_site_parents, joint_map=None):
    """Metres per unit from the skeleton's size; returns ``(units_m, text)``.

    Parameters
    ----------
    rest_positions : (J, 3) float
        Joint positions with every channel zero, file units.
    end_positions : (E, 3) float
    names, parents, end_site_parents, joint_map
        As for :func:`depthtrack.io.bvh.names.map_joints`.

    The leg length (hip to knee to ankle; it does not depend on the rest pose of the
    arms) decides: the naming convention's own unit when the leg is of adult length in
    it (cgspeed MotionBuilder and 3dsMax files: CMU units, Daz and Reallusion files:
    centimetres), otherwise the unit that makes the leg nearest 0.83 m. Without legs,
    the skeleton's extent along its longest axis against 1.7 m.
    """
    pts = np.concatenate([rest_positions, end_positions]) if len(end_positions) else rest_positions
    convention = detect_convention(names)
    try:
        mapping = map_joints(names, parents, end_site_parents, joint_map)
    except InputError:
        mapping = None
    if mapping is not None:
        chain = [mapping[k][1] for k in ("l_hip", "l_knee", "l_ankle")]
        size = (np.linalg.norm(rest_positions[chain[1]] - rest_positions[chain[0]])
                + np.linalg.norm(rest_positions[chain[2]] - rest_positions[chain[1]]))
        what, typical = "leg (hip to ankle)", _TYPICAL_LEG_M
    else:
        size = float(np.max(pts.max(axis=0) - pts.min(axis=0)))
        what, typical = "rest-pose extent", _TYPICAL_HEIGHT_M
    if not size > 0:
        raise InputError(None, "cannot infer BVH units: the skeleton has zero size; give units")
    own = CONVENTION_UNITS.get(convention)
    if mapping is not None and own is not None and \
            _PLAUSIBLE_LEG_M[0] <= size * UNIT_NAMES[own] <= _PLAUSIBLE_LEG_M[1]:
        best, why = own, f"the unit of {convention} files"
    else:
        candidates = ("m", "cm", "mm", "inch", "cmu")
        errors = [abs(math.log(size * UNIT_NAMES[c] / typical)) for c in candidates]
        best, why = candidates[int(np.argmin(errors))], "the nearest to an adult's"
    units = UNIT_NAMES[best]
    text = (f"inferred from the skeleton's size: {what} is {size:.4g} units, which as "
            f"'{best}' ({units:.6g} m/unit) is {size * units:.3f} m ({why}; {convention} names)")
    return units, text


def resolve_units(units, path):
    """``(units_m, text)`` for a unit the caller gave: a name in :data:`UNIT_NAMES` or metres per unit."""
    if isinstance(units, str):
        key = units.strip().lower()
        if key in UNIT_NAMES:
            return UNIT_NAMES[key], f"given: '{key}' ({UNIT_NAMES[key]:.6g} m/unit)"
        try:
            value = float(key)
        except ValueError:
            raise InputError(path, f"unknown BVH units {units!r}; use metres per unit or one of "
                                   f"{', '.join(sorted(UNIT_NAMES))}") from None
    else:
        value = float(units)
    if not (math.isfinite(value) and 1e-6 <= value <= 100):
        raise InputError(path, f"BVH units must be a positive number of metres per unit (1e-06 to 100), not {units!r}")
    return value, f"given: {value:.6g} m/unit"
