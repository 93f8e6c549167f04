"""Zero-phase low-pass filtering per contiguous segment, and resampling to a grid.

Filter: Butterworth low-pass designed as second-order sections
(:func:`scipy.signal.butter` with ``output="sos"``), run forward and backward
(:func:`scipy.signal.sosfiltfilt`): zero phase, amplitude response the square
of the design's (order 4 -> effective order 8, -6 dB at the cutoff). It is
applied to each contiguous run of valid samples separately, so a gap is never
bridged and a sample is never smeared into a gap. Resampling onto the output
grid interpolates linearly within a segment only; the low-pass, with the
cutoff at most 0.4 x the output rate, is also the anti-alias filter.

``DEFAULT_CUTOFF_HZ = 5`` Hz: the accelerate-brake manoeuvres of the paper
(sec. 2.2) change speed, load and drawbar pull within about a second (content
below about 2 Hz), while the WFT's strain-gauge noise and hub vibration, the
wheel-speed quantisation and the GNSS noise are broad-band; 5 Hz keeps the
manoeuvre, and removes about 99 % of the noise power of 500 Hz WFT data.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal
from scipy.interpolate import CubicSpline

__all__ = ["DEFAULT_CUTOFF_HZ", "FILTER_ORDER", "MAX_FILL_SAMPLES", "segments", "lowpass",
           "lowpass_segments", "filter_to_grid"]

DEFAULT_CUTOFF_HZ = 5.0
FILTER_ORDER = 4
#: Lost samples bridged by linear interpolation; longer gaps split a series into segments.
MAX_FILL_SAMPLES = 3


def segments(valid: np.ndarray) -> list[tuple[int, int]]:
    """Contiguous runs of True in ``valid`` (N,) bool as ``[(start, stop), ...]`` (stop exclusive)."""
    v = np.concatenate([[False], np.asarray(valid, dtype=bool), [False]])
    edges = np.flatnonzero(np.diff(v.astype(np.int8)))
    return list(zip(edges[0::2].tolist(), edges[1::2].tolist()))


def lowpass(x: np.ndarray, fs_hz: float, cutoff_hz: float, order: int = FILTER_ORDER) -> np.ndarray:
    """Zero-phase Butterworth low-pass of one gap-free series.

    ``x`` (N,) finite samples at ``fs_hz``; ``cutoff_hz`` must be below
    ``fs_hz/2`` (a cutoff at or above Nyquist returns ``x`` unchanged). The ends
    are extended by odd reflection over ``3 fs/cutoff`` samples (or as far as a
    short series allows) to keep edge transients small.
    Raises ``ValueError`` for a non-positive cutoff.
    """
    if not cutoff_hz > 0:
        raise ValueError(f"cutoff must be > 0 Hz, not {cutoff_hz}")
    x = np.asarray(x, dtype=np.float64)
    if cutoff_hz >= 0.5 * fs_hz or x.shape[0] < 2:
        return x.copy()
    sos = signal.butter(order, cutoff_hz, btype="low", fs=fs_hz, output="sos")
    # odd extension over ~3 time constants (scipy's default of 3*(2*sections+1) samples
    # is far shorter than the impulse response and leaves edge transients on ramps)
    padlen = min(max(3 * (2 * sos.shape[0] + 1), int(3 * fs_hz / cutoff_hz)), x.shape[0] - 1)
    return signal.sosfiltfilt(sos, x, padlen=padlen)


def lowpass_segments(x: np.ndarray, fs_hz: float, cutoff_hz: float, *, order: int = FILTER_ORDER) -> np.ndarray:
    """Apply :func:`lowpass` to each run of finite samples of ``x`` (N,); NaN stay NaN."""
    out = np.full(np.shape(x), np.nan)
    for a, b in segments(np.isfinite(x)):
        out[a:b] = lowpass(x[a:b], fs_hz, cutoff_hz, order)
    return out


def filter_to_grid(t_s: np.ndarray, x: np.ndarray, period_s: float, t_grid: np.ndarray,
                   cutoff_hz: float, *, derivative: bool = False):
    """Filter a source series per segment and interpolate it onto an output grid.

    ``t_s`` (n,) sorted times [s], ``x`` (n,) values (NaN = lost sample);
    segments break where more than ``MAX_FILL_SAMPLES`` consecutive samples
    are missing. Within a segment the series is resampled uniformly at
    ``period_s`` (lost samples linearly bridged), low-passed zero-phase and
    interpolated onto the ``t_grid`` points inside it; others stay NaN.

    With ``derivative=True`` returns ``(values, dxdt)``, both (len(t_grid),):
    ``dxdt`` [unit of x per s] is the time derivative *of the filtered series*
    (a cubic spline through the filtered uniform samples of each segment,
    differentiated and evaluated on the grid). Differentiation and the
    (linear, zero-phase) low-pass commute, so ``dxdt`` is the derivative of the
    signal passed through the same filter, with the same cutoff, segments and
    no phase lag: a correction ``m dV/dt`` built from it lines up with a force
    filtered by this function (inertia compensation, processing/pipeline.py).
    """
    out = np.full(t_grid.shape[0], np.nan)
    dout = np.full(t_grid.shape[0], np.nan) if derivative else None

    def ret():
        return (out, dout) if derivative else out

    if not period_s > 0:  # unknown period (too few samples): nothing to put on the grid
        return ret()
    ok = np.isfinite(x) & np.isfinite(t_s)
    t, v = t_s[ok], x[ok]
    if t.shape[0] < 2:
        return ret()
    brk = np.flatnonzero(np.diff(t) > (MAX_FILL_SAMPLES + 1.5) * period_s) + 1
    fs = 1.0 / period_s
    for a, b in zip(np.concatenate([[0], brk]), np.concatenate([brk, [t.shape[0]]])):
        if b - a < 2:
            continue
        n_u = int(math.floor((t[b - 1] - t[a]) / period_s)) + 1
        if n_u < 2:
            continue
        tu = t[a] + np.arange(n_u) * period_s
        xu = lowpass(np.interp(tu, t[a:b], v[a:b]), fs, cutoff_hz)
        lo = np.searchsorted(t_grid, tu[0], side="left")
        hi = np.searchsorted(t_grid, tu[-1], side="right")
        if hi > lo:
            out[lo:hi] = np.interp(t_grid[lo:hi], tu, xu)
            if derivative:
                if n_u >= 4:
                    dout[lo:hi] = CubicSpline(tu, xu).derivative()(t_grid[lo:hi])
                else:
                    dout[lo:hi] = np.interp(t_grid[lo:hi], tu, np.gradient(xu, tu))
    return ret()
