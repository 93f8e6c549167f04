"""Wheel force transducer: sample counters, lost frames, rotation to the hub frame.

The WFT sends three frames per sample (force, moment, angle), all carrying
the same 8-bit ``Counter`` (0..255, wrapping). This module

1. unwraps each message's counter into a sample index, using the host
   receive time to count whole wraps across long gaps
   (:func:`unwrap_counter`);
2. aligns the three messages' indices (same counter, nearest in time) and
   builds one table of samples, reporting lost frames
   (:func:`assemble_wft_samples`);
3. rotates the wheel-fixed forces into the hub frame with the wheel angle of
   the same sample (:func:`rotate_to_hub`, hardware.md "Frames and signs").

Source: ``docs`` of the WFT DBC (``dbc/wft.dbc``) and ``/work/shared/hardware.md``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from wheelsoil.daq.stats import counter_stride

__all__ = ["unwrap_counter", "rotate_to_hub", "angle_jumps", "frame_spikes", "WftSamples", "assemble_wft_samples", "GapReport",
           "rotation_ripple", "remove_ripple"]

#: A wheel-angle jump within one sample at least this large [rad] cannot be the wheel's motion (see
#: :func:`angle_jumps`): 0.5 deg more or less than the neighbouring samples' turn in 2 ms is an
#: angular acceleration of about 2000 rad/s^2, some 25 kN m on an 11.5 kg m^2 wheel.
ANGLE_JUMP_MIN_RAD = float(np.radians(0.5))
#: ... and at least this many robust standard deviations of the per-sample turn's scatter.
ANGLE_JUMP_SIGMA = 10.0
#: A transducer sample at least this many times its channel's noise off the mean of its two neighbours
#: (:func:`frame_spikes`) ...
SPIKE_SIGMA = 10.0
#: ... and at least this share of the channel's size (99th percentile of its magnitude) off is a spike:
#: 10 % of the load is about 1 kN on the vehicle's rear wheel, some 50 times its force noise.
SPIKE_MIN_REL = 0.10
#: ... and at least this many times the roughness of its neighbourhood without it.
SPIKE_ROUGH = 4.0
#: The wheel-angle-locked ripple (:func:`rotation_ripple`) is fitted where the wheel turns at least
#: this fast [rev/s] (a revolution then lasts 3.3 s at most, short against a run) ...
RIPPLE_MIN_REV_S = 0.3
#: ... and only over at least this many revolutions at that speed.
RIPPLE_MIN_REVOLUTIONS = 10.0
#: Its uncertainty is the scatter of the same fit on blocks of this many revolutions (at most
#: ``RIPPLE_MAX_BLOCKS`` blocks, at least 4); an order (cos and sin together) is taken out of the
#: forces only when it stands out of that scatter at this level (F test, 2 and blocks - 1 degrees of
#: freedom): a ripple found in the trend's leftovers is not subtracted.
RIPPLE_BLOCK_REVOLUTIONS = 5.0
RIPPLE_MAX_BLOCKS = 20
RIPPLE_ALPHA = 0.001


def unwrap_counter(timestamp_ns: np.ndarray, counter: np.ndarray, *, modulo: int = 256,
                   period_s: float | None = None, window: int = 64) -> tuple[np.ndarray, float, int]:
    """Unwrap a wrapping sample counter into a monotonic sample index.

    Parameters: ``timestamp_ns`` int64 (N,) host receive times (sorted);
    ``counter`` (N,) values in ``0..modulo-1`` (floats allowed, NaN not);
    ``period_s`` the nominal sample period (estimated as the median time step
    between frames whose counter advanced by one when None); ``window``
    frames on each side used to tell a lost-frame gap from a counter jump.

    Returns ``(index, period_s, jumps)``: ``index`` int64 (N,) starting at
    ``counter[0]``; a step of ``k`` between frames means ``k - 1`` lost
    samples (0 = repeated frame). The number of whole wraps in a step is
    chosen so the step is closest to ``dt / period_s``, so gaps longer than one
    wrap (0.512 s at 500 Hz) are counted correctly. A step that disagrees with
    the elapsed time is a lost-frame gap if the frames after it keep the
    time-vs-index line of the frames before it, and a *counter jump* (a
    corrupted counter, no time lost) if they keep it only with the step the
    clock says; jumps are replaced by the clock's step and counted in
    ``jumps``. Raises ``ValueError`` for fewer than 2 frames, no usable period, or a counter that keeps
    its value in most frames (not a per-sample counter: a DBC reading another field).
    """
    ts = np.asarray(timestamp_ns, dtype=np.int64)
    c = np.asarray(counter).astype(np.int64) % modulo
    if ts.shape[0] < 2:
        raise ValueError("need at least 2 frames to unwrap a counter")
    dt = np.diff(ts) * 1e-9
    d = np.diff(c) % modulo
    if d.size >= 16 and np.mean(d == 0) > 0.9:  # a sample counter advances with (nearly) every frame sent
        raise ValueError(f"the counter keeps its value in {100 * np.mean(d == 0):.0f} % of the frames while time "
                         "passes: not a per-sample counter (its bit position or length in the DBC?)")
    if period_s is None:
        if not np.any(d == 1):
            raise ValueError("counter never advances by one: cannot estimate the sample period")
        # elapsed time over counter advance in windows of frames: host timestamps of
        # bursty adapters (USB, UDP) put many consecutive frames microseconds apart and
        # the next burst tens of ms later, so a per-step median would be far too small.
        # A first estimate over 64-frame windows is biased by the burst quantisation
        # (20 ms bursts: ~6 %, enough to miscount a gap of several wraps), so it is
        # refined over windows of up to 1024 frames (~2 s at 500 Hz) that contain no
        # step long enough to hide a counter wrap.
        ct = np.concatenate([[0.0], np.cumsum(dt)])
        cd = np.concatenate([[0], np.cumsum(d)])

        def windowed(w, ok_steps=None):
            span_t, span_d = ct[w:] - ct[:-w], cd[w:] - cd[:-w]
            ok = (span_d > 0) & (span_d <= 2 * w)
            if ok_steps is not None:
                bad = np.concatenate([[0], np.cumsum(~ok_steps)])
                ok &= (bad[w:] - bad[:-w]) == 0
            return float(np.median(span_t[ok] / span_d[ok])) if ok.any() else None

        period_s = windowed(int(min(64, dt.shape[0])))
        if period_s is None:
            period_s = float(np.median(dt[d == 1]))
        elif period_s > 0:
            fine = windowed(int(min(1024, dt.shape[0])), ok_steps=dt < 0.25 * modulo * period_s)
            period_s = fine if fine is not None else period_s
        if not period_s > 0:
            raise ValueError("frames with consecutive counters share one timestamp: no sample period")
    expected = dt / period_s
    steps = d + modulo * np.round((expected - d) / modulo).astype(np.int64)
    clock = np.maximum(np.round(expected).astype(np.int64), 0)
    jumps = 0
    rel_t = (ts - ts[0]) * 1e-9
    # a counter that advances by exactly one lost nothing, whatever the host clock
    # says: a late delivery (USB/UDP burst, scheduling pause) is not a counter jump
    cands = np.flatnonzero((np.abs(steps - expected) > 1.5) & (steps != 1))
    for j, i in enumerate(cands):
        # frames a..i before the step (earlier steps already decided), i+1..b after it,
        # up to the frame before the next suspicious step
        nxt = cands[j + 1] if j + 1 < cands.size else ts.shape[0] - 1
        a, b = max(0, i - window), min(ts.shape[0] - 1, i + 1 + window, nxt)
        k_left = -np.cumsum(steps[a:i][::-1])[::-1]            # index of frames a..i-1 relative to frame i
        k_left = np.concatenate([k_left, [0]])                  # frame i
        k_right = np.cumsum(steps[i:b])                          # frames i+1..b
        r_left = float(np.median(rel_t[a:i + 1] - rel_t[i] - k_left * period_s))
        r_right = float(np.median(rel_t[i + 1:b + 1] - rel_t[i] - k_right * period_s))
        shift = r_right - r_left
        if abs(shift + (steps[i] - clock[i]) * period_s) < abs(shift):
            steps[i] = clock[i]
            jumps += 1
    # a small negative step is a frame delivered out of order: keep it, so the frames
    # after it stay on their own samples (clamping it to 0 shifted them all by one)
    steps = np.where(steps < -3, 0, steps)
    index = np.empty(ts.shape[0], dtype=np.int64)
    index[0] = c[0]
    np.cumsum(steps, out=index[1:])
    index[1:] += c[0]
    return index, period_s, jumps


def rotate_to_hub(fx_w: np.ndarray, fz_w: np.ndarray, angle_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotate wheel-fixed forces into the non-rotating hub frame.

    ``Fx = Fx_w cos a + Fz_w sin a``, ``Fz = -Fx_w sin a + Fz_w cos a`` with
    ``a`` the wheel angle of the same sample [rad] (hardware.md, "Frames and
    signs"; wft.dbc comment of ``WFT_RL_Force``). All arrays (N,) in N;
    returns ``(Fx, Fz)`` (N,): Fx > 0 drawbar pull, Fz > 0 vertical load.
    """
    ca, sa = np.cos(angle_rad), np.sin(angle_rad)
    return fx_w * ca + fz_w * sa, -fx_w * sa + fz_w * ca


