"""Which BVH joint is which: the 15 contract joints found in any common naming convention.

Conventions recognised (:func:`detect_convention` names them in reports):

======================  ==================================================================
CMU cgspeed MotionBuilder  ``Hips LHipJoint LeftUpLeg LeftLeg LeftFoot ... LeftShoulder``
                        (clavicle) ``LeftArm LeftForeArm LeftHand Neck Neck1 Head``
CMU cgspeed 3dsMax      ``LeftHip LeftKnee LeftAnkle ... LeftCollar LeftShoulder`` (upper
                        arm) ``LeftElbow LeftWrist lowerneck Neck Head``
CMU cgspeed Daz         ``hip abdomen chest neck head lThigh lShin lFoot lCollar lShldr
                        lForeArm lHand`` (per-joint rotation orders, eyes on the head)
Reallusion CC           ``CC_Base_Hip CC_Base_L_Thigh CC_Base_L_Calf CC_Base_L_Foot
                        CC_Base_L_Upperarm CC_Base_L_Forearm CC_Base_L_Hand CC_Base_Head``
Mixamo                  MotionBuilder names behind a ``mixamorig:`` namespace
DeepMimic               ``Hips Spine1 Neck1 LeftUpLeg ...`` (head centre = neck end site)
SMPL                    ``pelvis left_hip left_knee left_ankle left_shoulder left_elbow
                        left_wrist neck head`` (or ``L_Hip``, ``L_Knee`` ...)
Xsens MVN               ``Pelvis L5 T8 Neck Head LeftUpperLeg LeftLowerLeg LeftFoot
                        LeftShoulder LeftUpperArm LeftForeArm LeftHand``
Rokoko, Perception Neuron  MotionBuilder-like (``LeftThigh``/``LeftShin`` also accepted)
Blender Rigify          ``DEF-``/``ORG-`` bones: ``thigh.L shin.L foot.L upper_arm.L
                        forearm.L hand.L spine.004`` (neck) ``spine.006`` (head)
======================  ==================================================================

How a name is read: any ``namespace:`` and a known prefix (``CC_Base_``, ``DEF-``,
``ORG-``, ``Bip01``) are dropped, the side is taken from a ``Left``/``Right`` word, an
``l``/``r`` before a capital (``lThigh``), an ``L_``/``l_`` prefix or a ``.L``/``_l``
suffix, and what remains, lower-cased without separators, is the *base* (``upleg``,
``knee``, ``forearm`` ...).

Names alone are ambiguous (``LeftShoulder`` is the clavicle in MotionBuilder files and
the upper arm in 3dsMax files; ``foot`` is the ankle in most files and the toes in SMPL;
``hand`` the wrist or the fingers), so the limbs are found from the skeleton's
structure: first the unambiguous middle joint of each limb (elbow: ``ForeArm``,
``Elbow``, ``LowerArm``; knee: ``Leg``, ``Knee``, ``Shin``, ``Calf``, ``LowerLeg``),
then the upper joint as the nearest *ancestor* of it with an upper-limb name (so a
``LeftShoulder`` that is the elbow's parent is the upper arm, and one above a
``LeftArm`` is the clavicle), and the lower joint as a *descendant* with a wrist or
ankle name (``Wrist``/``Ankle`` before ``Hand``/``Foot``). The pelvis is the lowest
common ancestor of both hips and the neck.

Anything else: a joint map ``{our joint name: file joint name}`` (``--joint-map
FILE.json``) names some or all joints; the rest are found as above.
"""
from __future__ import annotations

import json
import re
from pathlib import Path

from ...contract import JOINT_NAMES
from ...errors import InputError

#: Bases (see the module docstring) for each part of a limb, in order of preference.
KNEE = ("leg", "knee", "shin", "calf", "lowerleg", "lowleg", "tibia")
THIGH = ("upleg", "upperleg", "thigh", "hip", "femur")
ANKLE = ("ankle", "foot")
ELBOW = ("forearm", "elbow", "lowerarm", "lowarm", "radius")
UPPER_ARM = ("arm", "upperarm", "uparm", "shldr", "shoulder", "humerus")
WRIST = ("wrist", "hand")
HEAD = ("head", "spine006")
#: The contract neck sits at shoulder level: CMU's ``Neck1`` (its ``Neck`` is the base of
#: the neck on the chest), 3dsMax's ``Neck`` (over ``lowerneck``), Rigify's ``spine.004``.
NECK = ("neck1", "upperneck", "neck", "necktwist01", "neck01", "spine004", "lowerneck")
HEAD_TOP = ("headtopend", "headtop", "headend", "headnub", "headsite")
EYE = ("eye",)

