"""depthtrack: markerless human motion capture from depth cameras.

The public names are re-exported here; see the README for a tour.
"""
from .contract import JOINT_NAMES
from .errors import InputError
from .body import BodyModel

__version__ = "0.1.0"

__all__ = ["JOINT_NAMES", "InputError", "BodyModel", "__version__"]
