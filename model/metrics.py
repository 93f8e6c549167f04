"""Agreement metrics of paper section 1.3: M0 (%), R0, R^2.

All take ``measured`` y_a and ``predicted`` y_p, 1-D arrays of one shape
(N,), N >= 1 (R^2: N >= 2), finite; they raise ``ValueError`` naming the
element otherwise.
"""

from __future__ import annotations

import numpy as np

__all__ = ["m0_pct", "r0", "r2"]


def _pair(measured, predicted) -> tuple[np.ndarray, np.ndarray]:
    ya = np.asarray(measured, dtype=float)
    yp = np.asarray(predicted, dtype=float)
    if ya.ndim != 1 or ya.shape != yp.shape:
        raise ValueError(f"measured and predicted must be 1-D of one shape, got {ya.shape} and {yp.shape}")
    if ya.size == 0:
        raise ValueError("measured and predicted are empty")
    for name, arr in (("measured", ya), ("predicted", yp)):
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise ValueError(f"{name}[{bad[0]}] = {float(arr[bad[0]])!r} is not finite")
    return ya, yp


def m0_pct(measured, predicted) -> float:
    """Maximum error rate M0 [%] = 100 * max_i |y_p,i - y_a,i| / |y_a,i| (paper §1.3).

    Raises ``ValueError`` if a measured value is 0 (the rate is undefined there;
    the paper excludes small slips, where Dp is near zero, for this reason).
    """
    ya, yp = _pair(measured, predicted)
    zero = np.flatnonzero(ya == 0)
    if zero.size:
        raise ValueError(f"measured[{zero[0]}] = 0: the error rate M0 is undefined for a zero measured value")
    return float(100.0 * np.max(np.abs(yp - ya) / np.abs(ya)))


def r0(measured, predicted) -> float:
    """Root mean squared error R0 = sqrt(mean((y_p - y_a)^2)), unit of the data (paper §1.3)."""
    ya, yp = _pair(measured, predicted)
    return float(np.sqrt(np.mean((yp - ya) ** 2)))


def r2(measured, predicted) -> float:
    """Correlation coefficient R^2 = [cov(y_a, y_p) / (sigma_a sigma_p)]^2 (paper §1.3).

    Population (1/N) covariance and standard deviations, as in the paper.
    Raises ``ValueError`` if either series is constant (R^2 undefined) or N < 2.
    """
    ya, yp = _pair(measured, predicted)
    if ya.size < 2:
        raise ValueError("R^2 needs at least 2 samples")
    da = ya - ya.mean()
    dp = yp - yp.mean()
    sa = np.sqrt(np.mean(da * da))
    sp = np.sqrt(np.mean(dp * dp))
    if sa == 0 or sp == 0:
        which = "measured" if sa == 0 else "predicted"
        raise ValueError(f"{which} values are constant: R^2 is undefined")
    return float((np.mean(da * dp) / (sa * sp)) ** 2)
