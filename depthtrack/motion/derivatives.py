"""Discrete derivative filters (thesis section 4.8, Tables 4.1 and 4.2, section 7.1).

Masks are written as convolution masks, as in the thesis: ``[1 0 -1] / 2`` means
``f'(t) ~ (f(t+1) - f(t-1)) / 2``. The Taylor-optimised masks are *derived* here,
not copied (the thesis text lost digits, and its r = 4 row prints 673 where the
construction gives 672): a symmetric mask of radius r for the n-th derivative
is the one that is exact on every polynomial of degree <= 2r (n = 1) or
<= 2r + 1 (n = 2), i.e. the solution of the moment equations
``sum_k c_k k^m / m! = [m == n]`` for m = 0 .. 2r (a Vandermonde system).

Table 4.2's second-order masks come from a weighted least-squares fit of the
frequency response (Jaehne), not from Taylor series; they are kept as printed
in :data:`TABLE_4_2_SECOND_ORDER` and are *not* exact on quadratics (their
second moment is 2.209, 1.950, 1.967 instead of 2).
"""
from __future__ import annotations

from fractions import Fraction

import numpy as np
from scipy import ndimage

#: Table 4.2 as printed: centre coefficient then the one-sided coefficients (symmetric masks).
TABLE_4_2_SECOND_ORDER = {
    1: (-2.20914, 1.10457),
    2: (-2.71081, 1.48229, -0.126882),
    3: (-2.92373, 1.65895, -0.224751, 0.0276655),
}


def taylor_coefficients(radius: int, order: int = 1):
    """Exact rational coefficients ``c_k`` (k = -r .. r) with ``f^(n)(0) ~ sum_k c_k f(k)``.

    Solves ``sum_k c_k k^m = n! [m == n]`` for m = 0 .. 2r with exact fractions.

    Returns
    -------
    list of Fraction, length 2r + 1, for k = -r .. r.
    """
    if radius < 1 or order not in (1, 2):
        raise ValueError("radius >= 1 and order 1 or 2")
    ks = list(range(-radius, radius + 1))
    size = len(ks)
    # Gauss-Jordan elimination on the Vandermonde system in exact arithmetic.
    factorial = 1 if order == 1 else 2
    rows = [[Fraction(k) ** m for k in ks] + [Fraction(factorial if m == order else 0)]
            for m in range(size)]
    for col in range(size):
        pivot = next(r for r in range(col, size) if rows[r][col] != 0)
        rows[col], rows[pivot] = rows[pivot], rows[col]
        p = rows[col][col]
        rows[col] = [v / p for v in rows[col]]
        for r in range(size):
            if r != col and rows[r][col] != 0:
                f = rows[r][col]
                rows[r] = [a - f * b for a, b in zip(rows[r], rows[col])]
    return [rows[i][-1] for i in range(size)]


def taylor_mask(radius: int, order: int = 1) -> np.ndarray:
    """Taylor-optimised derivative mask of radius r as a convolution mask (2r + 1,) float.

    ``taylor_mask(2)`` = ``[-1, 8, 0, -8, 1] / 12`` (Table 4.1, r = 2);
    ``taylor_mask(1, 2)`` = ``[1, -2, 1]``.
    """
    coeffs = taylor_coefficients(radius, order)
    # convolution mask = coefficients for k = +r .. -r
    return np.array([float(c) for c in coeffs[::-1]])


def table_4_2_mask(radius: int) -> np.ndarray:
    """Table 4.2's weighted-least-squares second-order mask (2r + 1,) as printed."""
    centre, *side = TABLE_4_2_SECOND_ORDER[radius]
    side = np.array(side)
    return np.concatenate([side[::-1], [centre], side])


#: Named first-order filters of the comparison in section 7.1.
FIRST_ORDER_FILTERS = {
    "D1 [1 -1]": np.array([1.0, -1.0]),
    "D2 1/2[1 0 -1]": np.array([0.5, 0.0, -0.5]),
    "Taylor r=2": taylor_mask(2),
    "Taylor r=3": taylor_mask(3),
    "Taylor r=4": taylor_mask(4),
}


