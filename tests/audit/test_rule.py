"""The audit rule (ur3hanoi.audit.rule): whatever a table's own scatter, a contact inside the floors is never
flagged and one past the ceilings always is; above poses by their own rule; the table's axis is robust."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ur3hanoi.audit.rule import (
    ABOVE_CLEAR_MM,
    ABOVE_FLAG_LINE_MM,
    ABOVE_LINE_MM,
    ABOVE_MIN_MM,
    CONTACT_FLAG_MM,
    CONTACT_OK_MM,
    TILT_FLAG_DEG,
    TILT_OK_DEG,
    angle_deg,
    derive_rule,
    judge_above,
    judge_contact,
    table_axis,
)

SCATTER = st.lists(st.floats(0.0, 50.0), min_size=0, max_size=30)


@settings(max_examples=200, deadline=None)
@given(dev=SCATTER, tilts=SCATTER, line=st.floats(0.0, CONTACT_OK_MM), level=st.floats(-CONTACT_OK_MM, CONTACT_OK_MM),
       tilt=st.floats(0.0, TILT_OK_DEG))
def test_inside_the_floors_is_never_flagged(dev: list[float], tilts: list[float], line: float, level: float,
                                            tilt: float) -> None:
    rule = derive_rule(np.array(dev), np.array(tilts))
    assert CONTACT_OK_MM <= rule.warn_mm <= CONTACT_FLAG_MM and TILT_OK_DEG <= rule.warn_deg <= TILT_FLAG_DEG
    assert judge_contact(line, level, tilt, rule).status == "ok"


@settings(max_examples=200, deadline=None)
@given(dev=SCATTER, tilts=SCATTER, off=st.floats(CONTACT_FLAG_MM + 1e-6, 500.0), angle=st.floats(-math.pi, math.pi))
def test_past_the_ceiling_is_always_flagged(dev: list[float], tilts: list[float], off: float, angle: float) -> None:
    rule = derive_rule(np.array(dev), np.array(tilts))
    line, level = abs(off * math.cos(angle)), off * math.sin(angle)  # 8 mm from where the grid puts it, any way
    v = judge_contact(line, level, 0.0, rule)
    assert v.status == "flagged" and v.severity > 1.0 and f"more than {CONTACT_FLAG_MM:g} mm" in v.why
    assert judge_contact(0.0, 0.0, TILT_FLAG_DEG + 0.01, rule).status == "flagged"


def test_in_between_a_warning_over_the_data_s_threshold() -> None:
    tight = derive_rule(np.full(9, 0.5), np.full(9, 0.1))  # sigma 0.33 mm: warnings from the 5 mm floor
    loose = derive_rule(np.full(9, 2.0), np.full(9, 0.9))  # sigma 1.3 mm: 5 sigma = 6.5 mm
    assert tight.warn_mm == CONTACT_OK_MM and loose.warn_mm == pytest.approx(5 * 2.0 / 1.5382, rel=1e-12)
    assert judge_contact(6.0, 0.0, 0.0, tight).status == "warn" and judge_contact(6.0, 0.0, 0.0, loose).status == "ok"
    assert judge_contact(0.0, 0.0, 4.5, tight).status == "warn"
    few = derive_rule(np.array([1.0, 2.0]), np.array([0.2]))  # too few contacts for a scatter: the floors
    assert math.isnan(few.sigma_mm) and (few.warn_mm, few.warn_deg) == (CONTACT_OK_MM, TILT_OK_DEG)
    fixed = derive_rule(np.full(9, 2.0), np.full(9, 0.9), tol_mm=2.0)
    assert fixed.fixed and fixed.flag_mm == 2.0 and fixed.warn_mm == 2.0
    assert judge_contact(2.5, 0.0, 0.0, fixed).status == "flagged"


def test_above_poses() -> None:
    assert judge_above(ABOVE_LINE_MM, ABOVE_CLEAR_MM, 40.0).status == "ok"
    assert judge_above(ABOVE_LINE_MM + 0.5, 30.0, 40.0).status == "warn"
    assert judge_above(ABOVE_FLAG_LINE_MM + 0.5, 30.0, 40.0).status == "flagged"
    assert judge_above(0.0, ABOVE_CLEAR_MM - 0.5, 40.0).status == "warn"
    low = judge_above(0.0, ABOVE_MIN_MM - 0.5, ABOVE_MIN_MM - 0.5)
    assert low.status == "flagged" and "over the table's top level" in low.why
    under = judge_above(0.0, 30.0, -20.0)  # (a contact level above the top one cannot happen; its own rule holds)
    assert under.status == "flagged" and "20.0 mm below its own contact" in under.why


def test_the_table_axis_is_robust_to_a_tilted_entry() -> None:
    rng = np.random.default_rng(0)
    true = np.array([math.sin(math.radians(2.0)), 0.0, -math.cos(math.radians(2.0))])
    axes = []
    for _ in range(8):
        v = true + rng.normal(scale=math.radians(0.3), size=3)
        axes.append(v / np.linalg.norm(v))
    bad = np.array([math.sin(math.radians(9.0)), 0.0, -math.cos(math.radians(9.0))])
    a = table_axis(np.array([*axes, bad]))
    assert float(angle_deg(a.reshape(1, 3), true)[0]) < 0.3
    assert float(angle_deg(bad.reshape(1, 3), a)[0]) > 6.7
    assert np.array_equal(table_axis(np.array(axes[:2])), [0.0, 0.0, -1.0])  # too few: straight down
