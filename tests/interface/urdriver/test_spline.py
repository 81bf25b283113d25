"""The joint trajectory controller's segments: degree by the fields given, boundary conditions, time bounds."""

from __future__ import annotations

import numpy as np
import pytest

from ur3hanoi.interface.urdriver.spline import JointState, find_segment, segment

RNG = np.random.default_rng(34)


def state(n: int = 6, fields: int = 3) -> JointState:
    q, qd, qdd = RNG.uniform(-1, 1, n), RNG.uniform(-1, 1, n), RNG.uniform(-3, 3, n)
    return JointState(q, qd if fields > 1 else None, qdd if fields > 2 else None)


@pytest.mark.parametrize(("fields", "degree"), [(1, 1), (2, 3), (3, 5)])
def test_degree_follows_the_fields_and_the_ends_are_met(fields, degree):
    a, b = state(fields=fields), state(fields=fields)
    s = segment(1.0, a, 1.7, b)
    assert s.degree == degree
    p0, v0, acc0 = s.sample(1.0)
    p1, v1, acc1 = s.sample(1.7)
    np.testing.assert_allclose(p0, a.q, atol=1e-12)
    np.testing.assert_allclose(p1, b.q, atol=1e-12)
    if fields > 1:
        np.testing.assert_allclose(v0, a.qd, atol=1e-12)
        np.testing.assert_allclose(v1, b.qd, atol=1e-11)
    if fields > 2:
        np.testing.assert_allclose(acc0, a.qdd, atol=1e-11)
        np.testing.assert_allclose(acc1, b.qdd, atol=1e-10)


def test_mixed_fields_use_the_lower_degree():
    full, positions = state(fields=3), state(fields=1)
    assert segment(0.0, full, 1.0, positions).degree == 1
    assert segment(0.0, full, 1.0, state(fields=2)).degree == 3


def test_derivatives_are_consistent():
    s = segment(0.0, state(), 2.0, state())
    h = 1e-6
    for t in (0.3, 1.1, 1.9):
        p_minus, v_minus, _ = s.sample(t - h)
        p_plus, v_plus, _ = s.sample(t + h)
        _, v, acc = s.sample(t)
        np.testing.assert_allclose((p_plus - p_minus) / (2 * h), v, atol=1e-6)
        np.testing.assert_allclose((v_plus - v_minus) / (2 * h), acc, atol=1e-5)


def test_outside_the_segment_it_holds_its_ends_at_rest():
    a, b = state(), state()
    s = segment(1.0, a, 2.0, b)
    p, v, acc = s.sample(0.5)
    np.testing.assert_allclose(p, a.q, atol=1e-12)
    assert not v.any() and not acc.any()
    p, v, acc = s.sample(5.0)
    np.testing.assert_allclose(p, b.q, atol=1e-12)
    assert not v.any() and not acc.any()


def test_a_zero_length_segment_holds_its_start():
    a, b = state(), state()
    p, _, _ = segment(1.0, a, 1.0, b).sample(1.0)
    np.testing.assert_allclose(p, a.q, atol=1e-12)


def test_a_quintic_reproduces_a_quintic_polynomial():
    c = RNG.uniform(-1, 1, 6)
    poly = np.polynomial.Polynomial(c)

    def st(t: float) -> JointState:
        return JointState(np.array([poly(t)]), np.array([poly.deriv(1)(t)]), np.array([poly.deriv(2)(t)]))

    s = segment(0.2, st(0.2), 1.3, st(1.3))
    for t in np.linspace(0.2, 1.3, 9):
        assert s.sample(t)[0][0] == pytest.approx(poly(t), abs=1e-12)


def test_find_segment_takes_the_last_started_or_the_first():
    a = state()
    segs = [segment(t, a, t + 1.0, a) for t in (0.0, 1.0, 2.0)]
    assert [find_segment(segs, t) for t in (-1.0, 0.0, 0.5, 1.0, 2.5, 9.0)] == [0, 0, 0, 1, 2, 2]


def test_end_before_start_is_refused():
    with pytest.raises(ValueError, match="before its start"):
        segment(1.0, state(), 0.5, state())
