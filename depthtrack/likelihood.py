"""Sensor model and smoothed likelihood: the numpy reference of the GL cost pass.

Everything here is what ``shaders/tile_cost.comp`` computes on the GPU, written over
numpy arrays so tests can compare the two routes number for number.

Sensor model (the ToF paper)
----------------------------
A rendered depth ``r`` explains an observed depth ``o`` with the robust cost

    c(o, r) = smoothstep(|o - r| / depth_scale),   smoothstep(x) = min(x,1)^2 (3 - 2 min(x,1))

i.e. ``-log p`` of a Gaussian-plus-uniform mixture: quadratic near 0, saturating at 1 once
``|o - r| >= depth_scale`` (:attr:`LikelihoodParams.depth_scale`, default 0.10 m).

Smoothed likelihood (the ToF paper)
-----------------------------------
Observed pixel ``k`` may be explained by the rendered value of any pixel ``j`` of its 3x3
neighbourhood, paying a penalty ``eps(j, k)`` = 0 for ``j = k`` and
:attr:`LikelihoodParams.neighbor_penalty` for the 8 neighbours:

    s_k = min_j [ c(o_k, r_j) + eps(j, k) ]

Neighbours outside the tile are not considered (the tile is the whole world of a candidate).
The paper chose the penalty to approximate the Euclidean distance of a one-pixel shift; the
default 0.025 is the cost of a 9 mm depth error (one SR4000 pixel at 2 m) at depth_scale 0.1 m.

Edge rules (what the paper leaves open)
---------------------------------------
Observed depth images use 0 for "no reading" (NaN and negative values count as no reading
too); pixels at or beyond :attr:`LikelihoodParams.max_depth`, or ``+inf`` (the way to mark
background, e.g. after foreground segmentation), are *background*. Rendered tiles use 0 for
"model absent".

=====================  =========================  ======================================
observed pixel          model drawn (r > 0)         model absent (r = 0)
=====================  =========================  ======================================
no reading (0)          ``no_reading_cost``         ``no_reading_cost`` (neutral: the same
                                                    for every candidate, no smoothing)
background              ``silhouette_cost`` (1)     0 (explained by the scene)
depth o                 c(o, r)                     c(o, b) if a scene background depth b
                                                    is known there, else ``missing_cost`` (1)
=====================  =========================  ======================================

The model-absent column depends only on the observation, so it is precomputed once per
observation (:func:`encode_observation`, the RG texture the shader reads).

Resampling
----------
The observation is resampled once per ``set_observation`` into the tile grid of the ROI by
*nearest* sampling at the tile pixel centres (:func:`observation_tile`): each tile pixel takes
the camera pixel nearest to its centre (ties go to the larger index), never a blend, so no
phantom depths appear at silhouettes. The rendered tile is point-sampled at the tile pixel
centres themselves, so both sides see the same rays when the ROI is as many camera pixels
wide as the tile, and rays at most half a camera pixel apart otherwise (the smoothed
likelihood absorbs that at silhouettes). Pixels of the ROI outside the image have no reading.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError

#: Observed depth values that mark a pixel's class in an observation image: no reading
#: (also NaN and negative values) and background (also values at or beyond ``max_depth``).
NO_READING = 0.0
BACKGROUND = np.inf
#: The same classes in the encoded observation the shader reads (channel 0; a reading is
#: its depth, > 0).
NO_READING_CODE = 0.0
BACKGROUND_CODE = -1.0

#: THE sensor model (the table of the module docstring): the cost of each observed-pixel
#: class where the model is drawn and where it is absent, as a :class:`LikelihoodParams`
#: field name or a number; ``"smoothstep"`` is ``c(o, r)`` and ``"missing_cost"`` of a
#: reading gives way to ``c(o, b)`` where a scene depth ``b`` is known. The numpy reference
#: (:func:`encode_observation`, :func:`pixel_costs`), the shader's constants
#: (:func:`shader_constants`), the tracker's unexplained share (:func:`fixed_and_empty_costs`)
#: and the observation image of the tracker (``BACKGROUND`` for open space) all read it.
SENSOR_MODEL = {
    "no_reading": {"drawn": "no_reading_cost", "absent": "no_reading_cost"},
    "background": {"drawn": "silhouette_cost", "absent": 0.0},
    "reading": {"drawn": "smoothstep", "absent": "missing_cost"},
}


@dataclass(frozen=True)
class LikelihoodParams:
    """Parameters of the per-pixel sensor cost, shared by the GL pass and numpy.

    Attributes
    ----------
    depth_scale : float
        Depth difference (m) at which the smoothstep cost saturates at 1.
    neighbor_penalty : float
        Cost added when a pixel is explained by one of its 8 neighbours (smoothed likelihood).
    silhouette_cost : float
        Cost of model drawn where the observation is background.
    missing_cost : float
        Cost of an observed depth where the model is absent and no scene depth is known.
    no_reading_cost : float
        Cost of an observed pixel without a reading, whatever is rendered (neutral constant).
    max_depth : float
        Observed readings at or beyond this depth (m) count as background.
    """

    depth_scale: float = 0.10
    neighbor_penalty: float = 0.025
    silhouette_cost: float = 1.0
    missing_cost: float = 1.0
    no_reading_cost: float = 0.5
    max_depth: float = 20.0

    def __post_init__(self):
        values = (self.depth_scale, self.neighbor_penalty, self.silhouette_cost,
                  self.missing_cost, self.no_reading_cost, self.max_depth)
        if not all(np.isfinite(v) and v >= 0 for v in values) or self.depth_scale <= 0:
            raise InputError(None, f"likelihood parameters must be finite and >= 0 "
                                   f"(depth_scale > 0): {self}")



def sensor_cost(params: LikelihoodParams, observed: str, model: str) -> float:
    """The constant cost :data:`SENSOR_MODEL` gives ``(observed, model)`` under ``params``."""
    entry = SENSOR_MODEL[observed][model]
    if entry == "smoothstep":
        raise ValueError(f"the cost of ({observed}, {model}) depends on the depths")
    return float(getattr(params, entry) if isinstance(entry, str) else entry)


def shader_constants(params: LikelihoodParams) -> dict:
    """``#define`` values of ``tile_cost.comp``: the sensor model's codes and costs, as GLSL
    float literals (the shader holds no number of its own)."""
    values = {"NO_READING_CODE": NO_READING_CODE, "BACKGROUND_CODE": BACKGROUND_CODE,
              "DEPTH_SCALE": params.depth_scale,
              "NEIGHBOR_PENALTY": params.neighbor_penalty,
              "SILHOUETTE_COST": sensor_cost(params, "background", "drawn"),
              "NO_READING_COST": sensor_cost(params, "no_reading", "drawn")}
    if sensor_cost(params, "no_reading", "absent") != values["NO_READING_COST"]:
        raise ValueError("the shader assumes no-reading pixels cost the same drawn or absent")
    return {k: repr(float(v)) for k, v in values.items()}


def classify_observed(observed, params: LikelihoodParams):
    """``(no_reading, background)`` boolean masks of an observed depth array (any shape)."""
    o = np.asarray(observed, dtype=np.float64)
    no_reading = np.isnan(o) | (o <= NO_READING)
    background = ~no_reading & (np.isinf(o) | (o >= params.max_depth))
    return no_reading, background


def fixed_and_empty_costs(observed, params: LikelihoodParams | None = None, background=None):
    """Mean tile costs that bound what a candidate can explain of an observed tile.

    Returns
    -------
    fixed : float
        The share every candidate pays whatever it draws (pixels without a reading).
    empty : float
        The mean cost with no body drawn (every pixel at its model-absent cost).
    """
    params = params or LikelihoodParams()
    encoded = encode_observation(observed, params, background)
    absent = encoded[..., 1].astype(np.float64)
    fixed = np.where(encoded[..., 0] == NO_READING_CODE, absent, 0.0)
    return float(fixed.mean()), float(absent.mean())

def smoothstep(x):
    """GLSL ``smoothstep(0, 1, x)``: ``t^2 (3 - 2t)`` with ``t = clip(x, 0, 1)``; same shape as ``x``."""
    t = np.clip(x, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def observation_tile(depth, roi, tile: int) -> np.ndarray:
    """Resample an observed frame into the ``tile x tile`` grid of a square ROI (nearest).

    Parameters
    ----------
    depth : (H, W) float
        Observed camera z in metres; 0 = no reading.
    roi : (u0, v0, size)
        Square region of interest in camera pixels: columns ``u0 .. u0+size-1`` and rows
        ``v0 .. v0+size-1`` (may reach outside the image).
    tile : int
        Tile side in pixels.

    Returns
    -------
    observed : (tile, tile) float32
        The camera pixel nearest to each tile pixel centre; 0 outside the image.
    """
    depth = np.asarray(depth, dtype=np.float32)
    u0, v0, size = (float(x) for x in roi)
    # tile pixel j covers camera interval [u0 - 0.5 + j s, u0 - 0.5 + (j+1) s], s = size / tile
    centres = (np.arange(tile) + 0.5) * (size / tile) - 0.5
    cols = np.floor(u0 + centres + 0.5).astype(np.int64)
    rows = np.floor(v0 + centres + 0.5).astype(np.int64)
    h, w = depth.shape
    out = np.zeros((tile, tile), np.float32)
    rin, cin = (rows >= 0) & (rows < h), (cols >= 0) & (cols < w)
    out[np.ix_(rin, cin)] = depth[np.ix_(rows[rin], cols[cin])]
    return out


def encode_observation(observed, params: LikelihoodParams, background=None) -> np.ndarray:
    """Observation tile as the shader reads it: (depth code, model-absent cost) per pixel.

    Parameters
    ----------
    observed : (t, t) float
        Observed depth tile; 0, NaN or negative = no reading; +inf or >= max_depth = background.
    params : LikelihoodParams
    background : (t, t) float, optional
        Depth of the static scene behind the subject (0 = unknown) in the same tile grid.

    Returns
    -------
    encoded : (t, t, 2) float32
        ``[..., 0]``: observed z, 0 for no reading, -1 for background;
        ``[..., 1]``: the cost of this pixel when the model is absent there.
    """
    o = np.asarray(observed, dtype=np.float64)
    no_reading, is_background = classify_observed(o, params)
    o = np.where(no_reading, NO_READING_CODE, o)
    code = np.where(is_background, BACKGROUND_CODE, o)
    absent = np.full(o.shape, sensor_cost(params, "reading", "absent"))
    if background is not None:
        b = np.asarray(background, dtype=np.float64)
        known = np.isfinite(b) & (b > 0)
        with np.errstate(invalid="ignore"):
            scene = smoothstep(np.abs(o - b) / params.depth_scale)
        absent = np.where(known, scene, absent)
    absent = np.where(is_background, sensor_cost(params, "background", "absent"), absent)
    absent = np.where(no_reading, sensor_cost(params, "no_reading", "absent"), absent)
    return np.stack([code, absent], axis=-1).astype(np.float32)


def _pair_costs(encoded, rendered, params):
    """c(o_k, r) for every pixel k of ``encoded`` (t, t, 2) against ``rendered`` (..., t, t)."""
    code, absent = encoded[..., 0], encoded[..., 1]
    r = np.asarray(rendered, dtype=np.float32)
    diff = np.abs(code - r) / np.float32(params.depth_scale)
    c = np.where(code == BACKGROUND_CODE, np.float32(sensor_cost(params, "background", "drawn")),
                 smoothstep(diff))
    c = np.where(r <= 0, absent, c)
    return np.where(code == NO_READING_CODE, np.float32(sensor_cost(params, "no_reading", "drawn")),
                    c).astype(np.float64)


def pixel_costs(rendered, observed, params: LikelihoodParams | None = None,
                background=None) -> np.ndarray:
    """Per-pixel sensor cost of rendered tiles against the observed tile.

    Parameters
    ----------
    rendered : (..., t, t) float
        Rendered camera z, 0 = model absent.
    observed : (t, t) float
        Observed depth tile (0 = no reading; inf or >= max_depth = background).
    params : LikelihoodParams, optional
    background : (t, t) float, optional
        Scene depth behind the subject (0 = unknown).

    Returns
    -------
    costs : (..., t, t) float64
    """
    params = params or LikelihoodParams()
    return _pair_costs(encode_observation(observed, params, background), rendered, params)


def smoothed_costs(rendered, observed, params: LikelihoodParams | None = None,
                   background=None) -> np.ndarray:
    """Per-pixel smoothed cost: min over the 3x3 neighbourhood j of c(o_k, r_j) + penalty.

    Parameters and returns as :func:`pixel_costs`; neighbours outside the tile are skipped.
    """
    params = params or LikelihoodParams()
    encoded = encode_observation(observed, params, background)
    r = np.asarray(rendered, dtype=np.float32)
    t_rows, t_cols = r.shape[-2:]
    best = _pair_costs(encoded, r, params)
    # shift the rendered tile by (dy, dx) with a value that marks "outside the tile"
    padded = np.pad(r, [(0, 0)] * (r.ndim - 2) + [(1, 1), (1, 1)], constant_values=np.nan)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            if dx == 0 and dy == 0:
                continue
            shifted = padded[..., 1 + dy:1 + dy + t_rows, 1 + dx:1 + dx + t_cols]
            c = _pair_costs(encoded, np.nan_to_num(shifted, nan=0.0), params) \
                + params.neighbor_penalty
            best = np.minimum(best, np.where(np.isnan(shifted), np.inf, c))
    return best


def tile_costs(rendered, observed, params: LikelihoodParams | None = None,
               smoothed: bool = True, background=None) -> np.ndarray:
    """Mean per-pixel cost of each rendered tile (what ``TileRenderer.costs`` returns).

    Parameters
    ----------
    rendered : (N, t, t) float
    observed : (t, t) float
    params : LikelihoodParams, optional
    smoothed : bool
        Smoothed likelihood (True) or the pixel-wise sensor cost (False).
    background : (t, t) float, optional

    Returns
    -------
    costs : (N,) float64, lower is better
    """
    per_pixel = (smoothed_costs if smoothed else pixel_costs)(rendered, observed, params, background)
    return per_pixel.reshape(per_pixel.shape[:-2] + (-1,)).mean(axis=-1)
