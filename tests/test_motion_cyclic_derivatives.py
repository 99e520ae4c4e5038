"""Derivative masks (thesis Tables 4.1, 4.2) and the comparison of section 7.1."""
from fractions import Fraction

import numpy as np
import pytest

from depthtrack.motion.derivatives import (
    TABLE_4_2_SECOND_ORDER, apply_mask, compare_derivative_filters, extrapolation_error, table_4_2_mask,
    taylor_coefficients, taylor_mask, velocity_acceleration)


def test_taylor_masks_reproduce_table_4_1():
    assert np.allclose(taylor_mask(2) * 12, [-1, 8, 0, -8, 1])
    assert np.allclose(taylor_mask(3) * 60, [1, -9, 45, 0, -45, 9, -1])
    # the thesis prints 673 in the r = 4 row; the construction gives 672 (antisymmetric)
    assert np.allclose(taylor_mask(4) * 840, [-3, 32, -168, 672, 0, -672, 168, -32, 3])
    assert taylor_coefficients(2)[3] == Fraction(2, 3)
    assert np.allclose(taylor_mask(1, 2), [1, -2, 1])
    assert np.allclose(taylor_mask(2, 2) * 12, [-1, 16, -30, 16, -1])


@pytest.mark.parametrize("r", [1, 2, 3, 4])
def test_first_order_masks_exact_on_polynomials_up_to_degree_2r(r):
    t = np.arange(-20, 21, dtype=float)
    for degree in range(0, 2 * r + 1):
        f = (t / 7.0) ** degree
        exact = degree * (t / 7.0) ** max(degree - 1, 0) / 7.0 if degree else 0 * t
        got = apply_mask(f, taylor_mask(r))
        np.testing.assert_allclose(got[r:-r], exact[r:-r], atol=1e-9)
    f = (t / 7.0) ** (2 * r + 1)
    exact = (2 * r + 1) * (t / 7.0) ** (2 * r) / 7.0
    assert np.abs(apply_mask(f, taylor_mask(r))[r:-r] - exact[r:-r]).max() > 1e-6   # not beyond


@pytest.mark.parametrize("r", [1, 2, 3])
def test_second_order_taylor_masks_exact_up_to_degree_2r_plus_1(r):
    t = np.arange(-20, 21, dtype=float) / 5.0
    for degree in range(0, 2 * r + 2):
        f = t ** degree
        exact = degree * (degree - 1) * t ** max(degree - 2, 0) / 25.0 if degree > 1 else 0 * t
        np.testing.assert_allclose(apply_mask(f, taylor_mask(r, 2))[r:-r], exact[r:-r], atol=1e-9)


def test_taylor_order_of_accuracy_on_a_sinusoid():
    errs = []
    for r in (1, 2, 3, 4):
        t = np.arange(200.0)
        w = 0.3
        got = apply_mask(np.sin(w * t), taylor_mask(r))[10:-10]
        errs.append(np.abs(got - w * np.cos(w * t[10:-10])).max())
    assert errs[0] > errs[1] > errs[2] > errs[3]
    assert errs[3] < 1e-5


def test_simple_masks_and_alignment():
    t = np.arange(30.0)
    f = t ** 2
    np.testing.assert_allclose(apply_mask(f, [1.0, -1.0])[1:], (t ** 2 - (t - 1) ** 2)[1:])   # backward difference
    np.testing.assert_allclose(apply_mask(f, [0.5, 0.0, -0.5])[1:-1], 2 * t[1:-1])


@pytest.mark.parametrize("r", [1, 2, 3])
def test_table_4_2_masks_as_printed(r):
    m = table_4_2_mask(r)
    assert len(m) == 2 * r + 1 and np.allclose(m, m[::-1])
    assert abs(m.sum()) < 1e-4                                # no response to constants
    k = np.arange(-r, r + 1)
    second_moment = (m * k ** 2).sum()                        # 2 for an exact mask
    assert second_moment == pytest.approx(2.0, rel=0.11)
    omega = 0.2                                               # low frequencies: close to -omega^2
    response = (m * np.cos(omega * k)).sum()
    assert response == pytest.approx(-omega ** 2, rel=0.12)
    assert TABLE_4_2_SECOND_ORDER[r][0] == m[r]


def test_extrapolation_error_equation_7_1_and_7_2():
    t = np.arange(50.0)
    p = 0.5 * 0.01 * t ** 2 + 0.2 * t          # quadratic: exact velocity/acceleration extrapolate exactly?
    v = 0.01 * t + 0.2
    a = np.full_like(t, 0.01)
    # p[t] = p[t-1] + v[t-1] + a/2 exactly for a quadratic
    assert extrapolation_error(p, v, a) == pytest.approx(0.0, abs=1e-20)
    assert extrapolation_error(p, v, 0 * a) == pytest.approx(0.5 * 49 * (0.005 ** 2))


def test_comparison_ranks_the_forward_difference_last():
    t = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    cycles = np.stack([np.stack([np.sin(t + ph), np.cos(2 * t + ph)], -1) for ph in (0.0, 0.5, 1.0)])
    rows = compare_derivative_filters(cycles)
    errors = {r["name"]: r["error"] for r in rows}
    assert errors["D1 [1 -1]"] > 10 * errors["Taylor r=2"]
    assert all(np.isfinite(r["error"]) for r in rows)
    v, a = velocity_acceleration(cycles[0], taylor_mask(3), axis=0)
    np.testing.assert_allclose(a[10:-10, 0], -np.sin(t[10:-10]) * (t[1] ** 2), rtol=0, atol=1e-5)