_PREFIXES = re.compile(r"^(cc_base_|def[-_]|org[-_]|mch[-_]|bip0*1[\s_]|mixamorig\d*_)", re.IGNORECASE)
_SIDE_PATTERNS = (
    re.compile(r"^(left|right)[\s_.-]?(.+)$", re.IGNORECASE),
    re.compile(r"^(.+?)[\s_.-]?(left|right)$", re.IGNORECASE),
    re.compile(r"^([lr])[\s_.-](.+)$", re.IGNORECASE),
    re.compile(r"^(.+)[\s_.-]([lr])$", re.IGNORECASE),
    re.compile(r"^(.+)[\s_.-]([lr])([._]\d+)$", re.IGNORECASE),
    re.compile(r"^([lLrR])([A-Z].*)$"),
)
#: Joints a refusal asks for, per contract joint (what a user can name in a joint map);
#: ``{S}`` is Left or Right, ``{s}`` l or r.
_NEEDS = {
    "pelvis": "Hips/hip/pelvis (the joint above both hips and the neck)", "neck": "Neck1/Neck",
    "head": "Head", "shoulder": "{S}Arm/{S}Shoulder/{s}Shldr/{S}UpperArm above the elbow",
    "elbow": "{S}ForeArm/{S}Elbow/{S}LowerArm", "wrist": "{S}Hand/{S}Wrist below the elbow",
    "hip": "{S}UpLeg/{S}Hip/{s}Thigh above the knee", "knee": "{S}Leg/{S}Knee/{s}Shin/{S}Calf",
    "ankle": "{S}Foot/{S}Ankle below the knee",
}


def _needs(joint: str) -> str:
    if joint[:2] in ("l_", "r_"):
        left = joint[0] == "l"
        return _NEEDS[joint[2:]].format(S="Left" if left else "Right", s=joint[0])
    return _NEEDS[joint]


def strip_namespace(name: str) -> str:
    """``"mixamorig:LeftArm"`` -> ``"LeftArm"`` (any ``prefix:`` namespace)."""
    return name.rsplit(":", 1)[-1]


def split_name(name: str) -> tuple:
    """``(side, base)`` of a joint name: side ``"l"``, ``"r"`` or ``""``; base lower case.

    >>> split_name("mixamorig:LeftUpLeg"), split_name("CC_Base_R_Calf"), split_name("DEF-thigh.L")
    (('l', 'upleg'), ('r', 'calf'), ('l', 'thigh'))
    """
    raw = _PREFIXES.sub("", strip_namespace(name).strip())
    side, rest = "", raw
    for k, pattern in enumerate(_SIDE_PATTERNS):
        m = pattern.match(raw)
        if not m:
            continue
        groups = m.groups()
        if k in (0, 2, 5):
            side, rest = groups[0], groups[1]
        elif k in (1, 3):
            rest, side = groups[0], groups[1]
        else:
            rest, side = groups[0] + groups[2], groups[1]
        side = side[0].lower()
        break
    return side, re.sub(r"[\s_.\-]", "", rest).lower()


