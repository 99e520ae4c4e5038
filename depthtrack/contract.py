"""File contracts shared by every package: joint names and format identifiers.

These names are read and written by outside tools (see README, "File contracts"),
so they never change without a new format version.
"""

#: The 15 contract joints, in the order used by every ``(..., 15, 3)`` array.
JOINT_NAMES = (
    "head", "neck", "pelvis",
    "l_shoulder", "l_elbow", "l_wrist",
    "r_shoulder", "r_elbow", "r_wrist",
    "l_hip", "l_knee", "l_ankle",
    "r_hip", "r_knee", "r_ankle",
)

JOINT_INDEX = {name: i for i, name in enumerate(JOINT_NAMES)}

#: ``sequence.json`` format identifier.
SEQUENCE_FORMAT = "depthtrack-sequence/1"