def angle_jumps(angle_rad: np.ndarray, *, half_window: int = 10, max_gap: int = 5
                ) -> tuple[np.ndarray, list[tuple[int, float]]]:
    """Find and undo jumps of the transducer's wheel angle: an encoder that loses or gains counts.

    The wheel turns smoothly: from one 2 ms sample to the next its turn changes by far less than a
    degree (:data:`ANGLE_JUMP_MIN_RAD`).  Each turn between valid samples up to ``max_gap`` samples
    apart is compared with the local turn per sample (the median over ``half_window`` turns on
    either side) times the gap; a departure of at least :data:`ANGLE_JUMP_MIN_RAD` and
    :data:`ANGLE_JUMP_SIGMA` robust standard deviations (1.4826 x the median absolute departure) is a
    jump of the reading, not of the wheel.  Every later angle then carries it, and the hub forces
    rotated with it (hardware.md, "Frames and signs") are off by ``W sin(jump)`` in Fx: hundreds of
    newtons for a degree or two.  The jumps are subtracted from every later sample (an encoder that
    re-synchronises at its index pulse jumps back, and that jump is undone too).

    ``angle_rad`` (M,) wheel angle per sample index [rad], wrapping, NaN where lost.  Returns
    ``(corrected (M,) [rad], [(row, jump_rad), ...])``: ``row`` the first sample carrying the jump.
    Nothing is changed when fewer than ``2 half_window + 1`` turns are valid.  Source: hardware.md
    (the angle's resolution, 0.0055 deg, and rate, 500 Hz); a robust outlier test on the increments.
    """
    a = np.asarray(angle_rad, dtype=float)
    rows = np.flatnonzero(np.isfinite(a))
    if rows.size < 2 * half_window + 2:
        return a, []
    gap = np.diff(rows)
    turn = np.angle(np.exp(1j * np.diff(a[rows])))  # wrapped to (-pi, pi]
    rate = np.where(gap <= max_gap, turn / gap, np.nan)  # per sample
    w = 2 * half_window + 1
    pad = np.pad(rate, half_window, constant_values=np.nan)
    with warnings.catch_warnings():  # a window of lost samples has no median: NaN, as wanted
        warnings.simplefilter("ignore", RuntimeWarning)
        local = np.nanmedian(np.lib.stride_tricks.sliding_window_view(pad, w), axis=1)
    dev = np.where(gap <= max_gap, turn - gap * local, np.nan)
    ok = np.isfinite(dev)
    if ok.sum() < w:
        return a, []
    sigma = 1.4826 * float(np.median(np.abs(dev[ok])))
    hit = np.flatnonzero(ok & (np.abs(np.nan_to_num(dev)) >= max(ANGLE_JUMP_MIN_RAD, ANGLE_JUMP_SIGMA * sigma)))
    if hit.size == 0:
        return a, []
    jumps = [(int(rows[i + 1]), float(dev[i])) for i in hit]
    shift = np.zeros(a.shape)
    for row, j in jumps:
        shift[row:] += j
    return a - shift, jumps


