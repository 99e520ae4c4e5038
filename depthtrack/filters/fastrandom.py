"""Fast approximate standard normals for particle noise.

numpy's float32 Ziggurat costs ~17 ns a number here; the particle filter needs a
few million a frame. :func:`table_normals` draws 16-bit uniform integers and maps
them through a table of the 65,536 normal quantiles ``Phi^-1((k + 1/2) / 65536)``
(rescaled to unit variance): every quantile bin is equally likely, so the draws
are standard normal up to a quantisation of 1/65536 in probability, truncated at
about 4.2 standard deviations. About 2x faster; fine for transition noise, not
for tail statistics.
"""
from __future__ import annotations

import numpy as np
from scipy.special import ndtri

_LEVELS = 1 << 16
_TABLE = ndtri((np.arange(_LEVELS) + 0.5) / _LEVELS)
_TABLE = (_TABLE / _TABLE.std()).astype(np.float32)


def table_normals(rng: np.random.Generator, shape) -> np.ndarray:
    """Approximate N(0, 1) float32 draws of ``shape`` (see module docstring)."""
    codes = rng.integers(0, _LEVELS, size=shape, dtype=np.uint16)
    return _TABLE[codes]