def detect_convention(names) -> str:
    """A readable name for the naming convention of a skeleton's joint names (for reports)."""
    raw = [strip_namespace(n) for n in names]
    s = set(raw)
    low = {n.lower() for n in raw}
    if any(n.lower().startswith("mixamorig") for n in names):
        return "Mixamo"
    if any(n.startswith("CC_Base_") for n in raw):
        return "Reallusion CC"
    if any(n.upper().startswith(("DEF-", "ORG-")) for n in raw):
        return "Blender Rigify"
    if {"LHipJoint", "LeftHip", "LeftKnee"} <= s:
        return "CMU cgspeed 3dsMax"
    if {"LHipJoint", "LeftUpLeg", "LeftLeg"} <= s:
        return "CMU cgspeed MotionBuilder"
    if {"lThigh", "lShin"} <= s or {"lShldr", "lForeArm"} <= s:
        return "CMU cgspeed Daz"
    if {"left_hip", "left_knee"} <= low or {"l_hip", "l_knee"} <= low:
        return "SMPL"
    if {"LeftUpperLeg", "LeftLowerLeg"} <= s:
        return "Xsens MVN"
    if {"LeftThigh", "LeftShin"} <= s:
        return "Rokoko"
    if {"Spine1", "Neck1", "LeftUpLeg"} <= s and "Spine" not in s:
        return "DeepMimic"
    if any(n.startswith(("LeftInHand", "RightInHand")) for n in raw):
        return "Perception Neuron"
    if {"LeftUpLeg", "LeftForeArm"} <= s:
        return "MotionBuilder-style"
    return "unrecognised"


#: Metres-per-unit name of the conventions whose files always use one unit.
CONVENTION_UNITS = {"CMU cgspeed MotionBuilder": "cmu", "CMU cgspeed 3dsMax": "cmu",
                    "CMU cgspeed Daz": "cm", "Reallusion CC": "cm"}


def read_joint_map(path) -> dict:
    """Read a joint-map JSON file ``{our joint name: file joint name}``.

    Raises
    ------
    InputError
        Unreadable file, not a JSON object of strings, or a key that is not one of the
        15 contract joints.
    """
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(path, f"cannot read joint map ({exc.strerror or exc})") from None
    except ValueError as exc:
        raise InputError(path, f"joint map is not valid JSON ({exc})") from None
    return check_joint_map(data, path)


def check_joint_map(data, path=None) -> dict:
    """Validate a joint map given as a dict (see :func:`read_joint_map`); returns a copy."""
    if not isinstance(data, dict) or not all(isinstance(k, str) and isinstance(v, str) for k, v in data.items()):
        raise InputError(path, 'joint map must be a JSON object {"our joint": "file joint"} of strings')
    unknown = sorted(set(data) - set(JOINT_NAMES))
    if unknown:
        raise InputError(path, f"joint map names unknown joints {', '.join(unknown)}; "
                               f"ours are {', '.join(JOINT_NAMES)}")
    return dict(data)


def _ancestors(parents, j):
    out = []
    j = int(parents[j])
    while j >= 0:
        out.append(j)
        j = int(parents[j])
    return out


def _descendants(parents, j):
    out, frontier = [], [j]
    while frontier:
        kids = [k for k in range(len(parents)) if int(parents[k]) in frontier]
        out.extend(kids)
        frontier = kids
    return out