def first_order_filter(name: str) -> np.ndarray:
    """Mask of a named first-order filter: ``"d1"``, ``"d2"``, ``"taylor2"`` .. ``"taylor4"``."""
    key = name.lower().replace(" ", "")
    if key == "d1":
        return FIRST_ORDER_FILTERS["D1 [1 -1]"]
    if key == "d2":
        return FIRST_ORDER_FILTERS["D2 1/2[1 0 -1]"]
    if key.startswith("taylor") and key[6:].isdigit():
        return taylor_mask(int(key[6:]))
    raise ValueError(f"unknown derivative filter {name!r} (d1, d2, taylor2, taylor3, taylor4)")


def apply_mask(signal, mask, axis: int = 0, mode: str = "nearest"):
    """Convolve ``signal`` along ``axis`` with a derivative mask.

    Odd masks are centred. The two-tap ``[1 -1]`` is the backward difference
    ``f(t) - f(t-1)`` (its true position is t - 1/2; the thesis's D1x).

    Parameters
    ----------
    signal : (..., T, ...) float
    mask : (K,) float, convolution order
    mode : str
        Border handling of :func:`scipy.ndimage.convolve1d`.

    Returns
    -------
    Same shape as ``signal``.
    """
    mask = np.asarray(mask, dtype=float)
    origin = 0 if len(mask) % 2 else -1
    return ndimage.convolve1d(np.asarray(signal, dtype=float), mask, axis=axis, mode=mode, origin=origin)


def velocity_acceleration(angles, first_order, second_order=None, axis: int = 0, mode: str = "nearest"):
    """Velocity and acceleration of ``angles`` along ``axis`` (per sample, per sample^2).

    The acceleration is the first-order mask applied twice (as in the thesis) or,
    when ``second_order`` is given, that mask applied once.
    """
    v = apply_mask(angles, first_order, axis, mode)
    a = apply_mask(v, first_order, axis, mode) if second_order is None else \
        apply_mask(angles, second_order, axis, mode)
    return v, a


def extrapolation_error(angles, velocity, acceleration, trim: int = 0, axis: int = 0):
    """Thesis equations 7.1 and 7.2 with dt = 1.

    ``p_hat[t] = p[t-1] + v[t-1] + a[t-1] / 2`` and ``E = 1/2 sum (p - p_hat)^2`` over
    all angles and the time steps ``trim + 1 .. T - 1 - trim`` (``trim`` drops the
    border samples a long mask cannot reach).

    Returns
    -------
    float
    """
    p = np.moveaxis(np.asarray(angles, float), axis, 0)
    v = np.moveaxis(np.asarray(velocity, float), axis, 0)
    a = np.moveaxis(np.asarray(acceleration, float), axis, 0)
    p_hat = p[:-1] + v[:-1] + 0.5 * a[:-1]
    err = (p[1:] - p_hat) ** 2
    stop = err.shape[0] - trim
    return 0.5 * float(err[trim:stop].sum())


def compare_derivative_filters(cycles, trim: int | None = None):
    """Section 7.1's comparison on training cycles.

    Parameters
    ----------
    cycles : (n, T, A) float
        Resampled (and smoothed) training cycles.

    Returns
    -------
    list of dict
        One row per filter: ``name``, ``mask``, ``error`` (E of eq. 7.2), ``error_per_sample``.
    """
    cycles = np.asarray(cycles, float)
    filters = dict(FIRST_ORDER_FILTERS)
    combos = [(name, m, None) for name, m in filters.items()]
    for r in (1, 2, 3):
        combos.append((f"Taylor r=3 + Table 4.2 r={r}", taylor_mask(3), table_4_2_mask(r)))
        combos.append((f"Taylor r=3 + Taylor 2nd r={r}", taylor_mask(3), taylor_mask(r, 2)))
    if trim is None:
        trim = 2 * 4 + 1
    rows = []
    for name, first, second in combos:
        err = 0.0
        count = 0
        for cycle in cycles:
            v, a = velocity_acceleration(cycle, first, second, axis=0)
            err += extrapolation_error(cycle, v, a, trim=trim)
            count += (cycle.shape[0] - 1 - 2 * trim) * cycle.shape[1]
        rows.append({"name": name, "first_order": [float(x) for x in first],
                     "second_order": None if second is None else [float(x) for x in second],
                     "error": err, "error_per_sample": err / max(count, 1)})
    return rows