def _departures(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Each sample less the mean of its two neighbours (NaN where it or one of them is lost), the level
    from which that departure is a lone spike (:func:`frame_spikes`), per sample (inf where the
    neighbourhood is lost or too few samples are valid), and the channel's noise-and-size part of it."""
    x = np.asarray(values, dtype=float)
    m = x.size
    dev = np.full(m, np.nan)
    limit = np.full(m, np.inf)
    if m < 7:
        return dev, limit, np.inf
    dev[1:-1] = x[1:-1] - 0.5 * (x[:-2] + x[2:])
    d2 = np.diff(x, 2)  # d2[k] centred on sample k + 1
    good = np.isfinite(d2)
    if good.sum() < 100:
        return dev, limit, np.inf
    sigma = 1.4826 * float(np.median(np.abs(d2[good]))) / np.sqrt(6.0)  # white noise: var(d2) = 6 var
    size = float(np.percentile(np.abs(x[np.isfinite(x)]), 99))
    # the neighbourhood's own roughness, sample i left out: its two neighbours' difference and the steps
    # leading to them (a fast oscillation, whose peaks are single samples too, is steep there; the
    # samples around a glitch lie level or on a gentle slope)
    rough = np.full(m, np.inf)
    step = np.abs(np.diff(x))  # step[k] = |x[k+1] - x[k]|
    rough[2:-2] = np.fmax(np.abs(x[3:-1] - x[1:-3]), np.fmax(step[:-3], step[3:]))
    rough[~np.isfinite(rough)] = np.inf
    base = max(SPIKE_SIGMA * sigma, SPIKE_MIN_REL * size)
    limit = np.maximum(base, SPIKE_ROUGH * rough) if base > 0 else limit
    return dev, limit, base if base > 0 else np.inf


def frame_spikes(frames: dict[str, dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Lone samples of a transducer frame far off their neighbours: a glitch of that frame.

    The wheel assembly cannot change what it transmits within one sample by much of the load and back:
    its mass, the tyre and the transducer's own bandwidth smooth it, and what does change that fast (a
    driveline shock, the wheel breaking loose) moves the forces and the moment together, which travel in
    different frames.  A frame corrupted on the bus or an EMI burst in one bridge's amplifier moves one
    sample of one frame.  A channel's sample is a spike when it departs from the mean of its two
    neighbours by at least :data:`SPIKE_SIGMA` times the channel's noise (from the median absolute second
    difference), :data:`SPIKE_MIN_REL` of its size (99th percentile of its magnitude) and
    :data:`SPIKE_ROUGH` times the roughness of its neighbourhood without it (a channel oscillating from
    sample to sample is not smooth enough to tell a glitch in), and it is a spike of its frame when no
    channel of another frame departs by a quarter of its noise-and-size level at that sample.  Left in, a 2-5 kN
    single-frame spike passes the 5 Hz low-pass as a 25-86 N bump in the force for half a second (an
    independent generator's EMI spikes).

    ``frames``: frame (message) name -> {channel name: (M,) values per sample index [N or N m], NaN where
    lost}, at least one channel per frame, every array of one length M.  Returns frame name -> bool mask
    (M,), True where that frame is a spike; never raises.  A channel with fewer than 100 valid second
    differences finds none.  Source: a robust outlier
    test on departures from the neighbours (Hampel 1974; Pearson et al. 2016), per frame.
    """
    out, loud = {}, {}
    for name, chans in frames.items():
        hit = np.zeros(len(next(iter(chans.values()))), dtype=bool)
        near = hit.copy()
        for v in chans.values():
            dev, limit, base = _departures(v)
            a = np.abs(np.nan_to_num(dev))
            hit |= a >= limit
            near |= a >= base / 4
        out[name], loud[name] = hit, near
    for name in out:
        for other, near in loud.items():
            if other != name:
                out[name] = out[name] & ~near
    return out


def rotation_ripple(fx: np.ndarray, fz: np.ndarray, angle_rad: np.ndarray, t_s: np.ndarray, *,
                    my: np.ndarray | None = None, min_rev_s: float = RIPPLE_MIN_REV_S,
                    min_revolutions: float = RIPPLE_MIN_REVOLUTIONS) -> dict | None:
    """The hub forces' (and hub moment's) components locked to the wheel's angle, once and twice
    per revolution.

    A transducer that turns with the wheel and reads its two in-plane bridges correctly gives hub
    forces with no part that follows the wheel angle (hardware.md, "Frames and signs"); a gain
    mismatch g between ``Fx_w`` and ``Fz_w`` leaves about ``g W / 2`` twice per revolution, an
    offset o in one of them ``o`` once per revolution (so does an out-of-round tyre, usually far
    less), and bridge crosstalk into ``My`` a part of the moment that follows the angle too. No
    steady wheel-soil model has such a part. Each channel less its centred moving mean over one
    revolution (a harmonic of the wheel angle averages out of it; the window follows the wheel's
    speed) is fitted by least squares with ``cos a, sin a, cos 2a, sin 2a`` on the samples where
    the wheel turns at ``min_rev_s`` [rev/s] or faster (order analysis: harmonic regression on
    the angle of rotation).

    ``fx``, ``fz`` (N,) hub forces [N], ``my`` (N,) or None the hub moment [N m] (NaN: lost),
    ``angle_rad`` (N,) the wheel angle of the same samples, ``t_s`` (N,) their times [s],
    uniformly sampled. Returns ``{"fx_1x_n", "fx_2x_n", "fz_1x_n", "fz_2x_n"[, "my_1x_nm",
    "my_2x_nm"], "samples", "revolutions", "coef"}`` (amplitudes; ``coef`` channel -> the four
    coefficients to take out with :func:`remove_ripple`, an order set to 0 where it does not stand
    out of the scatter between blocks of revolutions, ``RIPPLE_ALPHA``) or None with fewer than
    ``min_revolutions`` revolutions turned at that speed. Raises nothing.
    """
    ok = np.isfinite(fx) & np.isfinite(fz) & np.isfinite(angle_rad) & np.isfinite(t_s)
    if ok.sum() < 100:
        return None
    dt = float(np.median(np.diff(t_s[ok])))
    turn = np.interp(t_s, t_s[ok], np.unwrap(angle_rad[ok]) / (2 * np.pi))  # revolutions turned
    step = np.diff(turn, prepend=turn[0])
    # each sample weighs the angle it turns through: a mean over a revolution is then the mean over the
    # angle, from which every harmonic of the angle drops out however the speed varies within it
    wgt = np.where(ok, np.clip(step, 0.0, None), 0.0)
    rate = np.convolve(step, np.ones(max(int(round(1.0 / dt)), 1)), "same")  # revolutions per second
    mono = np.maximum.accumulate(turn)
    lo = np.searchsorted(mono, mono - 0.5, side="left")
    hi = np.searchsorted(mono, mono + 0.5, side="right")
    use = ok & (rate >= min_rev_s) & (mono - 0.5 >= mono[0]) & (mono + 0.5 <= mono[-1]) & (wgt > 0)
    revs = float(wgt[use].sum())
    if revs < min_revolutions:
        return None
    lo, hi = lo[use], hi[use]
    cw = np.concatenate([[0.0], np.cumsum(wgt)])
    a = angle_rad[use]
    X = np.column_stack([np.cos(a), np.sin(a), np.cos(2 * a), np.sin(2 * a)])
    sw = np.sqrt(wgt[use])
    out = {"samples": int(use.sum()), "revolutions": revs, "coef": {}}
    chans = [("fx", fx, "n"), ("fz", fz, "n")] + ([("my", my, "nm")] if my is not None else [])
    for name, y, unit in chans:
        good = np.isfinite(y)
        wy = np.where(good, wgt, 0.0)
        csum = np.concatenate([[0.0], np.cumsum(wy * np.where(good, y, 0.0))])
        cg = np.concatenate([[0.0], np.cumsum(wy)])
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = (csum[hi] - csum[lo]) / (cg[hi] - cg[lo])
        r = y[use] - mean
        fin = np.isfinite(r) & ((cg[hi] - cg[lo]) >= 0.8 * (cw[hi] - cw[lo]))  # the revolution mostly seen
        if fin.sum() < 100:
            continue
        Xw, rw = X[fin] * sw[fin, None], r[fin] * sw[fin]
        c = np.linalg.lstsq(Xw, rw, rcond=None)[0]
        # the same fit on blocks of equal revolutions: their scatter is the estimate's uncertainty,
        # what the trend leaves in a revolution included (a residual-based error would miss it)
        cum = np.cumsum(wgt[use][fin])
        nb = int(min(RIPPLE_MAX_BLOCKS, cum[-1] // RIPPLE_BLOCK_REVOLUTIONS))
        keep = np.zeros(4, dtype=bool)
        if nb >= 4:
            blk = np.minimum((cum / cum[-1] * nb).astype(np.int64), nb - 1)
            cb = np.array([np.linalg.lstsq(Xw[blk == b], rw[blk == b], rcond=None)[0] for b in range(nb)])
            se = cb.std(axis=0, ddof=1) / np.sqrt(nb)
            crit = 2.0 * stats.f.ppf(1.0 - RIPPLE_ALPHA, 2, nb - 1)
            for o in (0, 2):  # each order: the cos and sin parts together
                with np.errstate(divide="ignore", invalid="ignore"):
                    keep[o:o + 2] = np.sum((c[o:o + 2] / se[o:o + 2]) ** 2) > crit
        out["coef"][name] = [float(v) if k else 0.0 for v, k in zip(c, keep)]
        out[f"{name}_1x_{unit}"] = float(np.hypot(c[0], c[1]))
        out[f"{name}_2x_{unit}"] = float(np.hypot(c[2], c[3]))
    return out if "fx" in out["coef"] and "fz" in out["coef"] else None


def remove_ripple(y: np.ndarray, angle_rad: np.ndarray, coef) -> np.ndarray:
    """``y`` less its part locked to the wheel angle: ``y - (c0 cos a + c1 sin a + c2 cos 2a +
    c3 sin 2a)`` with ``coef`` the four coefficients :func:`rotation_ripple` fitted (same unit as
    ``y``). ``y``, ``angle_rad`` (N,); a NaN angle leaves the sample as it is. Returns (N,).
    """
    a = np.nan_to_num(angle_rad)
    h = coef[0] * np.cos(a) + coef[1] * np.sin(a) + coef[2] * np.cos(2 * a) + coef[3] * np.sin(2 * a)
    return y - np.where(np.isfinite(angle_rad), h, 0.0)


@dataclass
class GapReport:
    """Lost WFT samples: ``lost`` count, ``gaps`` list of (t_start_ns, t_end_ns, n_lost),
    ``repeated`` frames, counter ``jumps`` (no time lost, see :func:`unwrap_counter`)."""

    lost: int = 0
    gaps: list[tuple[int, int, int]] = field(default_factory=list)
    repeated: int = 0
    jumps: int = 0


@dataclass
class WftSamples:
    """One row per WFT sample index (from the first to the last sample seen).

    ``index`` int64 (M,) unwrapped sample index; ``timestamp_ns`` int64 (M,)
    sample times on the host clock, from the transducer's regular period
    with a slowly varying offset fitted to the frames' host times (see
    :func:`_smooth_sample_times`; missing samples included); ``complete`` bool (M,) all three frames present;
    ``columns`` name -> float64 (M,) (NaN where the frame was lost);
    ``period_s`` the period of the samples sent; ``reports`` message name -> :class:`GapReport`;
    ``stride`` the transducer's samples per sample sent (:func:`counter_stride`: 2 for an output
    decimated to every second sample; ``index`` then counts the samples sent).
    """

    index: np.ndarray
    timestamp_ns: np.ndarray
    complete: np.ndarray
    columns: dict[str, np.ndarray]
    period_s: float
    reports: dict[str, GapReport]
    stride: int = 1


def _gap_report(ts: np.ndarray, idx: np.ndarray) -> GapReport:
    steps = np.diff(idx)
    rep = GapReport(repeated=int(np.count_nonzero(steps == 0)))
    where = np.flatnonzero(steps > 1)
    # samples never seen between the first and the last (out-of-order frames fill their gap)
    rep.lost = int(idx.max() - idx.min() + 1 - np.unique(idx).size) if idx.size else 0
    rep.gaps = [(int(ts[i]), int(ts[i + 1]), int(steps[i] - 1)) for i in where]
    return rep


def assemble_wft_samples(streams: dict[str, tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]],
                         *, reference: str, modulo: int = 256) -> WftSamples:
    """Match the frames of one WFT sample across messages by counter and time.

    ``streams``: message name -> ``(timestamp_ns (n,), counter (n,),
    {column: (n,) values})``; ``reference`` the message whose counter defines
    the sample grid (the force message). Each other message's unwrapped index
    is shifted by the whole number of wraps that puts its frames on the
    reference frames nearest in time with the same counter value.

    A counter that advances by ``k`` > 1 per frame (:func:`counter_stride` of the reference: a
    decimated output) is divided by ``k`` in every message first, so that a lost frame is a step of
    2 and the period that of the samples sent.

    Returns :class:`WftSamples` covering every index from the first to the
    last sample of any message. Raises ``ValueError`` if the reference
    message has fewer than 2 frames, or its counter's stride does not divide ``modulo``.
    """
    ts_ref, c_ref, _ = streams[reference]
    order = np.argsort(ts_ref, kind="stable")
    stride = counter_stride(np.asarray(c_ref)[order], modulo=modulo)
    if stride > 1:
        streams = {k: (ts, np.asarray(c).astype(np.int64) % modulo // stride, cols)
                   for k, (ts, c, cols) in streams.items()}
        modulo //= stride
        ts_ref, c_ref, _ = streams[reference]
    try:
        idx_ref, period, jumps_ref = unwrap_counter(ts_ref[order], c_ref[order], modulo=modulo)
    except ValueError as exc:
        raise ValueError(f"{reference}'s counter: {exc}") from None
    jumps = {reference: jumps_ref}
    t_ref = ts_ref[order]
    unwrapped: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {reference: (t_ref, idx_ref, order)}
    for name, (ts, c, _) in streams.items():
        if name == reference or ts.shape[0] == 0:
            continue
        o = np.argsort(ts, kind="stable")
        t = ts[o]
        if t.shape[0] >= 2:
            try:
                idx, _, jumps[name] = unwrap_counter(t, c[o], modulo=modulo, period_s=period)
            except ValueError as exc:
                raise ValueError(f"{name}'s counter: {exc}") from None
        else:
            idx = np.asarray(c[o], dtype=np.int64) % modulo
            jumps[name] = 0
        # reference index expected at these times (interpolated) -> whole wraps
        k_at = np.interp(t.astype(np.float64), t_ref.astype(np.float64), idx_ref.astype(np.float64))
        shift = int(np.median(np.round((k_at - idx) / modulo))) * modulo
        unwrapped[name] = (t, idx + shift, o)

    lo = min(int(u[1][0]) for u in unwrapped.values())
    hi = max(int(u[1][-1]) for u in unwrapped.values())
    m = hi - lo + 1
    index = np.arange(lo, hi + 1, dtype=np.int64)
    t_sum = np.zeros(m)
    t_cnt = np.zeros(m)
    present = np.ones(m, dtype=bool)
    columns: dict[str, np.ndarray] = {}
    reports: dict[str, GapReport] = {}
    for name, (t, idx, o) in unwrapped.items():
        rows = idx - lo
        keep = np.ones(rows.shape[0], dtype=bool)
        # repeated counter values: keep the first frame; an out-of-order frame whose
        # sample was already passed is dropped (its neighbours keep their rows)
        keep[1:] = rows[1:] > np.maximum.accumulate(rows)[:-1]
        here = np.zeros(m, dtype=bool)
        here[rows[keep]] = True
        present &= here
        t_sum[rows[keep]] += t[keep] - t_ref[0]
        t_cnt[rows[keep]] += 1
        for col, values in streams[name][2].items():
            arr = np.full(m, np.nan)
            arr[rows[keep]] = np.asarray(values)[o][keep]
            columns[col] = arr
        reports[name] = _gap_report(t, idx)
        reports[name].jumps = jumps[name]
        # frames missing at the ends of this stream relative to the others
        reports[name].lost += int(idx[0] - lo) + int(hi - idx[-1])
    have = t_cnt > 0
    mean_t = t_sum[have] / t_cnt[have]
    timestamp_ns = t_ref[0] + np.round(_smooth_sample_times(index, have, mean_t, period)).astype(np.int64)
    return WftSamples(index, timestamp_ns, present, columns, period, reports, stride)


def _smooth_sample_times(index: np.ndarray, have: np.ndarray, mean_t_ns: np.ndarray, period_s: float,
                         block: int = 500) -> np.ndarray:
    """Sample times [ns, relative] from the transducer's regular clock, not the host's jitter.

    The WFT samples at a fixed period, so ``t = offset(K) + K * period`` with an
    offset that changes only slowly (clock drift). The offset is the median of
    ``t_host - K * period`` over blocks of ``block`` samples (1 s at 500 Hz),
    interpolated linearly between block centres: host receive jitter and
    bursty delivery (USB/UDP adapters) do not move the sample times.
    ``index`` (M,), ``have`` (M,) bool samples with frames, ``mean_t_ns``
    their mean frame time; returns float (M,).
    """
    k = index[have].astype(np.float64)
    resid = mean_t_ns - k * period_s * 1e9
    blk = ((index[have] - index[0]) // block).astype(np.int64)
    starts = np.flatnonzero(np.r_[True, np.diff(blk) != 0])
    ends = np.r_[starts[1:], blk.size]
    centres = np.array([k[a:b].mean() for a, b in zip(starts, ends)])
    offsets = np.array([np.median(resid[a:b]) for a, b in zip(starts, ends)])
    kk = index.astype(np.float64)
    if centres.size == 1:
        return offsets[0] + kk * period_s * 1e9
    # linear inside, extrapolated with the end blocks' slope outside the centres
    off = np.interp(kk, centres, offsets)
    lo, hi = kk < centres[0], kk > centres[-1]
    off[lo] = offsets[0] + (kk[lo] - centres[0]) * (offsets[1] - offsets[0]) / (centres[1] - centres[0])
    off[hi] = offsets[-1] + (kk[hi] - centres[-1]) * (offsets[-1] - offsets[-2]) / (centres[-1] - centres[-2])
    return off + kk * period_s * 1e9