def map_joints(names, parents, end_site_parents, joint_map=None, path=None) -> dict:
    """Find the 15 contract joints in a skeleton.

    Parameters
    ----------
    names : list of str, (J,)
    parents : (J,) int
        Parent index, -1 for the root; parents before children.
    end_site_parents : (E,) int
    joint_map : dict or None
        ``{contract joint: file joint name}`` overriding what would be found.
    path : str or None
        For error messages.

    Returns
    -------
    dict
        ``{contract name: recipe}`` with recipe ``("joint", j)``, ``("mid", j, k)``
        (halfway between two joints), ``("end", e)`` (an end site), ``("midend", j, e)``
        or ``("eyes", head, neck, eye_a, eye_b)`` (the head joint moved along the neck
        to the level of the eyes).

    Raises
    ------
    InputError
        One line naming the joints that were not found, the joints the file has and the
        names each missing joint may have.
    """
    parents = [int(p) for p in parents]
    joint_map = check_joint_map(joint_map, path) if joint_map is not None else None
    split = [split_name(n) for n in names]
    by_name = {}
    for j, n in enumerate(names):
        by_name.setdefault(n, j)
        by_name.setdefault(strip_namespace(n), j)
    given = {}
    for ours, theirs in (joint_map or {}).items():
        if theirs not in by_name:
            raise InputError(path, f"joint map names {theirs!r} for {ours}, but the file has no such joint "
                                   f"(joints: {' '.join(names)})")
        given[ours] = by_name[theirs]

    def named(side, bases, among=None):
        """The first joint (in ``among``'s order) with the side and a base, bases in preference order."""
        pool = range(len(names)) if among is None else among
        for base in bases:
            for j in pool:
                if split[j] == (side, base):
                    return j
        return None

    def nearest(side, bases, among):
        """The first joint in ``among`` (nearest first) with the side and any of the bases."""
        return next((j for j in among if split[j][0] == side and split[j][1] in bases), None)

    found = dict(given)
    for side in "lr":
        for mid, upper, lower, (up_key, mid_key, low_key) in (
                (KNEE, THIGH, ANKLE, ("hip", "knee", "ankle")),
                (ELBOW, UPPER_ARM, WRIST, ("shoulder", "elbow", "wrist"))):
            up_key, mid_key, low_key = (f"{side}_{k}" for k in (up_key, mid_key, low_key))
            if mid_key not in found:
                j = named(side, mid)
                if j is not None:
                    found[mid_key] = j
            m = found.get(mid_key)
            if m is None:
                continue
            if up_key not in found:
                # The nearest ancestor with an upper-limb name: structure, not name, tells
                # a 3dsMax LeftShoulder (the elbow's parent) from a MotionBuilder one (the
                # parent of LeftArm, a clavicle).
                j = nearest(side, upper, _ancestors(parents, m)[:3])
                if j is None and parents[m] >= 0 and split[parents[m]][0] == side:
                    j = parents[m]
                if j is not None:
                    found[up_key] = j
            if low_key not in found:
                below = _descendants(parents, m)
                j = named(side, lower, below)
                if j is None:
                    kids = [k for k in range(len(names)) if parents[k] == m]
                    j = kids[0] if len(kids) == 1 else None
                if j is not None:
                    found[low_key] = j
    if "head" not in found:
        j = named("", HEAD)
        if j is not None:
            found["head"] = j
    if "neck" not in found:
        head = found.get("head")
        pool = _ancestors(parents, head) if head is not None else None
        j = named("", NECK, pool)
        if j is None and head is None:
            j = named("", NECK)
        if j is None and head is not None and parents[head] >= 0:
            j = parents[head]
        if j is not None:
            found["neck"] = j
    if "pelvis" not in found and all(k in found for k in ("l_hip", "r_hip", "neck")):
        chains = [[found[k]] + _ancestors(parents, found[k]) for k in ("l_hip", "r_hip", "neck")]
        common = [j for j in chains[0] if j in chains[1] and j in chains[2]]
        if common:
            found["pelvis"] = common[0]

    ends = set(int(p) for p in end_site_parents)
    missing = [k for k in JOINT_NAMES if k not in found
               and not (k == "head" and found.get("neck") in ends)]    # DeepMimic: head = neck end site
    if missing:
        needs = "; ".join(f"{k}: {_needs(k)}" for k in missing)
        raise InputError(path, f"BVH skeleton ({detect_convention(names)} names) has no joint for "
                               f"{', '.join(missing)} (looked for {needs}); its joints: {' '.join(names)}; "
                               f"name them with --joint-map FILE.json {{\"our joint\": \"file joint\"}}")

    recipe = {k: ("joint", found[k]) for k in JOINT_NAMES if k != "head"}
    recipe["head"] = _head_recipe(names, parents, end_site_parents, split, found)
    return recipe


def _head_recipe(names, parents, end_site_parents, split, found):
    """The head centre: halfway from the skull base to the top of the head, where known."""
    ends = {int(p): e for e, p in enumerate(end_site_parents)}
    neck = found["neck"]
    head = found.get("head")
    if head is None:
        # DeepMimic: the neck's end site is the head centre.
        return ("end", ends[neck])
    kids = [k for k in range(len(names)) if parents[k] == head]
    top = next((k for k in kids if split[k][1] in HEAD_TOP), None)
    if top is not None:
        return ("mid", head, top)
    if head in ends:
        return ("midend", head, ends[head])
    eyes = [k for k in _descendants(parents, head) if split[k][1] in EYE and split[k][0]]
    if len(eyes) >= 2:
        return ("eyes", head, neck, eyes[0], eyes[1])
    return ("joint", head)
