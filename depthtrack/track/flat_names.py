"""The tracker settings' earlier flat names (:class:`~.settings.TrackerSettings` reads them).

``TrackerSettings(heading_frames=0)`` and ``settings.lost_ratio`` still construct and read;
``summary.json`` always writes these keys (add names, never remove one).
"""
from __future__ import annotations

#: The earlier flat setting names -> (group, field).
FLAT_NAMES = {
    "tile": ("observe", "tile"), "roi_margin": ("observe", "roi_margin"),
    "depth_band": ("observe", "depth_band"), "min_person_area": ("observe", "min_person_area"),
    "absent_frames": ("observe", "absent_frames"),
    "damping": ("energy", "damping"), "likelihood_weight": ("energy", "likelihood_weight"),
    "pose_prior_std": ("energy", "pose_prior_std"),
    "levels": ("search", "levels"), "max_iterations": ("search", "max_iterations"),
    "step_scale": ("search", "step_scale"), "passes": ("search", "passes"),
    "diagonals": ("search", "diagonals"),
    "prune_distance": ("associate", "prune_distance"), "ep_obs_std": ("associate", "ep_obs_std"),
    "ep_prior_scale": ("associate", "ep_prior_scale"),
    "max_correspondences": ("associate", "max_correspondences"),
    "refine_level": ("associate", "refine_level"),
    "refine_with_prior": ("associate", "refine_with_prior"),
    "refine_scope": ("associate", "refine_scope"), "accept": ("associate", "accept"),
    "accept_margin": ("associate", "accept_margin"),
    "fine_tile": ("polish", "fine_tile"), "fine_iterations": ("polish", "fine_iterations"),
    "lost_ratio": ("judge", "lost_ratio"), "lost_margin": ("judge", "lost_margin"),
    "init_passes": ("start", "passes"), "facing_prior": ("start", "facing_prior"),
    "heading_frames": ("heading", "frames"), "heading_margin": ("heading", "margin"),
}
