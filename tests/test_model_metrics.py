"""Agreement metrics of paper section 1.3."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wheelsoil.model import m0_pct, r0, r2


def test_values_by_hand():
    ya = [100.0, -200.0, 50.0]
    yp = [110.0, -150.0, 50.0]
    assert m0_pct(ya, yp) == pytest.approx(25.0)  # |50| / |-200|
    assert r0(ya, yp) == pytest.approx(np.sqrt((100 + 2500 + 0) / 3))


def test_r2_is_squared_correlation_and_affine_invariant():
    rng = np.random.default_rng(0)
    ya = rng.normal(size=50)
    yp = ya + 0.3 * rng.normal(size=50)
    assert r2(ya, yp) == pytest.approx(np.corrcoef(ya, yp)[0, 1] ** 2, rel=1e-12)
    assert r2(ya, 3 * ya - 7) == pytest.approx(1.0)
    assert r2(ya, -ya) == pytest.approx(1.0)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-1e4, 1e4), min_size=2, max_size=30))
def test_perfect_prediction(values):
    ya = np.array(values)
    assert r0(ya, ya) == 0.0
    if np.all(ya != 0):
        assert m0_pct(ya, ya) == 0.0
    if np.ptp(ya) > 1e-6:
        assert r2(ya, ya) == pytest.approx(1.0)


def test_errors():
    with pytest.raises(ValueError, match=r"measured\[1\] = 0: .*undefined"):
        m0_pct([1.0, 0.0], [1.0, 1.0])
    with pytest.raises(ValueError, match=r"predicted\[0\] = nan"):
        r0([1.0], [float("nan")])
    with pytest.raises(ValueError, match="one shape"):
        r0([1.0, 2.0], [1.0])
    with pytest.raises(ValueError, match="constant"):
        r2([1.0, 1.0, 1.0], [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="empty"):
        r0([], [])
