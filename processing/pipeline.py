"""From an MCAP recording to the signals of the wheel-soil fit: :func:`process_recording`.

Steps (each in its own module):

1. decode the frames the vehicle configuration names, streaming, with the
   vectorised decoder (:mod:`.decode`);
2. WFT: unwrap the sample counters, match the force/moment/angle frames of
   one sample, report lost frames, rotate to the hub frame (:mod:`.wft`);
   lost runs of at most ``MAX_FILL_SAMPLES`` samples are interpolated,
   longer ones split the data into segments;
3. clocks: host->GPS time mapping; the wheel-speed module's lag behind the
   transducer's clock, from the WFT's wheel angle (:func:`_wheel_speed_lag`;
   removed from the wheel speeds' times when determined and over 5 ms, so
   slip belongs to the moment of the forces; the module's scale against the
   same angle, corrected beyond ``WHEEL_SCALE_TOL``, :func:`_wheel_speed_scale`;
   a delay that grows as the wheel
   slows, per reading; from the fronts' too: a constant one when that makes
   the GNSS latency against them agree better with the slip-traction
   estimate, a per-tooth one unless their own delay against the GNSS speed
   does not grow as they slow, :func:`_fronts_pitch`); and the GNSS latency (:mod:`.timesync`)
   from up to three estimators: the free-rolling front wheels' r*omega (or,
   when none is logged or the 4x4 drives them, the measured wheel where it
   transmits no torque: coasting, another axle braking), the measured wheel's
   slip-traction consistency (T/(rW) a single function of slip: needs no
   free-rolling wheel) and the vehicle dynamics (GNSS dV/dt against the
   measured Fx); front wheels that turn with the measured one or disagree
   with the traction estimate are driven and not used; the choice, its total
   standard error and a ``reliable`` flag go to ``quality["latency"]``
   (:func:`_choose_latency`), an unreliable one is applied only when best
   supported and is stated in the warnings; removed from the GNSS timestamps;
4. per source and per contiguous segment: uniform resampling at the source's
   own rate, zero-phase Butterworth low-pass (:mod:`.filters`), linear
   interpolation onto the output grid (``rate_hz``, from the first frame);
5. inertia compensation: the WFT measures what the wheel assembly outboard
   of it transmits, ``Fx = Dp - m_w dV/dt``, ``My = T + I_w domega/dt``
   (hardware.md), so ``Dp = Fx + m_w dV/dt`` and ``T = My - I_w domega/dt``
   with ``m_w``, ``I_w`` from the vehicle configuration; dV/dt and domega/dt
   are the derivatives of the filtered V and omega (same zero-phase filter,
   same cutoff, same segments, :func:`.filters.filter_to_grid`), so the
   correction has the same response as the filtered forces (on by default);
6. slip (Eq. 6) with the wheel radius of the configuration or the one given
   (the radius the fit then uses), phase, cycle id, ``valid`` (:mod:`.slip`);
   samples where the wheel speed oscillates faster than the low-pass resolves
   (the slip's unresolved spread above ``UNSTEADY_SLIP_SD``: stick-slip, wheel
   hop, a driveline oscillating) are not valid (:func:`unresolved_slip_sd`).

Every problem met on the way is appended to ``ProcessResult.warnings`` with
what is missing and what was still computed; nothing silently turns into
numbers.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from .decode import DecodedMessage, Decoder, decode_batches, frame_key
from .filters import DEFAULT_CUTOFF_HZ, MAX_FILL_SAMPLES, filter_to_grid, segments
from .slip import PHASES, accel_cycles, classify_phases, slip_ratio
from .timebase import (MAX_GRID_ROWS, cycle_loss, find_clock_steps, find_time_outliers, robust_period,
                       split_joined_parts)
from .timesync import (CLOCK_DISTINCT_RATIO, CLOCK_GRID_S, CLOCK_MIN_CORR, CLOCK_PEAK_SEPARATION_S, TOOTH_LAG_MIN_Z,
                       LatencyEstimate, ToothLag, estimate_clock_offset, estimate_latency, estimate_latency_traction,
                       estimate_tooth_lag, fit_gps_time_mapping)
from .wft import angle_jumps, assemble_wft_samples, frame_spikes, remove_ripple, rotate_to_hub, rotation_ripple

__all__ = ["ProcessResult", "process_recording", "COLUMNS", "MAX_FILL_SAMPLES"]

#: The columns of ``ProcessResult.signals``, in order (docs/architecture.md).
COLUMNS = ("t_s", "slip", "load_n", "drawbar_pull_n", "torque_nm", "speed_mps", "omega_radps",
           "phase", "valid", "distance_m", "fx_n", "my_nm")
#: Plausible wheel radius [m] for ``wheel_radius_m`` (as ``daq.config.VEHICLE_RANGES``).
RADIUS_RANGE_M = (0.05, 2.0)
#: Plausible wheel widths [m] (a testbed's 2 cm wheel to twin tyres).
WIDTH_RANGE_M = (0.02, 2.0)
#: r*omega below this [m/s] leaves the slip undefined (NaN).
MIN_WHEEL_SPEED_MPS = 0.1
#: The slip's spread within one filter window that the low-pass does not resolve (:func:`unresolved_slip_sd`)
#: above which a sample is not valid: three quarters of the fit's slip resolution (a cell spans a slip bin about
#: 0.067 wide, ``wheelsoil.model.data.N_SLIP_BINS``); there the filtered forces average over slips the cells do
#: not see, and the slip from the filtered wheel speed is biased by about sd^2 / (1 - s).
UNSTEADY_SLIP_SD = 0.05
#: WFT Status bits that invalidate a sample (overload, bridge fault, encoder fault).
WFT_STATUS_BAD = 0x07
#: Reference speed deceleration [m/s^2] beyond which front wheels may skid (not used for latency).
LATENCY_MAX_DECEL_MPS2 = 0.3
#: Low-pass cutoff [Hz] of the reference speed used for the latency estimate (fixed, so the
#: estimate does not depend on --cutoff/--rate).
LATENCY_REF_CUTOFF_HZ = 5.0
#: |T| [N m] under which the measured wheel counts as free rolling (latency fallback).
FREE_ROLLING_TORQUE_NM = 150.0
#: The measured wheel serves as the latency reference only this long [s] on either side of a sample
#: after and before any torque above FREE_ROLLING_TORQUE_NM: a wheel passing through zero torque
#: between driving and braking is changing its slip fast, not rolling freely, and the 5 Hz zero-phase
#: filter of the reference (LATENCY_REF_CUTOFF_HZ) spreads such a change over about +-0.2 s.
FREE_ROLLING_HOLD_S = 0.5
#: A component of the hub forces locked to the wheel angle (once or twice per revolution) at or above
#: this fraction of the mean load is reported as a calibration fault: a 2x ripple of 3 % is a 6 %
#: gain mismatch of the rotating bridges; a tyre's radial force variation is usually under 1.5 %.
WFT_RIPPLE_REL = 0.03
#: A GNSS velocity frame whose receiver accuracy figure (the message's ``Accuracy_*`` signal, in the
#: receiver's own unit) is at least this many times its median over the run is a degraded solution
#: (too few satellites, RTK lost, the INS coasting on its own integration): its velocity is four
#: times less certain than the run's typical one, and an INS integrating through a GNSS outage
#: drifts while its Validity flag still says 1.  Such frames are left out as lost, said in a warning.
GNSS_ACCURACY_DEGRADED = 4.0
#: The GNSS speed on a grade: the receiver's 2D speed and the INS's forward velocity are horizontal
#: (the DBC's comments), while slip (Eq. 6) needs the speed along the ground the wheel rolls on,
#: V_h / cos(grade). The 3D speed over the 2D one is 1 / cos(grade); it is taken where the 2D speed
#: is at least GRADE_MIN_SPEED_MPS (the vertical velocity's noise sigma_z adds sigma_z^2 / (2 V^2) to
#: the ratio: 2e-4 at 0.02 m/s and 1 m/s), as a running median over GRADE_WINDOW_S, and applied only
#: when it reaches GRADE_MIN_RATIO somewhere (a 10 % grade; below it slip moves by less than 0.005,
#: and three times that noise, 1.8e-3 at 1 m/s, stays under it).
GRADE_MIN_SPEED_MPS = 1.0
GRADE_WINDOW_S = 2.0
GRADE_MIN_RATIO = 1.005
#: GNSS latency search range [s] (hardware.md: typically 20-200 ms); an estimate within 4 ms of
#: either end is an edge hit (unreliable).
LATENCY_MAX_S = 0.5
#: The receiver latency hardware.md calls typical [s]: it breaks a disagreement between the slip-traction
#: and dynamics estimates when only the dynamics one lies within it (:func:`_choose_latency`).
LATENCY_TYPICAL_S = (0.02, 0.2)
#: Lower end [s] of the search for the wheel-reference and slip-traction estimates: they measure
#: the GNSS speed's delay *relative to the wheel-speed readings*, which is what slip (Eq. 6) needs,
#: and a wheel-speed module can itself read late (a tone wheel reporting its last tooth period:
#: ~30 ms at 4 rad/s with 48 teeth, more at walking pace), so a short GNSS latency is negative
#: relative to it. An independent generator's towed runs (GNSS 25-48 ms, module ~30-60 ms) hit the
#: old lower end 0 and got no estimate, or a wrong slip-traction one. The dynamics estimate (GNSS
#: against the transducer's own clock) keeps 0.
LATENCY_MIN_S = -0.1
#: The wheel-speed module's lag behind the transducer's clock (:func:`_wheel_speed_lag`) is removed
#: from the wheel speeds' timestamps when it is determined to this standard error [s] ...
WSS_LAG_SE_S = 0.005
#: ... and at least this large [s]: half the 100 Hz module's frame period (hardware.md), under which a
#: lag is within the reading's own time resolution (recordings without one stay as they were) ...
WSS_LAG_MIN_S = 0.005
#: ... and the module's speed matches the angle's derivative within this gain (the same wheel).
WSS_LAG_GAIN_TOL = 0.05
#: Search range [s] of that lag (negative: the transducer's frames arrive later than the module's).
WSS_LAG_RANGE_S = (-0.1, 0.3)
#: Wheel load [N] below which the traction coefficient T/(rW) is not formed (wheel lifted).
LATENCY_MIN_LOAD_N = 500.0
#: Highest output rate [Hz] processing resamples to.
MAX_RATE_HZ = 1000.0
#: Lowest zero-phase low-pass cutoff [Hz] processing takes: 0.1 Hz averages over ~10 s, a whole accelerate cycle.
MIN_CUTOFF_HZ = 0.1
#: Systematic (model) uncertainty [s] of each latency estimator, added in quadrature to its
#: statistical standard error: the wheel reference is exact for a free-rolling wheel; the
#: slip-traction estimate is biased by up to ~15 ms where the torque is not a function of slip
#: and load alone (load transfer, hidden effects), the dynamics one by ~+15..25 ms (the measured
#: wheel's Fx only stands for the sum over the wheels); benchmarks/bench_latency.py measures them.
LATENCY_SYSTEMATIC_S = {"wheel_reference": 0.0, "traction": 0.015, "dynamics": 0.025,
                        # the measured wheel coasting: its slip at zero torque follows the load
                        # transfer of a decelerating vehicle a little (5 runs of an independent
                        # generator with coasting rear wheels: errors -9.6 .. +5.7 ms)
                        "measured_wheel": 0.010}
#: A wheel reference whose own fit shows it rolling freely: GNSS V = a r*omega + b with |a - 1| at
#: most this (a free tyre's effective rolling radius within 5 % of the configured one) ...
FREE_ROLLING_GAIN_TOL = 0.05
#: ... and a residual RMS at most this fraction of the RMS GNSS speed (a driven wheel in a slip
#: sweep, r*omega = V/(1 - s), leaves tens of per cent): then a slip-traction estimate that
#: disagrees is the one that fails (the torque is not a static function of slip and load there),
#: provided the wheel reference is itself precise (:data:`LATENCY_RELIABLE_SE_S`): fronts braked now
#: and then while the rears hold a slip (an independent generator's staircases) still fit with a
#: small residual overall, but their lag is poorly determined (300 +- 32 ms for a true 151 ms), and
#: such an estimate is no ground to throw out a precise slip-traction one.
FREE_ROLLING_RESID_REL = 0.05
#: Two estimates agree when they differ by at most this many combined (total) standard errors.
LATENCY_AGREE_SIGMAS = 2.0
#: A latency is reliable only with a total standard error at most this [s] (the +-20 ms target).
LATENCY_RELIABLE_SE_S = 0.015


@dataclass
class ProcessResult:
    """Output of :func:`process_recording`.

    ``signals``: DataFrame with exactly :data:`COLUMNS` (``t_s`` s since the
    first frame, slip [-], load_n W [N], drawbar_pull_n Dp [N], torque_nm T
    [N m], speed_mps V [m/s], omega_radps [rad/s], phase str, valid bool);
    ``gnss_latency_s`` / ``gnss_latency_stderr_s`` (None if not estimated);
    ``gps_time_mapping`` dict (see :func:`.timesync.fit_gps_time_mapping`) or
    None; ``lost_frames`` message -> dict(lost, gaps, longest_gap_s, received,
    method); ``warnings`` list of sentences; ``cycle`` int64 (N,)
    accelerate-cycle id (-1 outside); plus ``t0_ns`` (host time of the first
    frame processed, outliers set aside), ``rate_hz``, ``cutoff_hz``, ``wheel_radius_m`` (the radius slip was
    computed with: the ``wheel_radius_m`` argument, else the vehicle
    configuration's) and ``wheel_radius_source``, ``wheel_width_m``,
    ``latency_reference``.

    Signals also carry ``distance_m`` (travelled distance, integral of V from
    the first GNSS sample [m], NaN where V is), ``fx_n`` and ``my_nm`` (the
    WFT's Fx [N] and My [N m], filtered, before the inertia compensation);
    ``drawbar_pull_n = fx_n + m_w dV/dt`` and ``torque_nm = my_nm - I_w
    domega/dt`` when the compensation is applied.

    ``inertia`` dict: ``applied`` bool, ``wheel_mass_kg``, ``wheel_inertia_kgm2``,
    ``max_abs_force_n`` / ``max_abs_torque_nm`` (largest correction applied, None
    if not applied), ``method``, ``source``.
    ``excluded`` list of dicts ``{t0_s, t1_s, reason}`` (+ details): spans of
    data set aside (outlier timestamps, long gaps, the gap between joined parts,
    damaged parts of the file as the reader reports them; ``t0_s``/``t1_s`` None
    when the time is unknown).
    ``quality`` dict: frames with outlier timestamps, non-monotonic parts, lost
    frames per message (None = unknown), grid size, and ``quality["latency"]``:
    ``estimate_s`` (applied, None if none), ``stderr_s`` (total: statistical and
    systematic), ``method`` (``wheel_reference`` | ``traction`` |
    ``traction+dynamics`` | ``wheel_reference+dynamics`` | None), ``reliable`` bool (False: slip and what is built
    on it are less certain), ``reasons`` (why not reliable), ``fronts_driven``,
    ``candidates`` {name: {estimate_s, stderr_s, stderr_stat_s, systematic_s,
    usable, note, n, method}}, ``search_range_s`` (see :func:`_choose_latency`).
    """

    signals: pd.DataFrame
    gnss_latency_s: float | None
    gnss_latency_stderr_s: float | None
    gps_time_mapping: dict | None
    lost_frames: dict
    warnings: list[str]
    cycle: np.ndarray
    t0_ns: int = 0
    rate_hz: float = 100.0
    cutoff_hz: float = DEFAULT_CUTOFF_HZ
    wheel_radius_m: float = float("nan")
    wheel_width_m: float = float("nan")
    latency_reference: str = ""
    latency_detail: LatencyEstimate | None = field(default=None, repr=False)
    wheel_radius_source: str = ""
    inertia: dict = field(default_factory=dict)
    excluded: list = field(default_factory=list)
    quality: dict = field(default_factory=dict)

    def summary(self) -> str:
        """Human-readable report: latency, GPS time mapping, lost frames, valid share, warnings."""
        s = self.signals
        lines = [f"samples: {len(s)} at {self.rate_hz:g} Hz ({len(s) / self.rate_hz:.1f} s), "
                 f"low-pass {self.cutoff_hz:g} Hz (zero-phase Butterworth, order 4 x2), "
                 f"wheel radius {self.wheel_radius_m:g} m ({self.wheel_radius_source}) for slip (Eq. 6)"]
        ine = self.inertia or {}
        if ine.get("applied"):
            lines.append(f"inertia compensated: Dp = Fx + m_w dV/dt, T = My - I_w domega/dt with "
                         f"m_w = {ine['wheel_mass_kg']:g} kg, I_w = {ine['wheel_inertia_kgm2']:g} kg m^2 "
                         f"({ine.get('source', '')}); largest correction "
                         f"{_fmt(ine.get('max_abs_force_n'), ' N')} on Dp, "
                         f"{_fmt(ine.get('max_abs_torque_nm'), ' N m')} on T")
        elif ine:
            lines.append("inertia NOT compensated: drawbar_pull_n = Fx and torque_nm = My as measured "
                         f"({ine.get('reason', 'switched off')})")
        lq = (self.quality or {}).get("latency") or {}
        if self.gnss_latency_s is not None:
            lines.append(f"GNSS latency: {self.gnss_latency_s * 1e3:.1f} ms +- "
                         f"{self.gnss_latency_stderr_s * 1e3:.1f} ms (reference: {self.latency_reference}; removed)"
                         + ("" if lq.get("reliable", True) else
                            " UNRELIABLE: " + "; ".join(lq.get("reasons") or [])))
        else:
            lines.append("GNSS latency: not estimated (see warnings); GNSS timestamps used as received")
        g = self.gps_time_mapping
        if g:
            lines.append(
                f"GPS time: t_s = 0 is GPS week {g['gps_week_at_t0']} tow {g['gps_tow_at_t0_s']:.3f} s; "
                f"GPS - host clock = {g['offset_s']:+.3f} s (incl. leap seconds and the receiver's output "
                f"delay), drift {g['drift_ppm']:+.2f} ppm, residual rms "
                f"{g['residual_rms_s'] * 1e3:.2f} ms (max {g['residual_max_s'] * 1e3:.2f} ms, "
                f"{g['n']} fixes, {g['n_outliers']} outliers)")
        else:
            lines.append("GPS time: no mapping (see warnings)")
        if self.lost_frames:
            lines.append("lost frames:")
            for name, d in self.lost_frames.items():
                lost = "unknown number" if d['lost'] is None else d['lost']
                lines.append(f"  {name}: {lost} lost in {d['gaps']} gaps (longest "
                             f"{d['longest_gap_s'] * 1e3:.0f} ms), {d['received']} received [{d['method']}]")
        n = len(s)
        share = float(s["valid"].mean()) if n else 0.0
        counts = s["phase"].value_counts().to_dict() if n else {}
        n_cycles = int(self.cycle.max()) + 1 if self.cycle.size and self.cycle.max() >= 0 else 0
        lines.append(f"valid samples: {share * 100:.1f} % of {n}; phases: "
                     + ", ".join(f"{k} {counts.get(k, 0)}" for k in PHASES)
                     + f"; accelerate cycles: {n_cycles}")
        q = self.quality or {}
        ts = q.get("timestamps") or {}
        if ts.get("outlier_frames") or ts.get("joined_parts"):
            lines.append(f"time base: {ts.get('outlier_frames', 0)} frames with outlier timestamps set "
                         f"aside; {ts.get('joined_parts', 0)} out-of-order parts sorted")
        if self.excluded:
            lines.append(f"excluded spans: {len(self.excluded)}")
            for e in self.excluded[:10]:
                span = ("time unknown" if e["t0_s"] is None or e["t1_s"] is None
                        else f"{e['t0_s']:.3f}-{e['t1_s']:.3f} s")
                lines.append(f"  {span}: {e['reason']}")
            if len(self.excluded) > 10:
                lines.append(f"  ... {len(self.excluded) - 10} more")
        for w in self.warnings:
            lines.append(f"warning: {w}")
        return "\n".join(lines)


def _fmt(v, unit: str) -> str:
    return "n/a" if v is None else f"{v:.3g}{unit}"


# --------------------------------------------------------------------------- configuration
#: ``_resolve_config``'s source name for the shipped default used in place of a recording's own configuration.
ASSUMED_CONFIG = "the shipped default vehicle.toml"


def _validity_signal(names: list, signal: str) -> str | None:
    """The receiver's validity flag of ``signal`` among a message's signal ``names``: ``Validity_<X>`` with
    ``signal`` starting with ``X`` (the RT-Range/SpeedBox DBC convention: ``Validity_INS_Vel_Forwards`` for
    ``INS_Vel_Forwards_2D``); None when the message has none."""
    hits = [n for n in names if n.startswith("Validity_") and signal.startswith(n[len("Validity_"):])]
    return max(hits, key=len) if hits else None


def _accuracy_signal(names: list) -> str | None:
    """The receiver's accuracy figure among a message's signal ``names``: its one ``Accuracy_*`` signal (the
    RT-Range/SpeedBox DBC convention: ``Accuracy_INS_Vel_Body`` for the body-axis velocities); None when the
    message has none or several."""
    hits = [n for n in names if n.startswith("Accuracy_")]
    return hits[0] if len(hits) == 1 else None


def _at_range_limit(cfg, ref, v: np.ndarray) -> np.ndarray:
    """(n,) bool: which SI values ``v`` (n,) of the configured signal ``ref`` sit at the physical
    value of one of its extreme raw codes (within half its resolution): the highest code, and for a
    signed signal the lowest too (an unsigned 0 is a true zero); none for a float signal. A
    transducer or an encoder clipping at its range, or the all-ones "not available" code of many
    ECUs, sends these codes: no measurement. Source: the DBC's bit length, sign, scale and offset
    (the raw range of an n-bit two's complement or unsigned integer)."""
    s = cfg.database(ref.bus).get_message_by_name(ref.message).get_signal_by_name(ref.signal)
    out = np.zeros(v.shape, dtype=bool)
    if s.is_float:
        return out
    n = int(s.length)
    codes = (-(1 << (n - 1)), (1 << (n - 1)) - 1) if s.is_signed else ((1 << n) - 1,)
    for raw in codes:
        out |= np.abs(v - (raw * s.scale + s.offset) * ref.scale_to_si) <= 0.5 * abs(s.scale * ref.scale_to_si)
    return out


def _other_mux_value(message, decoded: dict[str, np.ndarray], names: list[str]) -> tuple[str, np.ndarray]:
    """Which frames of a decoded message carry another multiplexer value than one of the signals
    ``names`` needs (a multiplexed signal is absent there, not cut short).

    ``message`` is the cantools message, ``decoded`` its decoded signals (name -> (n,) float64,
    multiplexers included). Returns a phrase naming the multiplexer values seen and needed, and an
    (n,) bool mask; ("", all False) when no named signal is multiplexed. Source: the DBC's
    multiplexing (``M`` / ``mN`` in ``SG_``), as cantools reads it."""
    n = len(next(iter(decoded.values()))) if decoded else 0
    mask, said = np.zeros(n, dtype=bool), {}
    for name in dict.fromkeys(names):
        s = message.get_signal_by_name(name)
        if not s.multiplexer_ids or s.multiplexer_signal not in decoded:
            continue
        value = decoded[s.multiplexer_signal]
        other = np.isfinite(value) & ~np.isin(np.trunc(value), s.multiplexer_ids)
        if other.any():
            mask |= other
            seen = ", ".join(f"{v:g}" for v in np.unique(value[other])[:5])
            need = ", ".join(str(i) for i in sorted(s.multiplexer_ids))
            said.setdefault(f"{s.multiplexer_signal} = {seen}, not the {need} that", []).append(name)
    return "; ".join(f"{k} {', '.join(v)} need{'s' if len(v) == 1 else ''}" for k, v in said.items()), mask


def _grade_factor(t2: np.ndarray, v2: np.ndarray, t3: np.ndarray, v3: np.ndarray, period_s: float,
                  t_out: np.ndarray) -> np.ndarray | None:
    """1 / cos(grade) at the times ``t_out`` [s] (M,), from the GNSS receiver's horizontal (2D) and 3D
    ground speeds (``t2``, ``v2``, ``t3``, ``v3``: (N,) times [s] and speeds [m/s] of one message,
    ``period_s`` its period): the running median over :data:`GRADE_WINDOW_S` of v3 / v2 where
    v2 >= :data:`GRADE_MIN_SPEED_MPS`, clipped to [1, sqrt(2)] (3D < 2D is rounding; beyond 45 deg no
    vehicle drives), held between such samples. None when fewer than a window of such samples exist or
    the factor stays under :data:`GRADE_MIN_RATIO` (level ground: nothing to correct).
    Source: the RT SpeedBox DBC's comments (2D horizontal, 3D including the vertical component);
    Eq. (6) with V along the ground."""
    from scipy.ndimage import median_filter

    if t2.shape != t3.shape or not np.allclose(t2, t3, atol=0.5 * period_s):
        t3_on_2 = np.interp(t2, t3, v3, left=np.nan, right=np.nan)
    else:
        t3_on_2 = v3
    with np.errstate(invalid="ignore", divide="ignore"):
        ok = np.isfinite(v2) & np.isfinite(t3_on_2) & (v2 >= GRADE_MIN_SPEED_MPS)
        ratio = np.clip(t3_on_2[ok] / v2[ok], 1.0, math.sqrt(2.0))
    window = max(3, int(round(GRADE_WINDOW_S / period_s)) | 1)
    if ratio.size < window:
        return None
    smooth = median_filter(ratio, size=window, mode="nearest")
    if smooth.max() < GRADE_MIN_RATIO:
        return None
    return np.interp(t_out, t2[ok], smooth)


def _recorded_wheel(read_report) -> tuple[float, float] | None:
    """The wheel (radius, width) [m] a recording's ``wheelsoil.recording`` metadata states (the writer's
    copy of its configuration), from a reader's report; None when it states none or an implausible one."""
    facts = (getattr(read_report, "metadata", None) or {}).get("wheelsoil.recording") or {}
    try:
        return (check_wheel_radius(float(facts["wheel_radius_m"]), "recorded wheel_radius_m"),
                check_wheel_width(float(facts["wheel_width_m"]), "recorded wheel_width_m"))
    except (KeyError, ValueError, TypeError):
        return None


def _resolve_config(path: Path, config: Any, warnings: list[str]):
    """VehicleConfig from an object, a TOML path, the recording's attachment, or the default.

    Returns ``(config, where)``, ``where`` naming the source for messages."""
    from wheelsoil.daq import VehicleConfig, load_recording_config, load_vehicle_config

    if isinstance(config, VehicleConfig):
        return config, f"vehicle configuration {config.source or '(given)'}"
    if config is not None:
        return load_vehicle_config(config), f"vehicle configuration {config}"
    try:
        cfg = load_recording_config(path)
        if cfg is not None:
            return cfg, "the recording's vehicle configuration"
        why = "no usable vehicle configuration attached (none, or its attachments fail their CRC)"
    except ValueError as exc:  # not an MCAP file is reported by the reader; a bad attachment here
        why = f"the attached vehicle configuration is not usable ({exc})"
    cfg = load_vehicle_config()
    warnings.append(f"VEHICLE CONFIGURATION ASSUMED: {path}: {why}; the shipped default vehicle.toml is used "
                    f"(DBCs, signals, wheel mass and inertia; wheel {cfg.wheel_radius_m:g} x {cfg.wheel_width_m:g} m "
                    "unless the recording's metadata states its wheel); give the right one with --vehicle TOML")
    return cfg, ASSUMED_CONFIG


def check_wheel_radius(value, what: str = "wheel radius") -> float:
    """``value`` as a float radius [m], checked finite and within :data:`RADIUS_RANGE_M`.

    Raises ``ValueError`` naming ``what`` and the value (hint for millimetres)."""
    return _check_length(value, what, "radius", RADIUS_RANGE_M)


def check_wheel_width(value, what: str = "wheel width") -> float:
    """``value`` as a float width [m], checked finite and within :data:`WIDTH_RANGE_M`.

    Raises ``ValueError`` naming ``what`` and the value (hint for millimetres)."""
    return _check_length(value, what, "width", WIDTH_RANGE_M)


def _check_length(value, what: str, noun: str, bounds: tuple) -> float:
    try:
        if isinstance(value, bool):
            raise TypeError
        r = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{what} = {value!r}: must be a number in m") from None
    lo, hi = bounds
    if not (math.isfinite(r) and lo <= r <= hi):
        hint = "; did you give mm?" if math.isfinite(r) and lo * 1e3 <= r <= hi * 1e3 else ""
        raise ValueError(f"{what} = {value!r}: not a plausible {noun} in m ({lo:g}-{hi:g}){hint}")
    return r


def _front_wheel_refs(config) -> list:
    """SignalRefs of the free-rolling front wheels: config keys ``wheel_speed_fl``/``_fr``,
    else signals ending in FL/FR in the message of ``wheel_speed`` (same unit)."""
    from wheelsoil.daq import SignalRef

    refs = [config.signals[k] for k in ("wheel_speed_fl", "wheel_speed_fr") if k in config.signals]
    if refs:
        return refs
    ws = config.signals["wheel_speed"]
    try:
        msg = config.database(ws.bus).get_message_by_name(ws.message)
    except (KeyError, ValueError, OSError):
        return []
    return [SignalRef(ws.bus, ws.message, s.name, ws.unit, ws.scale_to_si)
            for s in msg.signals if s.name.upper().endswith(("FL", "FR")) and s.name != ws.signal]


# --------------------------------------------------------------------------- latency helpers
#: |front r*omega / measured r*omega - 1| below this for 99 % of the moving samples, while the
#: measured wheel is driven hard: the front wheels are coupled to it (not free rolling).
COUPLED_MAX_DEV = 0.02


def _fronts_speed(series: list, r: float) -> np.ndarray:
    """The front wheels' mean r*omega [m/s] at the first one's times: ``series`` [(times (n_i,), omega
    (n_i,) [rad/s])], each interpolated to ``series[0]``'s times; ``r`` [m].  NaN where every wheel is lost."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # every front wheel lost at a sample: NaN
        return np.nanmean(np.vstack([np.interp(series[0][0], t, v) for t, v in series]), axis=0) * r


def _fronts_coupled(t_front_ns: np.ndarray, v_front: np.ndarray, t_rear_ns: np.ndarray,
                    v_rear: np.ndarray) -> bool:
    """True when the front wheels' r*omega (n,) follows the measured wheel's r*omega (m,)
    within :data:`COUPLED_MAX_DEV` wherever it exceeds 1 m/s (at least 100 samples): all
    wheels turn together (locked differentials), so the fronts slip as much as the measured
    wheel and cannot serve as the latency reference. (A run without any slip also looks like
    this; the caller then checks against :func:`_force_latency`.)"""
    rear = np.interp(t_front_ns.astype(np.float64), t_rear_ns.astype(np.float64), v_rear)
    mv = np.isfinite(rear) & np.isfinite(v_front) & (rear > 1.0)
    if np.count_nonzero(mv) < 100:
        return False
    return bool(np.percentile(np.abs(v_front[mv] / rear[mv] - 1.0), 99) < COUPLED_MAX_DEV)


def _sustained(mask: np.ndarray, t_s: np.ndarray, hold_s: float) -> np.ndarray:
    """(n,) bool: ``mask`` (n,) holds at every sample within ``hold_s`` [s] of this one (times
    ``t_s`` (n,) sorted): a binary erosion in time."""
    bad = np.concatenate([[0], np.cumsum(~mask)])
    lo = np.searchsorted(t_s, t_s - hold_s, side="left")
    hi = np.searchsorted(t_s, t_s + hold_s, side="right")
    return mask & (bad[hi] - bad[lo] == 0)


def _force_latency(g_rel: np.ndarray, g_v: np.ndarray, g_period: float, t_grid: np.ndarray,
                   fx: np.ndarray, cutoff_hz: float) -> LatencyEstimate | None:
    """GNSS latency from vehicle dynamics: the vehicle's acceleration follows the soil's
    longitudinal forces, ``m dV/dt ~ a Fx + b`` (the measured wheel's Fx standing for the sum
    over the wheels, hence a free gain ``a``), so the GNSS dV/dt (g_rel (n,) s, g_v (n,) m/s,
    derivative of the filtered V) lags the measured Fx (fx (N,) N on ``t_grid``) by the
    latency. Both sides low-passed with the same zero-phase filter at ``cutoff_hz``; the fit is
    :func:`.timesync.estimate_latency`. None when it cannot be estimated."""
    ok = np.isfinite(fx)
    if np.count_nonzero(ok) < 100 or not g_period > 0:
        return None
    dv = filter_to_grid(g_rel, g_v, g_period, g_rel, cutoff_hz, derivative=True)[1]
    dt = float(t_grid[1] - t_grid[0]) if t_grid.size > 1 else 0.01
    fxs = filter_to_grid(t_grid[ok], fx[ok], dt, t_grid, cutoff_hz)
    try:
        return estimate_latency(g_rel, dv, t_grid, fxs, usable_ref=np.isfinite(fxs), min_speed_mps=-np.inf)
    except ValueError:
        return None


_LATENCY_METHODS = {
    "wheel_reference": "GNSS V aligned with a wheel-speed reference r*omega",
    "traction": "slip-traction consistency of the measured wheel (T/(rW) a function of slip, no hysteresis)",
    "dynamics": "GNSS dV/dt against the measured Fx (vehicle dynamics)",
}


def _agree(a: LatencyEstimate, b: LatencyEstimate) -> bool:
    """Two estimates (total standard errors) within :data:`LATENCY_AGREE_SIGMAS` combined errors."""
    return abs(a.latency_s - b.latency_s) <= LATENCY_AGREE_SIGMAS * math.hypot(a.stderr_s, b.stderr_s)


def _wheel_speed_lag(t_mid: np.ndarray, ref: np.ndarray, t_wss: np.ndarray, omega_wss: np.ndarray,
                     radius_m: float, period_wss: float):
    """How late the wheel-speed module reads the measured wheel against the transducer's clock.

    The WFT's wheel angle (500 Hz, hardware.md ``WFT_RL_Angle``) is sampled on the transducer's own
    clock, the forces' time base; its derivative is the speed of the wheel whose speed the module
    reports (``WheelSpeed_RL``). A module that averages over its last tooth period or is read
    through a gateway reports that speed late, and slip (Eq. 6) from it then belongs to an earlier
    moment than the forces it is paired with; during a spin-up of a few tenths of a second a lag of
    30 ms moves slip by several hundredths. The lag is found as the GNSS latency is
    (:func:`.timesync.estimate_latency`, the module's r*omega aligned with the angle's, 2 ms grid
    over :data:`WSS_LAG_RANGE_S`).

    ``t_mid`` (N,) [s] and ``ref`` (N,) [rad/s]: the wheel's speed from the angle (:func:`_angle_rate`);
    ``t_wss`` (M,) the module's frame times [s], ``omega_wss`` (M,) its speed of the measured wheel
    [rad/s], ``period_wss`` its period [s]; ``radius_m`` r [m]. Returns ``(constant, per_tooth)``: the
    constant lag, a
    :class:`.timesync.LatencyEstimate` (``latency_s`` > 0: the module late), and the delay that grows
    as the wheel slows (a tone wheel timed per tooth: ``lag + pitch/omega``,
    :func:`.timesync.estimate_tooth_lag`), a :class:`.timesync.ToothLag`, or why there is none (str).
    Raises ``ValueError`` when the two do not overlap (the estimator's messages).
    """
    const = estimate_latency(t_wss, np.abs(omega_wss) * radius_m, t_mid, ref * radius_m, usable_ref=np.isfinite(ref),
                             min_latency_s=WSS_LAG_RANGE_S[0], max_latency_s=WSS_LAG_RANGE_S[1])
    try:
        tooth = estimate_tooth_lag(t_wss, omega_wss, _module_speed(t_wss, omega_wss, period_wss), t_mid, ref,
                                   start_lag_s=const.latency_s, min_lag_s=WSS_LAG_RANGE_S[0],
                                   max_lag_s=WSS_LAG_RANGE_S[1], min_omega_radps=0.3 / radius_m)
    except ValueError as exc:
        tooth = str(exc)
    return const, tooth


def _angle_rate(t_w: np.ndarray, angle_rad: np.ndarray, period_w: float) -> tuple[np.ndarray, np.ndarray]:
    """The wheel's speed [rad/s] from the transducer's wheel angle: ``(t_mid, omega)`` (N - 1,) at the
    mid-times of consecutive samples ``t_w`` (N,) [s] of ``angle_rad`` (N,) (NaN where lost, wrapping at
    2 pi), low-passed zero-phase at :data:`LATENCY_REF_CUTOFF_HZ`, positive in the sense the wheel mostly
    turns.  Raises ``ValueError`` for fewer than 100 consecutive samples."""
    step = np.angle(np.exp(1j * np.diff(angle_rad)))  # wrapped to (-pi, pi]: one sample turns < half a turn
    dt = np.diff(t_w)
    ok = np.isfinite(step) & (dt > 0) & (dt < 1.5 * period_w)
    if np.count_nonzero(ok) < 100:
        raise ValueError("fewer than 100 consecutive wheel-angle samples")
    om = np.where(ok, step / np.where(dt > 0, dt, 1.0), np.nan)
    if np.nanmedian(om) < 0:  # the angle counting the other way
        om = -om
    t_mid = 0.5 * (t_w[1:] + t_w[:-1])
    return t_mid, filter_to_grid(t_mid, om, period_w, t_mid, LATENCY_REF_CUTOFF_HZ)


#: The wheel-speed module's scale against the transducer's wheel-angle rate (:func:`_wheel_speed_scale`):
#: a median ratio further than ``WHEEL_SCALE_TOL`` from 1 (a tone wheel of up to 200 teeth configured one tooth
#: off is 0.5 % or more; the ratio's scatter on recordings of one wheel is a few 1e-4) is a scale error of the
#: module, corrected when the ratios scatter less than ``WHEEL_SCALE_SPREAD`` (robust sd; another wheel's
#: channel scatters with the slip of the two wheels), over at least ``WHEEL_SCALE_MIN_N`` readings where the
#: wheel turns faster than ``WHEEL_SCALE_MIN_RADPS``.
WHEEL_SCALE_TOL = 0.005
WHEEL_SCALE_SPREAD = 0.02
WHEEL_SCALE_MIN_N = 200
WHEEL_SCALE_MIN_RADPS = 1.0


def _wheel_speed_scale(t_mid: np.ndarray, ref: np.ndarray, t_wss: np.ndarray, omega_wss: np.ndarray,
                       period_wss: float) -> dict:
    """The wheel-speed module's speed over the transducer's wheel-angle rate, both of the measured wheel.

    The angle is the transducer's absolute wheel angle (hardware.md ``WFT_RL_Angle``: it wraps once per
    revolution, so its rate is the wheel's rotation); the module counts tone-wheel teeth against a
    configured count.  Arrays as :func:`_wheel_speed_lag` (the angle's rate ``t_mid``, ``ref`` from
    :func:`_angle_rate`; ``t_wss``, ``omega_wss`` (M,) after the module's lag is removed).  Returns
    ``{"gain", "spread", "n", "applied", "note"}``: the median of the readings' ratio
    (both low-passed at :data:`LATENCY_REF_CUTOFF_HZ`) where the wheel turns faster than
    :data:`WHEEL_SCALE_MIN_RADPS`, its robust sd (1.4826 MAD), the readings used, and whether the module's
    speed is to be divided by the gain (:data:`WHEEL_SCALE_TOL`, :data:`WHEEL_SCALE_SPREAD`, at most
    ``WHEEL_GAIN_MAX``: beyond it a unit or another wheel, :func:`_implausible`), with why not.  Never raises.
    """
    out = _scale_not_found("")
    ok = np.isfinite(ref)
    if ok.sum() < 2:
        out["note"] = "no wheel-angle rate"
        return out
    ref_at = np.interp(t_wss, t_mid[ok], ref[ok], left=np.nan, right=np.nan)
    mod = _module_speed(t_wss, omega_wss, period_wss)
    use = np.isfinite(ref_at) & np.isfinite(mod) & (ref_at > WHEEL_SCALE_MIN_RADPS)
    out["n"] = n = int(np.count_nonzero(use))
    if n < WHEEL_SCALE_MIN_N:
        out["note"] = f"{n} readings with the wheel faster than {WHEEL_SCALE_MIN_RADPS:g} rad/s"
        return out
    ratio = mod[use] / ref_at[use]
    g = float(np.median(ratio))
    out["gain"], out["spread"] = g, float(1.4826 * np.median(np.abs(ratio - g)))
    if abs(g - 1.0) <= WHEEL_SCALE_TOL:
        out["note"] = f"within {WHEEL_SCALE_TOL:g} of 1"
    elif not g > 0 or max(g, 1.0 / g) > WHEEL_GAIN_MAX:
        out["note"] = f"beyond {WHEEL_GAIN_MAX:g}: a unit, a factor or another wheel's channel, not a tooth count"
    elif out["spread"] > WHEEL_SCALE_SPREAD:
        out["note"] = f"the ratio scatters by {out['spread']:.3g} (> {WHEEL_SCALE_SPREAD:g}): not one wheel's scale"
    else:
        out["applied"] = True
    return out


def _scale_not_found(note: str) -> dict:
    """:func:`_wheel_speed_scale`'s result when no scale is measured, saying why (``note``)."""
    return {"gain": None, "spread": None, "n": 0, "applied": False, "note": note}


def _module_speed(t_s: np.ndarray, omega: np.ndarray, period_s: float) -> np.ndarray:
    """A wheel-speed module's |omega| (n,) [rad/s] at its reading times ``t_s`` (n,) [s], low-passed
    zero-phase at :data:`LATENCY_REF_CUTOFF_HZ`: the speed a per-tooth delay's 1/omega is taken of."""
    return filter_to_grid(t_s, np.abs(omega), period_s, t_s, LATENCY_REF_CUTOFF_HZ)


def _tooth_not_applied(tooth, const: LatencyEstimate) -> str:
    """Why the per-tooth delay ``tooth`` (:func:`_wheel_speed_lag`) is not removed, or "" when it is."""
    if isinstance(tooth, str):
        return tooth
    if const.note:
        return const.note
    if not tooth.pitch_rad > TOOTH_LAG_MIN_Z * tooth.stderr_pitch_rad:
        return (f"pitch {tooth.pitch_rad:.3g} +- {tooth.stderr_pitch_rad:.2g} rad: not {TOOTH_LAG_MIN_Z:g} "
                "standard errors above zero (the delay does not grow as the wheel slows)")
    return _lag_imprecise(tooth.stderr_lag_s, tooth.gain)


def _fronts_pitch(series: list, rel_s, g_rel: np.ndarray, g_v: np.ndarray, g_period: float, radius_m: float,
                  tooth) -> dict:
    """Whether the front wheels' channels share the measured wheel's per-tooth delay ``tooth`` (a
    :class:`.timesync.ToothLag`).

    Each front's speed is fitted against the GNSS speed (low-passed at :data:`LATENCY_REF_CUTOFF_HZ`,
    over the radius ``radius_m`` [m]) with :func:`.timesync.estimate_tooth_lag`: the GNSS latency is
    constant, so the fitted pitch is the fronts' own (their constant delay and the latency are one
    lag, searched over +-0.6 s). ``series`` [(times (n_i,) [ns], omega (n_i,) [rad/s])] of the fronts in
    the module's message; ``rel_s`` maps ns to the run's seconds; ``g_rel`` (m,) [s], ``g_v`` (m,)
    [m/s] the GNSS speed, ``g_period`` its period [s]. Returns ``{"pitch_rad", "stderr_pitch_rad", "n",
    "shared", "note"}`` (inverse-variance mean over the fronts): ``shared`` True when the pitch is
    nearer the measured wheel's than zero, False when nearer zero, None (undecided: the default, shared)
    when the two are not :data:`TOOTH_LAG_MIN_Z` combined standard errors apart or no front could be
    fitted (``note`` says why). Source: as :class:`.timesync.ToothLag`."""
    fits, why = [], []
    try:
        ref = filter_to_grid(g_rel, g_v, g_period, g_rel, LATENCY_REF_CUTOFF_HZ) / radius_m
    except ValueError as exc:
        ref, why = None, [str(exc)]
    for t_ns, omega in series if ref is not None else ():
        t = rel_s(t_ns)
        try:
            fits.append(estimate_tooth_lag(t, omega, _module_speed(t, omega, _time_gaps("front", t_ns)[1]), g_rel,
                                           ref, start_lag_s=0.0, min_lag_s=-0.6, max_lag_s=0.6,
                                           min_omega_radps=0.3 / radius_m))
        except ValueError as exc:
            why.append(str(exc))
    fits = [f for f in fits if f.stderr_pitch_rad > 0 and math.isfinite(f.stderr_pitch_rad)]
    if not fits:
        return {"pitch_rad": None, "stderr_pitch_rad": None, "n": 0, "shared": None,
                "note": "; ".join(why) or "no front wheel fitted"}
    w = np.array([f.stderr_pitch_rad ** -2 for f in fits])
    p = float(np.sum(w * [f.pitch_rad for f in fits]) / np.sum(w))
    se = float(np.sum(w) ** -0.5)
    apart = tooth.pitch_rad > TOOTH_LAG_MIN_Z * math.hypot(se, tooth.stderr_pitch_rad)
    shared = (abs(p - tooth.pitch_rad) < abs(p)) if apart else None
    return {"pitch_rad": p, "stderr_pitch_rad": se, "n": int(sum(f.n for f in fits)), "shared": shared,
            "note": "" if apart else "the fronts' pitch cannot tell the measured wheel's from zero"}


def _unlag(t_ns: np.ndarray, omega: np.ndarray, lag) -> tuple[np.ndarray, np.ndarray]:
    """A wheel speed's readings (``t_ns`` int64 (n,) sorted times, ``omega`` (n,) [rad/s]) moved back to
    the moments they describe: by the constant ``lag`` [s] (float), by the per-tooth delay of a
    :class:`.timesync.ToothLag` (readings it would put out of order dropped, :meth:`ToothLag.unlag`), or
    unchanged (None). Returns the times and speeds kept."""
    if lag is None:
        return t_ns, omega
    if not isinstance(lag, ToothLag):
        return t_ns - int(round(lag * 1e9)), omega
    t_s = (t_ns - t_ns[0]) * 1e-9
    w = _module_speed(t_s, omega, robust_period(t_ns))
    keep = lag.unlag(t_s, w)
    return t_ns[keep] - np.round(lag.delay_s(w[keep]) * 1e9).astype(np.int64), omega[keep]


def _lag_imprecise(stderr_s: float, gain: float) -> str:
    """Why a wheel-speed lag of standard error ``stderr_s`` [s], found with the module's speed ``gain`` times
    the angle's, is not removed (too imprecise, or another wheel's speed), or ""."""
    if not stderr_s <= WSS_LAG_SE_S:
        return f"standard error {stderr_s * 1e3:.1f} ms > {WSS_LAG_SE_S * 1e3:g} ms"
    if abs(gain - 1) > WSS_LAG_GAIN_TOL:
        return f"speed gain {gain:.3f}: not the same wheel's speed"
    return ""


def _lag_not_applied(lag: LatencyEstimate) -> str:
    """Why the wheel-speed lag ``lag`` (:func:`_wheel_speed_lag`) is not removed, or "" when it is."""
    if lag.note:
        return lag.note
    if why := _lag_imprecise(lag.stderr_s, lag.gain):
        return why
    if abs(lag.latency_s) < WSS_LAG_MIN_S:
        return f"under {WSS_LAG_MIN_S * 1e3:g} ms"
    return ""


def _with_systematic(name: str, c: LatencyEstimate) -> LatencyEstimate:
    """``c`` with its standard error raised by :data:`LATENCY_SYSTEMATIC_S` (quadrature)."""
    from dataclasses import replace

    return replace(c, stderr_s=math.hypot(c.stderr_s, LATENCY_SYSTEMATIC_S.get(name, 0.0)))


def _choose_latency(cands: dict, errs: dict, *, coupled: bool, wheel_ref_label: str, fronts: bool,
                    speed_rms_mps: float | None = None):
    """Pick the GNSS latency from the candidate estimates and judge its reliability.

    ``cands`` name -> :class:`.timesync.LatencyEstimate` (``wheel_reference``,
    ``traction``, ``dynamics``); ``errs`` name -> why a candidate is missing;
    ``coupled`` the front wheels turn with the measured one (driven: no free-rolling
    reference; the caller then takes the measured wheel where it transmits no torque);
    ``fronts`` the reference is the front wheels; ``speed_rms_mps`` the RMS GNSS speed [m/s] (None:
    the wheel reference's own fit is not judged). Each candidate's standard
    error is first raised by its systematic uncertainty (:data:`LATENCY_SYSTEMATIC_S`).
    Rules: a candidate at the edge of the search range or without a finite standard
    error is unusable; the front wheels' reference is unusable when they are
    coupled, and when it disagrees with the slip-traction estimate (which needs no
    other wheel) unless the dynamics estimate sides with it: its wheels then do not
    roll freely (the measured wheel's own torque shows whether it does); but a wheel
    reference whose own fit shows it rolling freely (:data:`FREE_ROLLING_GAIN_TOL`,
    :data:`FREE_ROLLING_RESID_REL`) and is precise (:data:`LATENCY_RELIABLE_SE_S`) makes a
    disagreeing slip-traction estimate unusable instead. The choice: the wheel reference if
    usable and precise (total standard error at most :data:`LATENCY_RELIABLE_SE_S`; a coasting
    wheel whose deceleration hardly
    changes tells little), or usable without a traction estimate (joined, when imprecise, by an
    agreeing dynamics estimate: their inverse-variance mean), else the inverse-variance mean of
    agreeing traction and dynamics estimates, else the usable one with the smaller standard error, else
    (flagged) the best finite one;
    the dynamics estimate alone is applied only against a disagreeing slip-traction estimate outside
    the receiver's typical latency (:data:`LATENCY_TYPICAL_S`) when it lies within it (its bias is
    known, it otherwise only confirms or joins another); else no latency is applied.
    ``reliable`` needs a total standard error of at most
    :data:`LATENCY_RELIABLE_SE_S`, no edge hit, agreement (within
    :data:`LATENCY_AGREE_SIGMAS` combined standard errors) with every other usable
    candidate, and an independent confirmation: two agreeing estimators, or the
    front wheels' reference not coupled to the measured wheel.

    Returns ``(estimate or None, reference label, quality dict, warnings)``; the
    quality dict is ``ProcessResult.quality["latency"]``: ``estimate_s``,
    ``stderr_s`` (total), ``method``, ``reliable``, ``reasons`` (why not reliable),
    ``fronts_driven``, ``candidates`` {name: {estimate_s, stderr_s, stderr_stat_s,
    systematic_s, usable, note, n, method}} and ``search_range_s``.
    """
    warns: list[str] = []
    reasons: list[str] = []
    info: dict = {}
    usable: dict = {}
    stat = {k: c.stderr_s for k, c in cands.items()}
    sys_key = {k: "measured_wheel" if k == "wheel_reference" and not fronts else k for k in cands}
    cands = {k: _with_systematic(sys_key[k], c) for k, c in cands.items()}
    for k, c in cands.items():
        why = ""
        if c.note:
            why = c.note
        elif not (math.isfinite(c.stderr_s) and math.isfinite(c.latency_s)):
            why = "no finite standard error"
        elif k == "wheel_reference" and fronts and coupled:
            why = "the front wheels turn with the measured wheel (driven): no free-rolling reference"
        info[k] = {"estimate_s": c.latency_s, "stderr_s": c.stderr_s, "stderr_stat_s": stat[k],
                   "systematic_s": LATENCY_SYSTEMATIC_S[sys_key[k]], "usable": not why, "note": why,
                   "n": c.n, "method": _LATENCY_METHODS[k]}
        if not why:
            usable[k] = c
    for k, e in errs.items():
        info.setdefault(k, {"estimate_s": None, "stderr_s": None, "stderr_stat_s": None,
                            "systematic_s": LATENCY_SYSTEMATIC_S.get(k, 0.0), "usable": False, "note": e,
                            "n": 0, "method": _LATENCY_METHODS[k]})
    wr, tr, dy = usable.get("wheel_reference"), usable.get("traction"), usable.get("dynamics")
    rolls_freely = (wr is not None and speed_rms_mps is not None and abs(wr.gain - 1.0) <= FREE_ROLLING_GAIN_TOL
                    and wr.residual_rms_mps <= FREE_ROLLING_RESID_REL * speed_rms_mps
                    and wr.stderr_s <= LATENCY_RELIABLE_SE_S)
    if rolls_freely and tr is not None and not _agree(wr, tr):
        info["traction"]["usable"] = False
        info["traction"]["note"] = (
            f"disagrees with a wheel reference that rolls freely (GNSS V = {wr.gain:.3f} r*omega "
            f"{wr.offset_mps:+.3f} m/s, residual {wr.residual_rms_mps:.3f} m/s): the torque is not a static "
            "function of slip and load in this run")
        usable.pop("traction")
        tr = None
    if fronts and wr is not None and tr is not None and not _agree(wr, tr):
        # (the measured wheel as the reference is free rolling by its own torque: kept, and a
        # disagreement makes it unreliable below)
        if dy is None or _agree(tr, dy) or not _agree(wr, dy):
            # the slip-traction estimate (independent of any other wheel) contradicts the wheel
            # reference: the reference wheels slip (driven, or braking), so they are not used
            info["wheel_reference"]["usable"] = False
            info["wheel_reference"]["note"] = (
                f"disagrees with the slip-traction estimate ({tr.latency_s * 1e3:.1f} +- "
                f"{tr.stderr_s * 1e3:.1f} ms): the reference wheels do not roll freely")
            usable.pop("wheel_reference")
            wr = None
    chosen: LatencyEstimate | None = None
    method = ""

    def with_dynamics(a: LatencyEstimate, name: str) -> LatencyEstimate:  # the inverse-variance mean of a and dy
        w1, w2 = a.stderr_s ** -2, dy.stderr_s ** -2
        return LatencyEstimate((w1 * a.latency_s + w2 * dy.latency_s) / (w1 + w2), (w1 + w2) ** -0.5, 1.0, 0.0,
                               a.residual_rms_mps, a.n + dy.n,
                               f"inverse-variance mean of the {name} and dynamics estimates")

    if wr is not None and (wr.stderr_s <= LATENCY_RELIABLE_SE_S or tr is None):
        chosen, method = wr, "wheel_reference"
        if wr.stderr_s > LATENCY_RELIABLE_SE_S and dy is not None and _agree(wr, dy):
            # an imprecise lone wheel reference (a coasting wheel's few samples) joined by the dynamics one
            chosen, method = with_dynamics(wr, "wheel-reference"), "wheel_reference+dynamics"
    elif tr is not None and dy is not None and _agree(tr, dy):
        chosen, method = with_dynamics(tr, "traction"), "traction+dynamics"
    elif set(usable) - {"dynamics"}:
        alone = {k: c for k, c in usable.items() if k != "dynamics"}
        method = min(alone, key=lambda k: alone[k].stderr_s)
        chosen = alone[method]
        lo, hi = LATENCY_TYPICAL_S
        if method == "traction" and dy is not None and not lo <= tr.latency_s <= hi and lo <= dy.latency_s <= hi:
            # traction and dynamics disagree (else combined above), and only dynamics lies where a receiver's
            # latency typically does: an effect that breaks the static torque-slip curve moves the traction
            # estimate by hundreds of ms (an independent generator: 389 and 464 ms where the truth is 77
            # and 54 ms, the dynamics estimate 77 and 44 ms)
            chosen, method = dy, "dynamics"
            reasons.append(f"the slip-traction estimate ({tr.latency_s * 1e3:.1f} ms) lies outside a receiver's "
                           f"typical {lo * 1e3:g}-{hi * 1e3:g} ms (hardware.md) "
                           "and the dynamics estimate within it: the dynamics one (biased by some ms) is applied")
    elif cands:  # nothing usable: the best-supported one, flagged, if not at the edge
        fin = {k: c for k, c in cands.items() if not c.note and math.isfinite(c.stderr_s)
               and not (k == "wheel_reference" and fronts and coupled) and k != "dynamics"}
        if fin:
            method = min(fin, key=lambda k: fin[k].stderr_s)
            chosen = fin[method]
    if chosen is None:
        reasons.append("no usable estimate")
    else:
        if chosen.stderr_s > LATENCY_RELIABLE_SE_S:
            reasons.append(f"standard error {chosen.stderr_s * 1e3:.1f} ms > {LATENCY_RELIABLE_SE_S * 1e3:g} ms")
        others = [k for k in usable if k not in method.split("+")]
        bad = [k for k in others if not _agree(chosen, usable[k])]
        if bad:
            reasons.append("disagrees with " + ", ".join(
                f"{k} ({usable[k].latency_s * 1e3:.1f} +- {usable[k].stderr_s * 1e3:.1f} ms)" for k in bad))
        if "+" not in method and not [k for k in others if k not in bad] and not (
                method == "wheel_reference" and fronts and not coupled):
            reasons.append(f"only one estimator ({method}) usable: no independent check")
        if method not in usable and "+" not in method:
            reasons.append(f"{method} is not usable ({info[method]['note']})")
    reliable = chosen is not None and not reasons
    wr_info = info.get("wheel_reference", {})
    q = {"estimate_s": None if chosen is None else chosen.latency_s,
         "stderr_s": None if chosen is None else chosen.stderr_s,
         "method": method or None, "reliable": bool(reliable), "reasons": reasons,
         "fronts_driven": bool(coupled) or (fronts and not wr_info.get("usable", False)
                                            and "do not roll freely" in wr_info.get("note", "")),
         "candidates": info, "search_range_s": [LATENCY_MIN_S, LATENCY_MAX_S]}
    label = {"wheel_reference": wheel_ref_label, "traction": _LATENCY_METHODS["traction"],
             "dynamics": _LATENCY_METHODS["dynamics"],
             "traction+dynamics": _LATENCY_METHODS["traction"] + " and " + _LATENCY_METHODS["dynamics"],
             "wheel_reference+dynamics": wheel_ref_label + " and " + _LATENCY_METHODS["dynamics"]}.get(method, "")
    cand_txt = "; ".join(f"{k}: " + ("none" if v["estimate_s"] is None else
                                     f"{v['estimate_s'] * 1e3:.1f} +- {v['stderr_s'] * 1e3:.1f} ms")
                         + ("" if v["usable"] else f" (not used: {v['note']})") for k, v in info.items())
    if chosen is None:
        top = [v for v in info.values() if v["estimate_s"] is not None]
        beyond = bool(top) and all(v["estimate_s"] >= LATENCY_MAX_S - 0.011 for v in top)
        warns.append("GNSS LATENCY UNKNOWN: GNSS latency not estimated; GNSS timestamps used as received; slip "
                     "may be biased "
                     + (f"(every estimate stops at the search range's top, {LATENCY_MAX_S:g} s: the GNSS speed may "
                        "arrive later than that, a very late receiver or one stamped on another clock than the "
                        "wheels'; check the logger's clocks) " if beyond else "")
                     + f"(candidates: {cand_txt}); ProcessResult.quality['latency']")
    elif not reliable:
        warns.append(f"GNSS LATENCY UNRELIABLE: applied {chosen.latency_s * 1e3:.1f} +- "
                     f"{chosen.stderr_s * 1e3:.1f} ms from {label} ({'; '.join(reasons)}); slip and every verdict "
                     f"built on it are less certain (candidates: {cand_txt}); ProcessResult.quality['latency']")
    elif method != "wheel_reference" or coupled:
        warns.append(f"GNSS latency {chosen.latency_s * 1e3:.1f} +- {chosen.stderr_s * 1e3:.1f} ms from {label}"
                     + (": the front wheels turn with the measured wheel (all wheels driven?), so they are no "
                        "free-rolling reference" if q["fronts_driven"] else "")
                     + f" (candidates: {cand_txt})")
    return chosen, label, q, warns


# --------------------------------------------------------------------------- resampling
def _time_gaps(name: str, ts_ns: np.ndarray, nominal_s: float | None = None, nominal_src: str = "",
               *, parts: list | None = None) -> tuple[dict, float]:
    """Lost frames of a message without a counter and the period to filter it with.

    ``ts_ns`` int64 (n,) sorted receive times; ``nominal_s`` the nominal cycle
    time [s] (DBC ``GenMsgCycleTime`` or vehicle.toml ``cycle_time_s``, from
    ``nominal_src``) or None; ``parts`` frame ranges of joined parts (the time
    between them is not counted as loss). Returns ``(report, period_s)``:
    ``report`` dict(lost: int | None (unknown), gaps, longest_gap_s, received,
    method) with ``lost`` counted against the nominal cycle
    (:func:`.timebase.cycle_loss`; against the message's own period when it runs
    ``SLOWER_RATE_FACTOR`` or more times slower, hardly ever at the nominal interval: another
    rate, not lost frames); gaps are spacings over 2.5 periods;
    ``period_s`` the nominal period, else a robust estimate
    (:func:`.timebase.robust_period`).
    """
    n = int(ts_ns.shape[0])
    if n < 3:
        return {"lost": None, "gaps": 0, "longest_gap_s": 0.0, "received": n,
                "method": "too few frames: loss unknown"}, float("nan")
    est = robust_period(ts_ns)
    dt = np.diff(ts_ns) * 1e-9
    slower = None
    if nominal_s and est >= SLOWER_RATE_FACTOR * nominal_s and np.mean(np.abs(dt / nominal_s - 1.0) < 0.2) < 0.05:
        # hardly one interval at the nominal cycle: the sender runs at another rate (a receiver set to 10 Hz
        # where the DBC says 20), not one losing every other frame: its frames are counted against its own period
        slower, nominal_s = nominal_s, est
    period = float(nominal_s) if nominal_s else est
    lost, note = cycle_loss(ts_ns, nominal_s, breaks=parts)
    if parts and len(parts) > 1:  # the time between joined parts is no gap of the message
        dt[[a - 1 for a, _ in parts[1:]]] = 0.0
    big = dt > 2.5 * period if period > 0 else np.zeros(dt.shape, bool)
    if slower and lost is not None:
        method = (f"sent every {est * 1e3:.1f} ms, not at the nominal cycle time {slower * 1e3:g} ms ({nominal_src}): "
                  "frames counted against the period it keeps")
    elif nominal_s and lost is not None:
        method = f"frames counted against the nominal cycle time {nominal_s * 1e3:g} ms ({nominal_src})"
    elif nominal_s:
        method = note
    else:
        method = (f"no counter and no nominal cycle time (DBC GenMsgCycleTime or vehicle.toml "
                  f"cycle_time_s): loss unknown; period estimated {est * 1e3:.1f} ms")
    return {"lost": lost, "gaps": int(np.count_nonzero(big)),
            "longest_gap_s": float(dt[big].max()) if big.any() else 0.0,
            "received": n, "method": method}, period


#: A message without a counter whose frames come this many times slower than its nominal cycle, hardly
#: ever at the nominal interval, runs at another rate (:func:`_time_gaps`), it does not lose frames.
SLOWER_RATE_FACTOR = 1.5

#: Excluded spans listed one by one per kind; more are summarised in one entry.
MAX_EXCLUDED_LISTED = 50


#: Where each message's frames jump with a host clock step: within this [s] of the GPS-time
#: frames' jump (transport and buffering delays of one bus against another are far smaller).
CLOCK_STEP_TOL_S = 0.5


def _align_bus_clocks(dec: dict, sig: dict, cfg, path: Path, warns: list[str]) -> tuple[dict, dict | None]:
    """Put the wheel-speed module's bus on the transducer's bus's clock, when the two read the same
    wheel at moments that differ by more than a module's delay.

    The transducer's wheel angle (``wft_angle``) and the module's speed of the measured wheel
    (``wheel_speed``) describe one wheel; on one host clock their histories line up within the
    module's own delay (:data:`WSS_LAG_RANGE_S`, measured finely later).  A logger whose adapters stamp
    frames each on its own clock (device time since power-up), or two loggers joined, puts the buses
    seconds to hours apart: the forces are then paired with the slip of another moment, or with none.
    The offset is the shift at which the two speed histories correlate best
    (:func:`.timesync.estimate_clock_offset`, over every shift), refined on a 2 ms grid
    (:func:`.timesync.estimate_latency`); when it is clear and outside the module's delay range, every
    frame of the module's bus is moved back by it, loudly.  When the histories match at no shift near
    zero and no clear offset is found, it is said, and nothing is moved.

    ``dec`` message name -> :class:`DecodedMessage` (sorted times); ``sig`` the configured signals; ``cfg``
    the vehicle configuration (readings at a DBC range limit are left out); ``warns`` receives the messages.  Returns ``(dec, quality)``: ``quality`` None when the two are on
    one bus or either is missing, else ``{"bus", "reference_bus", "estimate_s", "corr", "corr_other",
    "corr_near_zero", "applied", "note"}``.  Never raises."""
    a_ref, b_ref = sig["wft_angle"], sig["wheel_speed"]
    ma, mb = dec.get(a_ref.message), dec.get(b_ref.message)
    if ma is None or mb is None or len(ma) < 100 or len(mb) < 100 or ma.bus == mb.bus:
        return dec, None
    t0 = min(int(ma.timestamp_ns[0]), int(mb.timestamp_ns[0]))
    ta = (ma.timestamp_ns - t0) * 1e-9
    ang = ma.signals[a_ref.signal] * a_ref.scale_to_si
    dt = np.diff(ta)
    ok = (dt > 0) & (dt < 0.05)
    with np.errstate(invalid="ignore", divide="ignore"):
        om_a = np.abs(np.where(ok, np.angle(np.exp(1j * np.diff(ang))) / np.where(ok, dt, 1.0), np.nan))
    t_mid = 0.5 * (ta[1:] + ta[:-1])
    tb = (mb.timestamp_ns - t0) * 1e-9
    om_b = mb.signals[b_ref.signal] * b_ref.scale_to_si
    om_b = np.abs(np.where(_at_range_limit(cfg, b_ref, om_b), np.nan, om_b))  # a pinned reading is no speed
    where = f"{b_ref.message} on {mb.bus} against {a_ref.message} on {ma.bus}"
    try:
        est = estimate_clock_offset(t_mid, om_a, tb, om_b, near_s=WSS_LAG_RANGE_S)
    except ValueError as exc:
        return dec, {"bus": mb.bus, "reference_bus": ma.bus, "estimate_s": None, "applied": False, "note": str(exc)}
    q = {"bus": mb.bus, "reference_bus": ma.bus, "estimate_s": est.offset_s, "corr": est.corr,
         "corr_other": est.corr_other, "corr_near_zero": est.corr_zero, "applied": False, "note": est.note}
    lo, hi = WSS_LAG_RANGE_S
    near = lo - 2 * CLOCK_GRID_S <= est.offset_s <= hi + 2 * CLOCK_GRID_S
    matches_near = np.isfinite(est.corr_zero) and (1 - est.corr ** 2) > CLOCK_DISTINCT_RATIO * (1 - est.corr_zero ** 2)
    if est.clear and not near and not matches_near:
        offset = est.offset_s
        period = float(np.median(dt[ok])) if ok.any() else 0.002
        try:  # refined as the module's delay is, around the coarse shift
            ref = filter_to_grid(t_mid, np.nan_to_num(om_a), period, t_mid, LATENCY_REF_CUTOFF_HZ)
            fine = estimate_latency(tb, om_b, t_mid, ref, usable_ref=np.isfinite(om_a),
                                    min_latency_s=offset - 2 * CLOCK_GRID_S, max_latency_s=offset + 2 * CLOCK_GRID_S)
            if not fine.note:
                offset = fine.latency_s
        except ValueError:
            pass
        shift = int(round(offset * 1e9))
        dec = {k: (dataclasses.replace(m, timestamp_ns=m.timestamp_ns - shift) if m.bus == mb.bus else m)
               for k, m in dec.items()}
        q.update(estimate_s=offset, applied=True)
        warns.append(f"CLOCK OFFSET BETWEEN BUSES: {path}: the frames of {mb.bus} are stamped {offset:+.3f} s from "
                     f"those of {ma.bus} for the same moment: the measured wheel's speed ({where}) matches only at "
                     f"that shift (correlation {est.corr:.4f}; at the module's own delay, {lo:g}..{hi:g} s, "
                     + (f"{est.corr_zero:.2f}" if np.isfinite(est.corr_zero) else "none: the buses' frames do not "
                        "overlap in time") + f"). Every {mb.bus} frame is moved back by it, so the forces and the slip "
                     "belong to one moment; check the logger's clocks (adapters stamping each on its own clock?); "
                     "ProcessResult.quality['bus_clocks']")
    elif not near and not matches_near and not (np.isfinite(est.corr_zero) and est.corr_zero >= CLOCK_MIN_CORR):
        warns.append(f"CLOCKS OF THE BUSES IN DOUBT: {path}: the measured wheel's speed ({where}) does not match at "
                     f"the module's own delay ({lo:g}..{hi:g} s: correlation "
                     + ("none, the two buses' frames do not overlap in time" if not np.isfinite(est.corr_zero)
                        else f"{est.corr_zero:.2f}")
                     + f"); the best shift, {est.offset_s:+.2f} s, is not clear ({est.note}): the buses' clocks may "
                     "be offset, and the forces paired with the slip of another moment; nothing moved; "
                     "ProcessResult.quality['bus_clocks']")
    return dec, q


def _gnss_far_shift(g_rel: np.ndarray, g_v: np.ndarray, refs: list, path: Path, g_msg: str,
                    warns: list[str]) -> tuple[float, dict | None]:
    """A first shift of the GNSS times when the GNSS velocity lies behind (or ahead of) the wheels' speed by
    about as much as the latency search range (:data:`LATENCY_MIN_S` .. :data:`LATENCY_MAX_S`) reaches, or
    more: a receiver on an adapter stamping on its own clock, or a very late one.  The fine estimators search
    only that range, and would all stop at its edge; slip would pair each wheel speed with the vehicle speed
    of another moment.

    ``g_rel`` (N,) GNSS times [s], ``g_v`` (N,) its speed [m/s]; ``refs`` [(times (M,) [s], r*omega (M,)
    [m/s])] free-rolling wheels' speeds (the front wheels', when they do not turn with the measured one: a
    driven wheel's speed leads the vehicle's by its slip), the first one with a clear answer used.  The
    coarse delay is the shift at which the two speed histories correlate best
    (:func:`.timesync.estimate_clock_offset`, every shift, 50 ms grid).  When it is clear and lies outside
    the range less two grid steps at its top, the GNSS times are shifted by it less the range's centre, so
    that the fine search is centred on it and measures the rest; the total is the latency reported.  Beyond
    the range, that is said loudly.  Returns ``(shift_s, quality or None)``, ``shift_s`` 0.0 when nothing is
    to be moved, quality ``{"estimate_s", "corr", "corr_other", "shift_s", "applied", "note"}``.
    Never raises."""
    q = None
    for t, v in refs:
        try:
            est = estimate_clock_offset(t, np.abs(v), g_rel, np.abs(g_v), near_s=(LATENCY_MIN_S, LATENCY_MAX_S))
        except ValueError:
            continue
        q = {"estimate_s": est.offset_s, "corr": est.corr, "corr_other": est.corr_other, "shift_s": 0.0,
             "applied": False, "note": est.note}
        if not est.clear:
            continue
        if LATENCY_MIN_S <= est.offset_s <= LATENCY_MAX_S - 2 * CLOCK_GRID_S:
            return 0.0, q
        shift = est.offset_s - 0.5 * (LATENCY_MIN_S + LATENCY_MAX_S)
        q.update(shift_s=shift, applied=True)
        if not LATENCY_MIN_S <= est.offset_s <= LATENCY_MAX_S:
            warns.append(f"GNSS BEYOND THE LATENCY SEARCH RANGE: {path}: the GNSS speed ({g_msg}) matches the "
                         f"wheels' speed best {est.offset_s:+.2f} s later (correlation {est.corr:.3f}; the next best "
                         f"shift more than {CLOCK_PEAK_SEPARATION_S:g} s away {est.corr_other:.2f}), outside the "
                         f"search range {LATENCY_MIN_S:g}..{LATENCY_MAX_S:g} s: the latency is searched around it "
                         "instead; a receiver on its own clock, or a very late one: check the logger's clocks; "
                         "ProcessResult.quality['latency']['pre_shift']")
        return shift, q
    return 0.0, q


def _undo_clock_steps(dec: dict, week_ref, tow_ref, path: Path, warns: list[str]) -> tuple[dict, list[dict]]:
    """Undo steps of the host clock that the GPS time in the frames shows
    (:func:`.timebase.find_clock_steps`): every frame logged after a step gets its host time
    moved by minus the step, so a forward step is neither a gap of lost frames nor a span of
    empty grid, and a step back is not two logs of the same time.  Each message's frames jump
    by the same step at one place in file order, next to the GPS-time frames' jump (within
    ``CLOCK_STEP_TOL_S``); a message that has frames near the step but no such jump, or more
    than one, means it is not a clock step: reported and left.

    ``dec`` message name -> :class:`DecodedMessage` in file order; ``week_ref``/``tow_ref`` the
    configured GPS week and time-of-week signals.  Returns ``(dec, steps)``: the messages with
    corrected times, and one dict per step found (``at_s`` host time since the first GPS frame,
    ``step_s``, ``undone``).
    """
    m = dec.get(tow_ref.message)
    if m is None or week_ref.message != tow_ref.message or len(m) < 2:
        return dec, []
    week = m.signals[week_ref.signal] * week_ref.scale_to_si
    tow = m.signals[tow_ref.signal] * tow_ref.scale_to_si
    gps_s = np.where((week > 0) | (tow > 0), week * 604800.0 + tow, np.nan)  # week 0, time 0: no fix
    tol = int(CLOCK_STEP_TOL_S * 1e9)
    steps, cuts = [], []
    for j, step_ns in find_clock_steps(m.timestamp_ns, gps_s):
        before, after = int(m.timestamp_ns[j]), int(m.timestamp_ns[j + 1])
        gap_ns = max(after - before - step_ns, 0)  # what GPS time says passed between the two frames
        at = {}  # message -> index of its first frame after the step
        odd = []
        for name, msg in dec.items():
            ts = msg.timestamp_ns
            jump = np.flatnonzero((np.abs(np.diff(ts) - step_ns) <= gap_ns + tol)
                                  & (ts[:-1] >= before - tol) & (ts[:-1] <= before + gap_ns + tol))
            near = np.count_nonzero((np.abs(ts - before) <= gap_ns + tol) | (np.abs(ts - after) <= gap_ns + tol))
            if jump.size == 1:
                at[name] = int(jump[0]) + 1
            elif jump.size or near:
                odd.append(name)
            elif step_ns > 0:  # no frame near a forward step: the later frames are those after it
                at[name] = int(np.searchsorted(ts, after - gap_ns))
            else:
                odd.append(name)
        at_s = (before - int(m.timestamp_ns[0])) * 1e-9
        steps.append({"at_s": at_s, "step_s": step_ns * 1e-9, "undone": not odd})
        if odd:
            warns.append(f"{path}: the host time jumps {_fmt_duration(step_ns * 1e-9)} against GPS time "
                         f"({tow_ref.message}) {at_s:.3f} s after its first frame, but {', '.join(odd)} do(es) not "
                         "jump with it: not a clock step, left as it is")
            continue
        cuts.append((step_ns, at))
        warns.append(f"{path}: the host clock stepped {_fmt_duration(step_ns * 1e-9)} {at_s:.3f} s after the first "
                     f"{tow_ref.message} frame while GPS time ran on (a clock sync during logging): every later "
                     "timestamp moved by minus the step; no frames were lost in it")
    if not cuts:
        return dec, steps
    out = {}
    for name, msg in dec.items():
        ts = msg.timestamp_ns.copy()
        for step_ns, at in cuts:
            ts[at[name]:] -= step_ns
        out[name] = dataclasses.replace(msg, timestamp_ns=ts)
    return out, steps


def _clean_time_base(dec: dict, path: Path, warns: list[str]):
    """Set aside outlier timestamps and sort joined parts of every decoded message.

    ``dec`` message name -> :class:`DecodedMessage` (file order). Returns
    ``(dec, runs, parts, quality)``: the messages with outliers removed and
    frames sorted by time; ``runs`` [(message, bus, run dict of
    :func:`.timebase.find_time_outliers`)]; ``parts`` message -> frame ranges of
    its joined parts in the sorted arrays (only for messages with > 1 part);
    ``quality`` dict(outlier_frames, outliers_by_message, joined_parts,
    non_monotonic). Raises ``ValueError`` (naming the file, message and bus)
    when joined parts overlap in time.
    """
    out: dict = {}
    runs_all: list = []
    parts_by_msg: dict = {}
    q = {"outlier_frames": 0, "outliers_by_message": {}, "joined_parts": 0, "non_monotonic": {}}
    for name, m in dec.items():
        ts = np.asarray(m.timestamp_ns, dtype=np.int64)
        if ts.shape[0] == 0:
            continue
        keep, runs = find_time_outliers(ts)
        nbad = int(np.count_nonzero(~keep))
        if nbad:
            q["outlier_frames"] += nbad
            q["outliers_by_message"][name] = nbad
            runs_all.extend((name, m.bus, r) for r in runs)
            r0 = runs[0]
            warns.append(f"{path}: {nbad} frame(s) of {name} ({m.bus}) with timestamps far outside their "
                         f"neighbours set aside, in {len(runs)} place(s); first at frame {r0['first']}: "
                         f"{_claim_text(r0)} (ProcessResult.excluded lists them)")
        ts_k = ts[keep]
        if ts_k.size == 0:
            warns.append(f"{path}: every frame of {name} ({m.bus}) has an outlier timestamp: {name} not used")
            continue
        try:
            parts = split_joined_parts(ts_k)
        except ValueError as exc:
            raise ValueError(f"{path}: {name} on bus {m.bus}: {exc}") from None
        order = np.argsort(ts_k, kind="stable")
        if len(parts) > 1:
            q["joined_parts"] = max(q["joined_parts"], len(parts) - 1)
            sizes = [b - a for a, b in sorted(parts, key=lambda p: int(ts_k[p[0]:p[1]].min()))]
            bounds = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
            sorted_parts = [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]
            parts_by_msg[name] = sorted_parts
            q["non_monotonic"].setdefault(m.bus, {})[name] = {
                "parts": len(parts),
                "backward_at_frames": [int(a) for a, _ in parts[1:]],
            }
            warns.append(f"{path}: {name} ({m.bus}): time runs backwards at frame(s) "
                         f"{', '.join(str(a) for a, _ in parts[1:])}: {len(parts)} parts joined out of order; "
                         "they do not overlap in time, so they were sorted by time (the time between them is "
                         "left empty and not counted as lost)")
        out[name] = DecodedMessage(m.bus, m.name, m.frame_id, m.is_extended, ts_k[order],
                                   {k: np.asarray(v)[keep][order] for k, v in m.signals.items()})
    return out, runs_all, parts_by_msg, q


def _fmt_duration(sec: float) -> str:
    a = abs(sec)
    if a >= 86400 * 365:
        return f"{sec / (86400 * 365.25):+.3g} years"
    if a >= 86400:
        return f"{sec / 86400:+.3g} days"
    if a >= 3600:
        return f"{sec / 3600:+.3g} h"
    if a >= 60:
        return f"{sec / 60:+.3g} min"
    return f"{sec:+.3g} s"


def _claim_text(run: dict) -> str:
    lo, hi = run["claimed_ns"]
    ref = run["before_ns"] if run["before_ns"] is not None else run["after_ns"]
    if lo <= -(2 ** 62) or hi >= 2 ** 62:
        what = "an impossible timestamp (a NaN or overflow stored as int64)"
    elif ref is None:
        what = "timestamps far from the rest"
    else:
        what = f"{_fmt_duration((lo - ref) * 1e-9)} from its neighbours"
    n = run["frames"]
    return f"{n} frame{'s' if n > 1 else ''} claiming {what}"


def _time_base_excluded(runs: list, parts: dict, dec: dict, t0_ns: int) -> list[dict]:
    """``ProcessResult.excluded`` entries for outlier timestamps (placed where they sit in
    the file: between their kept neighbours) and for the time between joined parts."""
    out = []
    per_msg: dict = {}
    for name, bus, r in runs:
        k = per_msg[name] = per_msg.get(name, 0) + 1
        if k > MAX_EXCLUDED_LISTED:
            continue
        a = r["before_ns"] if r["before_ns"] is not None else r["after_ns"]
        b = r["after_ns"] if r["after_ns"] is not None else r["before_ns"]
        out.append({"t0_s": (a - t0_ns) * 1e-9, "t1_s": (b - t0_ns) * 1e-9,
                    "reason": f"outlier timestamp: {name} ({bus}) frames {r['first']}-{r['last']}: "
                              f"{_claim_text(r)}; set aside",
                    "message": name, "bus": bus, "frames": r["frames"],
                    "claimed_t_s": [(c - t0_ns) * 1e-9 if abs(c) < 2 ** 62 else None for c in r["claimed_ns"]]})
    for name, k in per_msg.items():
        if k > MAX_EXCLUDED_LISTED:
            out.append({"t0_s": 0.0, "t1_s": 0.0, "message": name,
                        "reason": f"outlier timestamp: {k - MAX_EXCLUDED_LISTED} more places in {name} "
                                  "(not listed one by one)"})
    seen_bus = set()
    for name, rngs in parts.items():
        m = dec[name]
        if m.bus in seen_bus:
            continue
        seen_bus.add(m.bus)
        for (_, b), (c, _) in zip(rngs[:-1], rngs[1:]):
            out.append({"t0_s": (int(m.timestamp_ns[b - 1]) - t0_ns) * 1e-9,
                        "t1_s": (int(m.timestamp_ns[c]) - t0_ns) * 1e-9, "bus": m.bus,
                        "reason": f"between two parts of bus {m.bus} joined out of order (sorted by time): "
                                  "no data recorded"})
    return out


# --------------------------------------------------------------------------- log files
#: Log formats accepted besides MCAP (imported with ``wheelsoil.daq.convert.import_log`` first).
LOG_SUFFIXES = (".log", ".asc", ".blf", ".trc")


def _process_log(path: Path, *, config, rate_hz, cutoff_hz, progress, wheel_radius_m=None,
                 inertia=True, **wheel) -> "ProcessResult":
    """Import a candump/ASC/BLF/TRC log into a temporary MCAP, then process that."""
    import tempfile
    import warnings as _w

    from wheelsoil.daq import VehicleConfig, load_vehicle_config
    from wheelsoil.daq.convert import import_log

    cfg = config if isinstance(config, VehicleConfig) else load_vehicle_config(config)
    with tempfile.TemporaryDirectory(prefix="wheelsoil-process-") as tmp:
        mcap = Path(tmp) / (path.stem + ".mcap")
        with _w.catch_warnings():
            _w.simplefilter("ignore", RuntimeWarning)  # listed in conv.warnings
            conv = import_log(path, mcap, config=cfg)
        try:
            res = process_recording(mcap, config=cfg, rate_hz=rate_hz, cutoff_hz=cutoff_hz, progress=progress,
                                    wheel_radius_m=wheel_radius_m, inertia=inertia, **wheel)
        except ValueError as exc:  # name the log, not the temporary recording
            raise ValueError(str(exc).replace(str(mcap), str(path))) from None
    res.warnings[:] = [w.replace(str(mcap), str(path)) for w in res.warnings]
    res.warnings[:0] = [f"{path}: imported {sum(conv.frames.values())} frames "
                        f"({', '.join(f'{b}: {n}' for b, n in conv.frames.items())})"] + list(conv.warnings)
    return res


# --------------------------------------------------------------------------- main entry
def process_recording(path, *, config=None, rate_hz: float = 100.0, cutoff_hz: float | None = None,
                      wheel_radius_m: float | None = None, inertia: bool = True,
                      progress: bool = False, wheel_mass_kg: float | None = None,
                      wheel_inertia_kgm2: float | None = None) -> ProcessResult:
    """Decode, synchronise, filter and compute slip for one MCAP recording.

    Parameters: ``path`` ``.mcap`` recording (``wheelsoil log``/``import``), or a
    ``.log``/``.asc``/``.blf``/``.trc`` log (imported first, bus names as
    ``wheelsoil import`` gives them);
    ``config`` a ``VehicleConfig``, a vehicle TOML path, or None (the
    configuration attached to the recording, else ``dbc/vehicle.toml``);
    ``rate_hz`` output grid rate [Hz] (default 100); ``cutoff_hz`` low-pass
    cutoff [Hz] (default :data:`~.filters.DEFAULT_CUTOFF_HZ` = 5 Hz, capped at
    0.4 x ``rate_hz`` so it also serves as anti-alias filter);
    ``wheel_radius_m`` the radius r [m] for slip (Eq. 6), overriding the
    configuration's (a different value is reported in ``warnings``; the fit
    must use the same r: ``wheelsoil fit --wheel-radius`` passes it here);
    ``inertia`` compensate the wheel assembly's inertia (hardware.md:
    ``Dp = Fx + m_w dV/dt``, ``T = My - I_w domega/dt``, ``m_w``/``I_w`` from
    the configuration, or ``wheel_mass_kg`` [kg] and ``wheel_inertia_kgm2``
    [kg m^2] when given: a wheel other than the configured one; default on);
    ``progress`` shows a tqdm bar over the frames read.

    Returns :class:`ProcessResult` (columns :data:`COLUMNS`, one row per grid
    point from the first to the last frame of the messages processing reads,
    once frames with outlier timestamps are set aside and parts of logs joined
    out of order are sorted: :mod:`.timebase`; both reported in ``excluded``,
    ``quality`` and ``warnings``). Slip is Eq. (6) of the seed paper with
    r = ``wheel_radius_m`` or ``config.wheel_radius_m``.

    Raises: ``OSError`` unreadable file; ``ValueError`` not an MCAP
    recording, bad options (an implausible ``wheel_radius_m``, wheel mass or inertia), or a recording
    holding none of the configured messages (names what was looked for), parts
    of joined logs that overlap in time (names the message, bus and frames), or
    a run longer than :data:`~.timebase.MAX_GRID_ROWS` grid rows (memory bound). Missing parts (no GNSS, no wheel
    speed, no WFT, lost frames) are reported in ``warnings`` instead.
    """
    from wheelsoil.daq import iter_frame_batches
    from wheelsoil.daq.frames import DuplicateFrames, duplicate_frames_warning

    path = Path(path)
    if not 0 < rate_hz <= MAX_RATE_HZ:
        raise ValueError(f"rate must be > 0 Hz and at most {MAX_RATE_HZ:g} Hz (the transducer's 500 Hz twice over: "
                         f"a finer grid adds rows, not information), not {rate_hz}")
    cutoff = DEFAULT_CUTOFF_HZ if cutoff_hz is None else float(cutoff_hz)
    if not cutoff >= MIN_CUTOFF_HZ:
        raise ValueError(f"cutoff must be at least {MIN_CUTOFF_HZ:g} Hz, not {cutoff_hz}: a lower one smooths over "
                         "more than an accelerate cycle's seconds (and a filter that narrow is numerically unstable "
                         "at the transducer's sample rate)")
    warns: list[str] = []
    if cutoff > 0.4 * rate_hz:
        warns.append(f"cutoff {cutoff:g} Hz lowered to {0.4 * rate_hz:g} Hz (0.4 x the output rate, anti-alias)")
        cutoff = 0.4 * rate_hz
    if wheel_radius_m is not None:
        wheel_radius_m = check_wheel_radius(wheel_radius_m, "wheel_radius_m (--wheel-radius)")
    from wheelsoil.daq.config import check_vehicle_number

    wheel = {k: check_vehicle_number("command line", k, v, name=flag) for k, v, flag in (
        ("wheel_mass_kg", wheel_mass_kg, "--wheel-mass"), ("wheel_inertia_kgm2", wheel_inertia_kgm2, "--wheel-inertia"))
        if v is not None}
    if not path.exists():
        raise OSError(f"{path}: no such file")
    if path.suffix.lower() in LOG_SUFFIXES:
        return _process_log(path, config=config, rate_hz=rate_hz, cutoff_hz=cutoff_hz, progress=progress,
                            wheel_radius_m=wheel_radius_m, inertia=inertia, **wheel)
    cfg, cfg_where = _resolve_config(path, config, warns)
    if wheel:  # the wheel outboard of the transducer is not the configured one
        cfg = dataclasses.replace(cfg, **wheel)
    warns.extend(f"{cfg_where}: {n}" for n in (getattr(cfg, "notes", None) or []))
    cfg_r = float(cfg.wheel_radius_m)
    if wheel_radius_m is None:
        r = cfg_r
        r_source = f"from {cfg_where}"
    else:
        r = wheel_radius_m
        r_source = "given"
        if not math.isclose(r, cfg_r, rel_tol=1e-6):
            warns.append(f"WHEEL RADIUS CONFLICT: {r:g} m given, {cfg_where} says {cfg_r:g} m; slip (Eq. 6) "
                         f"is computed with the given {r:g} m (and the fit must use it too): check which "
                         "radius is right")
    sig = cfg.signals
    fronts = _front_wheel_refs(cfg)

    # ---- 1. decode only what is needed --------------------------------------------------
    refs = {k: sig[k] for k in ("wft_fx_w", "wft_fz_w", "wft_my", "wft_angle", "wft_counter_force",
                                "wft_counter_moment", "wft_counter_angle", "wheel_speed",
                                "gnss_speed", "gnss_forward_velocity", "gnss_time_week", "gnss_time_tow")}
    if "gnss_speed_3d" in sig:  # optional: the grade's correction of the horizontal GNSS speed
        refs["gnss_speed_3d"] = sig["gnss_speed_3d"]
    select: dict[str, set[str]] = {}
    for ref in list(refs.values()) + fronts:
        select.setdefault(ref.message, set()).add(ref.signal)
    for key in ("wft_fx_w", "wft_my", "wft_angle"):  # WFT Status, if the DBC has it
        msg = cfg.database(sig[key].bus).get_message_by_name(sig[key].message)
        if "Status" in [s.name for s in msg.signals]:
            select[sig[key].message].add("Status")
    validity = {}  # GNSS velocity key -> the receiver's validity flag of it in the same message, if the DBC has one
    accuracy = {}  # ... and its accuracy figure
    for key in ("gnss_forward_velocity", "gnss_speed"):
        msg = cfg.database(sig[key].bus).get_message_by_name(sig[key].message)
        names = [s.name for s in msg.signals]
        for found, flag in ((validity, _validity_signal(names, sig[key].signal)), (accuracy, _accuracy_signal(names))):
            if flag:
                found[key] = flag
                select[sig[key].message].add(flag)
    decoder = Decoder({bus: [cfg.database(bus)] for bus in cfg.buses}, select=select)
    screen = _FrameScreen({bus: [m for m in cfg.database(bus).messages if m.name in select] for bus in cfg.buses})

    span = [None, None]
    n_frames = [0]
    buses_seen: dict[str, int] = {}
    ids_seen: dict[str, set] = {}  # bus -> identifiers with frames (frame_key)

    # the reader's damage report (byte offset, frames lost, time span), where the daq
    # reader offers one (wheelsoil.daq.recording.ReadReport)
    read_report = None
    try:
        from wheelsoil.daq.recording import ReadReport

        read_report = ReadReport()
    except ImportError:
        pass

    copies = DuplicateFrames()  # a frame logged twice is one frame: counted, dropped

    def batches():
        it = iter_frame_batches(path) if read_report is None else iter_frame_batches(path, report=read_report)
        bar = None
        if progress:
            from tqdm import tqdm
            bar = tqdm(unit=" frames", unit_scale=True, desc=f"decode {path.name}")
        try:
            for b in it:
                b = copies(b)
                if len(b):
                    lo, hi = int(b.timestamp_ns.min()), int(b.timestamp_ns.max())
                    span[0] = lo if span[0] is None else min(span[0], lo)
                    span[1] = hi if span[1] is None else max(span[1], hi)
                    n_frames[0] += len(b)
                    buses_seen[b.bus] = buses_seen.get(b.bus, 0) + len(b)
                    ids_seen.setdefault(b.bus, set()).update(
                        np.unique(frame_key(b.arbitration_id, b.is_extended)).tolist())
                    if bar is not None:
                        bar.update(len(b))
                yield screen(b)
        finally:
            if bar is not None:
                bar.close()

    import warnings as _w

    with _w.catch_warnings(record=True) as caught:
        _w.simplefilter("always", RuntimeWarning)
        dec = decode_batches(batches(), decoder)
    # the reader's warnings (a truncated or damaged file) name the file
    warns += [str(c.message) for c in caught
              if issubclass(c.category, RuntimeWarning)
              and (str(path) in str(c.message) or path.name in str(c.message))]
    if copies.total:
        warns.append(duplicate_frames_warning(path, copies.dropped))
    if span[0] is None:
        raise ValueError(f"{path}: the recording holds no CAN frames" + _foreign_channels(read_report)
                         + "".join(f"; {w}" for w in warns))
    warns += screen.warnings(found={m.name for m in dec.values() if len(m)})
    mixed_up = bus_mix_up(cfg, select, {m.name for m in dec.values() if len(m)}, ids_seen, path,
                          _imported_from(read_report))
    if mixed_up:
        warns.append(mixed_up)

    def get(key_or_ref, measured: bool = False) -> tuple[np.ndarray, np.ndarray] | None:
        """(timestamps, SI values) of a configured signal; ``measured``: values at the DBC's range
        limit (:func:`_at_range_limit`) are NaN, with a warning (a clipped reading is no measurement)."""
        ref = sig[key_or_ref] if isinstance(key_or_ref, str) else key_or_ref
        m: DecodedMessage | None = dec.get(ref.message)
        if m is None or len(m) == 0:
            return None
        v = m.signals[ref.signal] * ref.scale_to_si
        if measured:
            at = _at_range_limit(cfg, ref, v)
            if at.any():
                v = np.where(at, np.nan, v)
                warns.append(f"{ref.message}.{ref.signal} ({ref.bus}): {int(at.sum())} of {at.size} values at the "
                             "DBC's range limit (clipped, or the 'not available' code): left out as lost")
        return m.timestamp_ns, v

    def label(key: str) -> str:
        return f"{sig[key].message}.{sig[key].signal} ({sig[key].bus})"

    if not any(sig[k].message in dec for k in refs):
        looked = ", ".join(sorted({f"{sig[k].message} on {sig[k].bus}" for k in refs}))
        seen = ", ".join(f"{b}: {n}" for b, n in buses_seen.items())
        raise ValueError(f"{path}: none of the configured messages found in {n_frames[0]} frames ({seen}) "
                         f"(looked for {looked}); "
                         + (mixed_up or "wrong vehicle configuration or bus names?")
                         + "".join(f"; {w}" for w in screen.warnings(found=set())))

    # ---- 1b. time base: outlier timestamps set aside, joined parts sorted ------------------
    dec, clock_steps = _undo_clock_steps(dec, sig["gnss_time_week"], sig["gnss_time_tow"], path, warns)
    dec, tb_runs, tb_parts, tb_quality = _clean_time_base(dec, path, warns)
    tb_quality["clock_steps"] = clock_steps
    dec, bus_clocks = _align_bus_clocks(dec, sig, cfg, path, warns)
    if not dec:
        raise ValueError(f"{path}: no frame of the configured messages has a usable timestamp")
    t0_ns = min(int(m.timestamp_ns[0]) for m in dec.values())
    t_end_ns = max(int(m.timestamp_ns[-1]) for m in dec.values())
    span_s = (t_end_ns - t0_ns) * 1e-9
    n_grid = int(math.floor(span_s * rate_hz)) + 1
    if n_grid > MAX_GRID_ROWS:
        raise ValueError(
            f"{path}: the run spans {span_s:.0f} s ({span_s / 3600:.1f} h) after setting aside "
            f"{tb_quality['outlier_frames']} frames with outlier timestamps: {n_grid} grid rows at {rate_hz:g} Hz, "
            f"more than the {MAX_GRID_ROWS} processing holds in memory; split the recording (or lower --rate)")
    t_grid = np.arange(n_grid) / rate_hz
    excluded: list[dict] = _time_base_excluded(tb_runs, tb_parts, dec, t0_ns)
    quality: dict = {"timestamps": {**tb_quality, "grid_rows": n_grid, "span_s": span_s}}
    if bus_clocks is not None:
        quality["bus_clocks"] = bus_clocks
    width = float(cfg.wheel_width_m)
    recorded = _recorded_wheel(read_report) if cfg_where == ASSUMED_CONFIG else None
    if recorded is not None and wheel_radius_m is None:  # the configuration is lost, the wheel is not
        r, width = recorded
        r_source = "from the recording's metadata (its attached configuration is not usable)"
        warns.append(f"VEHICLE CONFIGURATION ASSUMED: the wheel is the recording's own, {r:g} x {width:g} m, from its "
                     "metadata; the rest is the shipped default's")
    damage = list(getattr(read_report, "damage", None) or [])
    if damage:
        quality["damage"] = damage
        for d in damage:
            a, b = d.get("t0_ns"), d.get("t1_ns")
            lost = d.get("frames_lost")
            excluded.append({
                "t0_s": (a - t0_ns) * 1e-9 if a is not None else None,
                "t1_s": (b - t0_ns) * 1e-9 if b is not None else None,
                "reason": f"damaged recording ({d.get('kind')}) at byte {d.get('offset')}: "
                          f"{'unknown number of' if lost is None else lost} frames lost",
                "offset": d.get("offset")})

    def rel_s(ts_ns: np.ndarray) -> np.ndarray:
        return (ts_ns - t0_ns) * 1e-9

    lost_frames: dict[str, dict] = {}
    nan = np.full(n_grid, np.nan)

    # ---- 2. WFT -------------------------------------------------------------------------
    load = dp = torque = fx_f = my_f = nan
    wft_period = None
    wft_angle = None  # (t_w, angle) for the wheel-speed module's lag
    streams = {}
    for ckey, cols in (("wft_counter_force", ("wft_fx_w", "wft_fz_w")), ("wft_counter_moment", ("wft_my",)),
                       ("wft_counter_angle", ("wft_angle",))):
        cref = sig[ckey]
        m = dec.get(cref.message)
        if m is None or len(m) < 2:
            warns.append(f"no {cref.message} frames on {cref.bus}: "
                         + ", ".join(label(c) for c in cols) + " missing")
            continue
        columns = {}
        for c in cols + ((None,) if "Status" in m.signals else ()):
            if c is None:
                columns[f"status:{cref.message}"] = m.signals["Status"]
            elif sig[c].message == cref.message:
                columns[c] = m.signals[sig[c].signal] * sig[c].scale_to_si
        ts, counter = m.timestamp_ns, m.signals[cref.signal]
        whole = np.isfinite(counter)
        for v in columns.values():
            whole &= np.isfinite(v)
        if not whole.all():
            # NaN where the frame carries another multiplexer value than a signal's, else where the payload is
            # too short for the signal (a DLC mismatch)
            other_mux = _other_mux_value(cfg.database(cref.bus).get_message_by_name(cref.message), m.signals,
                                         [cref.signal] + [sig[c].signal for c in cols if c in columns])
            for what, bad in ((other_mux[0], ~whole & other_mux[1]), (None, ~whole & ~other_mux[1])):
                if not bad.any():
                    continue
                warns.append(f"WFT: {int(bad.sum())} {cref.message} frame(s) on {cref.bus} without a value in the "
                             + (f"counter or a signal (they carry {what}) dropped as lost samples" if what else
                                "counter or a signal (payload shorter than the DBC's layout: DLC mismatch) dropped "
                                "as lost samples"))
            if not whole.any() and other_mux[1].all():
                warns.append(f"WFT: no {cref.message} frame on {cref.bus} carries the multiplexer value of the "
                             f"configured signals ({other_mux[0]}): check the vehicle configuration's signals "
                             "against the DBC")
            ts, counter, columns = ts[whole], counter[whole], {k: v[whole] for k, v in columns.items()}
        if counter.size >= 2:
            streams[cref.message] = (ts, counter, columns)
    force_msg = sig["wft_counter_force"].message
    if streams:
        ref_msg = force_msg if force_msg in streams else next(iter(streams))
        try:
            cref = next(sig[k] for k in ("wft_counter_force", "wft_counter_moment", "wft_counter_angle")
                        if sig[k].message == ref_msg)
            bits = cfg.database(cref.bus).get_message_by_name(cref.message).get_signal_by_name(cref.signal).length
            ws = assemble_wft_samples(streams, reference=ref_msg, modulo=1 << min(int(bits), 62))
        except ValueError as exc:
            ws = None
            warns.append(f"WFT counters unusable ({exc}): load, drawbar pull and torque not computed")
            for name in streams:
                lost_frames[name] = {"lost": None, "gaps": 0, "longest_gap_s": 0.0,
                                     "received": int(streams[name][0].shape[0]),
                                     "method": "counter unusable: loss unknown"}
        if ws is not None:
            wft_period = ws.period_s
            if ws.stride > 1:
                quality["wft_counter_stride"] = ws.stride
                warns.append(f"WFT: the sample counter advances by {ws.stride} per frame: the transducer sends one "
                             f"sample in {ws.stride} ({1 / ws.period_s:.0f} Hz, one frame each {ws.period_s * 1e3:.2f} "
                             "ms; a decimated output rate); lost frames are counted in samples sent")
            for name, rep in ws.reports.items():
                # the time between joined parts was not recorded: not lost frames
                joints = set()
                if name in tb_parts:
                    t_s = streams[name][0]
                    rngs = tb_parts[name]
                    joints = {(int(t_s[b - 1]), int(t_s[c])) for (_, b), (c, _) in zip(rngs[:-1], rngs[1:])}
                if joints:
                    between = [g for g in rep.gaps if (g[0], g[1]) in joints]
                    rep.gaps = [g for g in rep.gaps if (g[0], g[1]) not in joints]
                    rep.lost -= sum(g[2] for g in between)
                longest = max(((b - a) * 1e-9 for a, b, _ in rep.gaps), default=0.0)
                lost_frames[name] = {"lost": rep.lost, "gaps": len(rep.gaps), "longest_gap_s": longest,
                                     "counter_jumps": rep.jumps,
                                     "received": int(streams[name][0].shape[0]),
                                     "method": f"counter, period {ws.period_s * 1e3:.2f} ms"
                                               + (f", counter step {ws.stride}" if ws.stride > 1 else "")}
            cols = ws.columns
            bad = np.zeros(ws.index.shape[0], dtype=bool)
            for k, v in cols.items():
                if k.startswith("status:"):
                    st = np.nan_to_num(v, nan=0).astype(np.int64)
                    bad |= (st & WFT_STATUS_BAD) != 0
                    if np.any(st & 0x80):
                        warns.append(f"{k[7:]}: WFT reports 'not zeroed since power-up' (Status bit 7) in "
                                     f"{np.count_nonzero(st & 0x80)} samples: force offsets may be wrong")
            if bad.any():
                warns.append(f"WFT Status flags overload/bridge/encoder fault in {np.count_nonzero(bad)} "
                             "samples: those samples are treated as lost")
            for k in ("wft_fx_w", "wft_fz_w", "wft_my"):  # clipped at the DBC's range: an overload the
                if k in cols:                                # Status did not flag
                    at = _at_range_limit(cfg, sig[k], cols[k]) & ~bad
                    if at.any():
                        bad |= at
                        warns.append(f"WFT: {label(k)} at the DBC's range limit in {int(at.sum())} samples "
                                     "(the transducer or its encoding clipped; Status did not flag it): those "
                                     "samples are treated as lost, like an overload")
            frames: dict[str, dict] = {}  # the force and moment channels by the frame (message) carrying them
            for k in ("wft_fx_w", "wft_fz_w", "wft_my"):
                if k in cols:
                    frames.setdefault(f"{sig[k].message} ({sig[k].bus})", {})[k] = np.where(bad, np.nan, cols[k])
            spikes = {f: m for f, m in frame_spikes(frames).items() if m.any()}
            if spikes:  # a glitch of one frame, not the wheel: a lost sample
                quality["wft_spikes"] = {f: int(m.sum()) for f, m in spikes.items()}
                for m in spikes.values():
                    bad |= m
                warns.append("WFT: samples far off their neighbours in one frame while the other frames' channels "
                             "stay on theirs (" + ", ".join(f"{n} of {f}" for f, n in quality["wft_spikes"].items())
                             + "): a glitch of that frame (bus or electrical), not the wheel, whose forces and moment "
                             "change together; those samples are treated as lost")
            t_w = rel_s(ws.timestamp_ns)
            my = np.where(bad, np.nan, cols["wft_my"]) if "wft_my" in cols else None
            if all(k in cols for k in ("wft_fx_w", "wft_fz_w", "wft_angle")):
                cols["wft_angle"], jumps = angle_jumps(cols["wft_angle"])
                if jumps:
                    quality["wft_angle_jumps"] = [{"t_s": float(t_w[r]), "jump_deg": math.degrees(j)}
                                                  for r, j in jumps]
                    warns.append(f"WFT: the wheel angle jumps {len(jumps)} time(s) within one sample ("
                                 + ", ".join(f"{math.degrees(j):+.2f} deg at t = {t_w[r]:.2f} s" for r, j in jumps[:5])
                                 + (", ..." if len(jumps) > 5 else "") + "), more than the wheel can turn: the "
                                 "encoder lost or gained counts. Each jump is taken out of the later angles, so the "
                                 "forces are rotated to the hub with the wheel's angle; check the encoder")
                fx, fz = rotate_to_hub(cols["wft_fx_w"], cols["wft_fz_w"], cols["wft_angle"])
                fx[bad] = np.nan
                fz[bad] = np.nan
                ripple = rotation_ripple(fx, fz, cols["wft_angle"], t_w, my=my)
                if ripple is not None:  # no steady model has a part locked to the wheel angle: taken out
                    fx = remove_ripple(fx, cols["wft_angle"], ripple["coef"]["fx"])
                    fz = remove_ripple(fz, cols["wft_angle"], ripple["coef"]["fz"])
                    if "my" in ripple["coef"]:
                        my = remove_ripple(my, cols["wft_angle"], ripple["coef"]["my"])
                    ripple["removed"] = [f"{ch}_{o + 1}x" for ch, c in ripple["coef"].items() for o in (0, 1)
                                         if c[2 * o] or c[2 * o + 1]]
                quality["wft_ripple"] = ripple
                wft_angle = (t_w, np.where(bad, np.nan, cols["wft_angle"]))
                w_mean = float(np.nanmean(fz)) if np.isfinite(fz).any() else float("nan")
                for order in (2, 1) if ripple is not None and w_mean > 0 else ():
                    amp = max(ripple[f"fx_{order}x_n"], ripple[f"fz_{order}x_n"])
                    if amp >= WFT_RIPPLE_REL * w_mean:
                        why = (f"the two in-plane bridges read with different gains (about {200 * amp / w_mean:.0f} %)"
                               if order == 2 else
                               "an offset in a rotating channel (the transducer not zeroed), or a wheel or tyre out "
                               "of round")
                        gone = any(r.endswith(f"_{order}x") for r in ripple["removed"])
                        warns.append(f"WFT: the hub forces carry {amp:.0f} N ({100 * amp / w_mean:.1f} % of the mean "
                                     f"load) {'twice' if order == 2 else 'once'} per wheel revolution: {why}; "
                                     + ("taken out of the forces before filtering (fitted on the wheel angle); "
                                        if gone else "") + "check the transducer's calibration")
                fx_f = filter_to_grid(t_w, fx, ws.period_s, t_grid, cutoff)
                load = filter_to_grid(t_w, fz, ws.period_s, t_grid, cutoff)
            else:
                warns.append("WFT force or angle frames missing: load_n and drawbar_pull_n not computed (NaN)")
            if my is not None:
                my_f = filter_to_grid(t_w, my, ws.period_s, t_grid, cutoff)
            else:
                warns.append("WFT moment frames missing: torque_nm not computed (NaN)")
            total_lost = sum(rep.lost for rep in ws.reports.values())
            joint_spans = [(e["t0_s"], e["t1_s"]) for e in excluded if "joined out of order" in e["reason"]]
            long_runs = [(a, b) for a, b in segments(~ws.complete) if b - a > MAX_FILL_SAMPLES
                         and not any(t_w[max(a - 1, 0)] <= j1 and t_w[min(b, t_w.size - 1)] >= j0
                                     and (b - a) * ws.period_s > 0.5 * (j1 - j0) for j0, j1 in joint_spans)]
            for a, b in long_runs[:MAX_EXCLUDED_LISTED]:
                excluded.append({"t0_s": float(t_w[max(a - 1, 0)]), "t1_s": float(t_w[min(b, t_w.size - 1)]),
                                 "reason": f"WFT: {b - a} samples lost (counter gap longer than "
                                           f"{MAX_FILL_SAMPLES} samples): left invalid, not interpolated"})
            if len(long_runs) > MAX_EXCLUDED_LISTED:
                excluded.append({"t0_s": float(t_w[long_runs[MAX_EXCLUDED_LISTED][0]]),
                                 "t1_s": float(t_w[min(long_runs[-1][1], t_w.size - 1)]),
                                 "reason": f"WFT: {len(long_runs) - MAX_EXCLUDED_LISTED} more gaps longer than "
                                           f"{MAX_FILL_SAMPLES} samples (not listed one by one)"})
            if total_lost:
                runs = [b - a for a, b in segments(~ws.complete)]
                long_gaps = sum(1 for k in runs if k > MAX_FILL_SAMPLES)
                warns.append(f"WFT: {total_lost} frames lost (counter gaps) in {len(runs)} gaps; gaps of up "
                             f"to {MAX_FILL_SAMPLES} samples interpolated, {long_gaps} longer ones left invalid")
            n_jumps = {k: rep.jumps for k, rep in ws.reports.items() if rep.jumps}
            if n_jumps:
                warns.append("WFT counter jumped without time passing (" + ", ".join(
                    f"{k}: {v}x" for k, v in n_jumps.items()) + "): treated as counter errors, the clock's "
                    "sample count used instead; check the transducer/cabling")
    else:
        warns.append("no WFT frames at all: load_n, drawbar_pull_n and torque_nm are NaN; slip and speed "
                     "still computed")

    # ---- 3a. wheel speeds -----------------------------------------------------------------
    omega = domega = omega_raw = nan
    ws_ref = sig["wheel_speed"]
    got = get("wheel_speed", measured=True)
    wss_t = wss_rel = None
    wss_lag = None  # the module's lag behind the transducer's clock, when removed (for _unlag)
    if got is not None and got[0].shape[0] < 3:
        warns.append(f"only {got[0].shape[0]} wheel speed frames ({label('wheel_speed')}): not used")
        got = None
    if got is None:
        warns.append(f"no wheel speed ({label('wheel_speed')}): omega_radps and slip are NaN; "
                     "forces and speed still computed")
    else:
        wss_t, w_rl = got
        rep, period = _time_gaps(ws_ref.message, wss_t, *cfg.cycle_time_s(ws_ref.bus, ws_ref.message),
                                 parts=tb_parts.get(ws_ref.message))
        lost_frames[ws_ref.message] = rep
        wss_rel = rel_s(wss_t)
        angle_rate = None  # the wheel's speed from the transducer's angle: the module's lag and scale are read on it
        if wft_angle is not None:
            try:
                angle_rate = _angle_rate(*wft_angle, wft_period)
                lag, tooth = _wheel_speed_lag(*angle_rate, wss_rel, w_rl, r, period)
            except ValueError as exc:
                quality["wheel_speed_lag"] = {"estimate_s": None, "applied": False, "note": str(exc)}
                if angle_rate is None:
                    quality["wheel_speed_scale"] = _scale_not_found(str(exc))
            else:
                why = _lag_not_applied(lag)
                why_t = _tooth_not_applied(tooth, lag)
                quality["wheel_speed_lag"] = q_lag = {"estimate_s": lag.latency_s, "stderr_s": lag.stderr_s,
                                                      "gain": lag.gain, "applied": not why or not why_t, "note": why}
                if isinstance(tooth, ToothLag):
                    q_lag["per_tooth"] = {"lag_s": tooth.lag_s, "stderr_lag_s": tooth.stderr_lag_s,
                                          "pitch_rad": tooth.pitch_rad, "stderr_pitch_rad": tooth.stderr_pitch_rad,
                                          "teeth": 2 * math.pi / tooth.pitch_rad if tooth.pitch_rad > 0 else None,
                                          "applied": not why_t, "note": why_t}
                if not why_t:
                    wss_lag = tooth
                    q_lag["note"] = "the per-tooth delay is removed instead (per_tooth)"
                    warns.append(f"the wheel speeds ({ws_ref.message}) read late against the transducer's clock (its "
                                 f"wheel angle), and later as the wheel slows: {tooth.lag_s * 1e3:.1f} ms + "
                                 f"{tooth.pitch_rad:.3g} rad / omega (a tone wheel timed per tooth; pitch "
                                 f"{tooth.pitch_rad:.3g} +- {tooth.stderr_pitch_rad:.2g} rad, "
                                 f"~{2 * math.pi / tooth.pitch_rad:.0f} teeth): each reading moved back by its "
                                 "delay, so slip belongs to the moment of the forces; "
                                 "ProcessResult.quality['wheel_speed_lag']")
                elif not why:
                    wss_lag = lag.latency_s
                    warns.append(f"the wheel speeds ({ws_ref.message}) read {lag.latency_s * 1e3:.1f} +- "
                                 f"{lag.stderr_s * 1e3:.1f} ms late against the transducer's clock (its wheel "
                                 "angle): their times moved back by that much, so slip belongs to the moment "
                                 "of the forces; ProcessResult.quality['wheel_speed_lag']")
                if wss_lag is not None:
                    wss_t, w_rl = _unlag(wss_t, w_rl, wss_lag)
                    got = (wss_t, w_rl)
                    wss_rel = rel_s(wss_t)
        if angle_rate is not None:  # the module's scale against the transducer's angle (a tooth count)
            quality["wheel_speed_scale"] = sc = _wheel_speed_scale(*angle_rate, wss_rel, w_rl, period)
            if sc["applied"]:
                w_rl = w_rl / sc["gain"]
                got = (wss_t, w_rl)
                warns.append(f"WHEEL SPEED SCALE CORRECTED: the wheel speed ({label('wheel_speed')}) reads "
                             f"{sc['gain']:.4f} times the rate of the transducer's wheel angle ({label('wft_angle')}; "
                             f"median over {sc['n']} readings, scatter {sc['spread']:.2g}), which measures the same "
                             "wheel's rotation and wraps once per revolution: the module's tone-wheel tooth count or "
                             f"scale is configured {100 * abs(sc['gain'] - 1):.1f} % off (48 teeth read as 50 is "
                             "0.96); its speed is divided by that gain for slip (Eq. 6). Check the module's "
                             "configuration; ProcessResult.quality['wheel_speed_scale']")
        omega, domega = filter_to_grid(wss_rel, w_rl, period, t_grid, cutoff, derivative=True)
        # the wheel speed as the module reports it (low-passed just below its Nyquist frequency only)
        omega_raw = filter_to_grid(wss_rel, w_rl, period, t_grid, max(cutoff, 0.4 / period) if period and period > 0
                                   else cutoff)

    # ---- 3a'. inertia: T = My - I_w domega/dt (hardware.md) ------------------------------
    m_w, i_w = float(cfg.wheel_mass_kg), float(cfg.wheel_inertia_kgm2)
    torque = my_f - i_w * domega if inertia else my_f
    if inertia and np.isfinite(my_f).any() and not np.isfinite(domega).any():
        warns.append("inertia compensation needs the wheel speed (domega/dt): torque_nm is NaN; "
                     "my_nm has the measured, uncompensated My")

    # ---- 3b. GNSS speed, GPS time, latency ---------------------------------------------
    speed = dspeed = nan
    latency: LatencyEstimate | None = None
    lat_ref = ""
    g_fwd, g_spd = get("gnss_forward_velocity"), get("gnss_speed")
    for key, g in (("gnss_forward_velocity", g_fwd), ("gnss_speed", g_spd)):
        if g is not None and g[0].shape[0] < 3:
            warns.append(f"only {g[0].shape[0]} frames of {label(key)}: not used")
    g_fwd = g_fwd if g_fwd is not None and g_fwd[0].shape[0] >= 3 else None
    g_spd = g_spd if g_spd is not None and g_spd[0].shape[0] >= 3 else None
    g_key = "gnss_forward_velocity" if g_fwd is not None else "gnss_speed"
    if g_fwd is not None:
        g_t, g_v = g_fwd
        g_msg = sig["gnss_forward_velocity"].message
    elif g_spd is not None:
        g_t, g_v = g_spd
        g_msg = sig["gnss_speed"].message
        warns.append(f"no {label('gnss_forward_velocity')}: using the unsigned ground speed "
                     f"{label('gnss_speed')} as V (reversing cannot be told apart)")
    else:
        g_t = g_v = None
        g_msg = ""
        warns.append(f"no GNSS velocity ({label('gnss_forward_velocity')} or {label('gnss_speed')}): "
                     "speed_mps, slip and the latency are not computed, all samples invalid; load, "
                     "drawbar pull, torque and wheel speed still computed")
    gps_map = None
    gt = get("gnss_time_tow")
    gw = get("gnss_time_week")
    if gt is None or gw is None or len(gt[0]) != len(gw[0]):
        warns.append(f"no GPS time frames ({label('gnss_time_tow')}): no host->GPS time mapping")
    else:
        try:
            gps_map = fit_gps_time_mapping(gt[0], gw[1], gt[1], t0_ns=t0_ns)
        except ValueError as exc:
            warns.append(f"GPS time mapping not possible: {exc}")
    flag = dec[g_msg].signals.get(validity[g_key]) if g_t is not None and g_key in validity else None
    if flag is not None and np.any(flag == 0):  # the receiver says these values are not measured (no fix)
        bad = flag == 0
        g_v = np.where(bad, np.nan, g_v)
        warns.append(f"GNSS: {int(bad.sum())} of {bad.size} {label(g_key)} frames flagged invalid by the receiver "
                     f"({validity[g_key]} = 0, e.g. no fix): left out as lost, so speed and slip are NaN there")
    acc = dec[g_msg].signals.get(accuracy[g_key]) if g_t is not None and g_key in accuracy else None
    if acc is not None and np.isfinite(g_v).any():
        typical = float(np.nanmedian(acc[np.isfinite(g_v)]))
        bad = np.isfinite(g_v) & (acc >= GNSS_ACCURACY_DEGRADED * typical)
        if typical > 0 and bad.any():  # a figure of 0 says nothing
            g_v = np.where(bad, np.nan, g_v)
            t_rel = rel_s(g_t)
            spans = [(float(t_rel[a]), float(t_rel[b - 1])) for a, b in segments(bad)]
            quality["gnss_degraded_spans_s"] = spans
            warns.append(f"GNSS: {int(bad.sum())} of {bad.size} {label(g_key)} frames with the receiver's accuracy "
                         f"figure ({accuracy[g_key]}) {GNSS_ACCURACY_DEGRADED:g} or more times its median over the run "
                         f"({typical:g}), in {len(spans)} span(s) ("
                         + ", ".join(f"{a:.1f}-{b:.1f} s" for a, b in spans[:5]) + (", ..." if len(spans) > 5 else "")
                         + "): a degraded solution (few satellites, the INS coasting; its velocity drifts while "
                         "flagged valid), left out as lost, so speed and slip are NaN there")
    if g_t is not None:
        g_bus = dec[g_msg].bus
        rep, g_period = _time_gaps(g_msg, g_t, *cfg.cycle_time_s(g_bus, g_msg), parts=tb_parts.get(g_msg))
        lost_frames[g_msg] = rep
        g_rel = rel_s(g_t)
        g3 = get("gnss_speed_3d") if "gnss_speed_3d" in sig else None
        if g3 is not None and g_spd is not None:  # V along the ground on a grade (Eq. 6)
            k = _grade_factor(rel_s(g_spd[0]), g_spd[1], rel_s(g3[0]), g3[1], g_period, g_rel)
            if k is not None:
                g_v = g_v * k
                grade = float(np.degrees(np.arccos(1.0 / k.max())))
                quality["grade"] = {"max_deg": grade, "max_factor": float(k.max())}
                warns.append(f"GNSS speed on a grade: {label(g_key)} is horizontal; the run climbs or descends "
                             f"up to {grade:.1f} deg ({100 * math.tan(math.radians(grade)):.0f} %), found from "
                             f"{label('gnss_speed_3d')} over {label('gnss_speed')}: V is taken along the ground "
                             f"(x 1/cos(grade), up to x{k.max():.4f}) for slip (Eq. 6). If the transducer's weight "
                             "compensation assumes level ground (hardware.md does not say), up to m_w g sin(grade) = "
                             f"{m_w * 9.81 * math.sin(math.radians(grade)):.0f} N of the wheel's weight stays in Fx, "
                             "against the drawbar pull climbing and with it descending (which of the two, no message "
                             "tells): it is not taken out")
        # the first shift needs free-rolling wheels: a driven wheel's speed leads the vehicle's by its slip
        # (a 4x4's sweeps matched 0.9 s late)
        f_ser = [s_ for s_ in (get(f, measured=True) for f in fronts) if s_ is not None and s_[0].shape[0] >= 3]
        refs = []
        if f_ser and wss_t is not None:
            fv0 = _fronts_speed(f_ser, r)
            if not _fronts_coupled(f_ser[0][0], fv0, wss_t, got[1] * r):
                refs = [(rel_s(f_ser[0][0]), fv0)]
        g_pre, pre_q = _gnss_far_shift(g_rel, g_v, refs, path, g_msg, warns)
        g_rel = g_rel - g_pre
        # latency candidates (docs/architecture.md "GNSS latency"): a wheel-speed reference
        # (free-rolling front wheels, else the measured wheel at low torque), the measured wheel's
        # slip-traction consistency, and the vehicle dynamics; combined in _choose_latency
        cands: dict[str, LatencyEstimate] = {}
        errs: dict[str, str] = {}
        if np.isfinite(omega).any() and np.isfinite(torque).any() and np.isfinite(load).any():
            with np.errstate(invalid="ignore", divide="ignore"):
                coeff = np.where(load > LATENCY_MIN_LOAD_N, torque / (r * load), np.nan)
            try:
                cands["traction"] = estimate_latency_traction(g_rel, g_v, t_grid, r * omega, coeff, load_n=load,
                                                              max_latency_s=LATENCY_MAX_S,
                                                              min_latency_s=LATENCY_MIN_S)
            except ValueError as exc:
                errs["traction"] = str(exc)
        else:
            errs["traction"] = "needs the measured wheel's speed, torque and load"
        f_raw = [(f, s) for f, s in ((f, get(f, measured=True)) for f in fronts)
                 if s is not None and s[0].shape[0] >= 3]
        # the module's lag was measured on the measured wheel: its front channels share it (a common
        # delay: a gateway, the frame's cycle, a module timing every wheel per tooth) or not (a filter in
        # one sensor, fronts read by another module). A constant lag: both are tried when the fronts are
        # in the module's message, and the one whose GNSS latency agrees better with the slip-traction
        # estimate (which needs no front wheel) is kept. A per-tooth delay: the fronts' own delay against
        # the GNSS speed says whether it grows as they slow by the measured wheel's pitch or not at all
        # (:func:`_fronts_pitch`); each reading then moves back at its own wheel's speed.
        fronts_in = wss_lag is not None and any(f.message == ws_ref.message for f, _ in f_raw)
        shared = [wss_lag] + ([None] if fronts_in and isinstance(wss_lag, float) else [])
        if fronts_in and isinstance(wss_lag, ToothLag):
            quality["wheel_speed_lag"]["fronts_pitch"] = fp = _fronts_pitch(
                [s for f, s in f_raw if f.message == ws_ref.message], rel_s, g_rel, g_v, g_period, r, wss_lag)
            if fp["shared"] is False:
                shared = [None]

        def wheel_reference(shift):
            """The wheel-reference latency with the fronts in the module's message moved back by ``shift`` (the
            module's lag, for :func:`_unlag`): (estimate, or why there is none; fronts coupled to the measured
            wheel; fronts the reference; label)."""
            ref_t = ref_v = usable = None
            label_ = ""
            f_series = [_unlag(*s, shift if f.message == ws_ref.message else None) for f, s in f_raw]
            coupled_ = False
            if f_series:
                ft = f_series[0][0]
                fv = _fronts_speed(f_series, r)
                coupled_ = wss_t is not None and _fronts_coupled(ft, fv, wss_t, got[1] * r)
            front = bool(f_series) and not coupled_
            if front:
                ref_t, ref_v = rel_s(ft), fv
                label_ = "front wheels r*omega (" + ", ".join(f.signal for f, _ in f_raw) + ")"
            elif wss_t is not None and np.isfinite(torque).any():
                # no front wheel rolls freely (none logged, or the 4x4 drives them): the measured wheel
                # where it transmits no torque does (coasting, another axle braking); its transducer
                # reads a brake torque too, so no deceleration limit is needed
                ref_t, ref_v = wss_rel, got[1] * r
                tq = np.interp(ref_t, t_grid, np.nan_to_num(torque, nan=1e9))
                usable = _sustained(np.abs(tq) < FREE_ROLLING_TORQUE_NM, ref_t, FREE_ROLLING_HOLD_S)
                label_ = f"measured wheel r*omega where |T| < {FREE_ROLLING_TORQUE_NM:g} N m"
            est_: LatencyEstimate | str = "no free-rolling wheel speed to compare with"
            if ref_t is not None:
                _, ref_period = _time_gaps("ref", (ref_t * 1e9).astype(np.int64))
                ref_f = filter_to_grid(ref_t, ref_v, ref_period, ref_t, LATENCY_REF_CUTOFF_HZ)
                if front:  # a braked front wheel may skid
                    usable = np.gradient(np.nan_to_num(ref_f), ref_t) > -LATENCY_MAX_DECEL_MPS2
                try:
                    est_ = estimate_latency(g_rel, g_v, ref_t, ref_f, usable_ref=usable,
                                            max_latency_s=LATENCY_MAX_S, min_latency_s=LATENCY_MIN_S)
                except ValueError as exc:
                    est_ = str(exc)
            return est_, coupled_, front, label_

        tr0 = cands.get("traction")

        def off_traction(est_) -> float:  # how far from the slip-traction estimate (inf: not comparable)
            ok = isinstance(est_, LatencyEstimate) and tr0 is not None and not tr0.note
            return abs(est_.latency_s - tr0.latency_s) if ok else math.inf

        # the shift whose estimate agrees best (on a tie the first: the module's lag)
        shift, est, coupled, front_ref, wheel_ref_label = min(
            ((sh, *wheel_reference(sh)) for sh in shared), key=lambda t: off_traction(t[1]))
        if fronts_in:
            quality["wheel_speed_lag"]["fronts_shifted"] = shift is not None
            if shift is None:
                warns.append("the front wheels' speeds are not as late as the measured wheel's ("
                             + (f"their delay against the GNSS speed grows by {fp['pitch_rad']:.3g} +- "
                                f"{fp['stderr_pitch_rad']:.2g} rad / omega as they slow, the measured wheel's by "
                                f"{wss_lag.pitch_rad:.3g} rad / omega" if isinstance(wss_lag, ToothLag) else
                                "the GNSS latency against them agrees with the slip-traction estimate only "
                                "unshifted")
                             + "): only the measured wheel's times were moved back")
        if isinstance(est, LatencyEstimate):
            cands["wheel_reference"] = est
        else:
            errs["wheel_reference"] = est
        alt = _force_latency(g_rel, g_v, g_period, t_grid, fx_f, min(cutoff, 0.4 / g_period))
        if alt is not None:
            cands["dynamics"] = alt
        else:
            errs["dynamics"] = "needs the measured Fx and the GNSS speed"
        if g_pre:  # the estimates measured from the first shift: each the whole delay
            cands = {k: dataclasses.replace(c, latency_s=c.latency_s + g_pre) for k, c in cands.items()}
            g_rel = g_rel + g_pre
        latency, lat_ref, quality["latency"], lat_warns = _choose_latency(
            cands, errs, coupled=coupled, wheel_ref_label=wheel_ref_label, fronts=front_ref,
            speed_rms_mps=float(np.sqrt(np.nanmean(g_v ** 2))) if np.isfinite(g_v).any() else None)
        warns.extend(lat_warns)
        if pre_q is not None:
            quality["latency"]["pre_shift"] = pre_q
        shift = latency.latency_s if latency is not None else g_pre
        speed, dspeed = filter_to_grid(g_rel - shift, g_v, g_period, t_grid, min(cutoff, 0.4 / g_period),
                                       derivative=True)

    # ---- 3c. inertia: Dp = Fx + m_w dV/dt (hardware.md) ----------------------------------
    dp = fx_f + m_w * dspeed if inertia else fx_f
    if inertia and np.isfinite(fx_f).any() and not np.isfinite(dspeed).any():
        warns.append("inertia compensation needs the vehicle speed (dV/dt): drawbar_pull_n is NaN; "
                     "fx_n has the measured, uncompensated Fx")
    if inertia:
        corr_f = m_w * dspeed[np.isfinite(fx_f) & np.isfinite(dspeed)]
        corr_t = i_w * domega[np.isfinite(my_f) & np.isfinite(domega)]
        inertia_info = {
            "applied": True, "wheel_mass_kg": m_w, "wheel_inertia_kgm2": i_w,
            "max_abs_force_n": float(np.max(np.abs(corr_f))) if corr_f.size else None,
            "max_abs_torque_nm": float(np.max(np.abs(corr_t))) if corr_t.size else None,
            "method": "Dp = Fx + m_w dV/dt, T = My - I_w domega/dt; dV/dt and domega/dt are derivatives "
                      "(cubic spline) of V and omega after the same zero-phase low-pass as Fx and My",
            "source": cfg_where if not wheel else f"{', '.join(k for k in wheel)} given, else {cfg_where}",
        }
    else:
        inertia_info = {"applied": False, "wheel_mass_kg": m_w, "wheel_inertia_kgm2": i_w,
                        "max_abs_force_n": None, "max_abs_torque_nm": None,
                        "reason": "switched off (inertia=False / --no-inertia)", "source": cfg_where}
        warns.append("inertia not compensated (--no-inertia): drawbar_pull_n and torque_nm include the wheel "
                     f"assembly's inertia (m_w = {m_w:g} kg, I_w = {i_w:g} kg m^2)")

    # ---- 4. slip, phase, cycles, valid --------------------------------------------------------
    rw = r * omega
    slip, in_range = slip_ratio(rw, speed, min_wheel_speed_mps=MIN_WHEEL_SPEED_MPS)
    phase = classify_phases(t_grid, speed, rw, torque)
    cycle = accel_cycles(t_grid, phase)
    valid = in_range & np.isfinite(load) & np.isfinite(dp) & np.isfinite(torque)
    sd_s = unresolved_slip_sd(omega_raw, omega, slip, rate_hz, cutoff)
    unsteady = valid & (sd_s > UNSTEADY_SLIP_SD)
    if unsteady.any():
        valid &= ~unsteady
        spans = segments(unsteady)
        for a, b in spans[:MAX_EXCLUDED_LISTED]:
            excluded.append({"t0_s": float(t_grid[a]), "t1_s": float(t_grid[b - 1]),
                             "reason": f"wheel speed unsteady: the slip spreads by up to {np.max(sd_s[a:b]):.2f} "
                                       f"(sd) within {1 / cutoff:.2g} s, unresolved by the {cutoff:g} Hz low-pass: "
                                       "not valid"})
        quality["unsteady_slip"] = {"seconds": float(np.count_nonzero(unsteady) / rate_hz), "spans": len(spans),
                                    "max_sd": float(np.max(sd_s[unsteady])), "threshold_sd": UNSTEADY_SLIP_SD}
        warns.append(f"WHEEL SPEED UNSTEADY: in {np.count_nonzero(unsteady) / rate_hz:.1f} s of the valid samples "
                     f"({len(spans)} spans) the wheel speed ({label('wheel_speed')}) oscillates faster than the "
                     f"{cutoff:g} Hz low-pass resolves (stick-slip, wheel hop, a driveline oscillating): the slip "
                     f"spreads by up to {float(np.max(sd_s[unsteady])):.2f} (sd; limit {UNSTEADY_SLIP_SD}) within "
                     f"{1 / cutoff:.2g} s, so the filtered forces average over slips that the filtered slip does "
                     "not show, and that slip is biased; these samples are not valid (not fitted; "
                     "ProcessResult.excluded lists the spans)")
    moving = np.isfinite(rw) & np.isfinite(speed)
    undefined = moving & (np.abs(rw) < MIN_WHEEL_SPEED_MPS)
    if undefined.any():
        runs = segments(undefined)
        longest = max(b - a for a, b in runs) / rate_hz
        fast = undefined & (np.abs(speed) > 0.5)
        why = (f"; in {np.count_nonzero(fast) / rate_hz:.1f} s of them the vehicle moved (V > 0.5 m/s): "
               "locked wheel or wheel-speed sensor fault" if fast.any() else " (standstill)")
        warns.append(f"slip undefined (NaN) for {np.count_nonzero(undefined) / rate_hz:.1f} s where "
                     f"r*omega < {MIN_WHEEL_SPEED_MPS} m/s (longest run {longest:.1f} s){why}; "
                     "load, drawbar pull, torque and speed still computed there")
    for name, m in dec.items():  # every other message read (GNSS time/speed...): against its cycle time
        if name not in lost_frames and len(m):
            lost_frames[name] = _time_gaps(name, m.timestamp_ns, *cfg.cycle_time_s(m.bus, name),
                                           parts=tb_parts.get(name))[0]
    unknown = sorted(k for k, d in lost_frames.items() if d["lost"] is None)
    quality["lost_frames"] = {k: d["lost"] for k, d in lost_frames.items()}
    quality["lost_frames_known_total"] = int(sum(d["lost"] for d in lost_frames.values() if d["lost"] is not None))
    quality["lost_frames_unknown"] = unknown
    for k in unknown:
        warns.append(f"{k}: lost frames unknown ({lost_frames[k]['method']})")
    out_range = np.isfinite(slip) & ~in_range
    if out_range.any():
        warns.append(f"slip outside [-1, 1) in {np.count_nonzero(out_range)} samples: flagged invalid")
    quality["implausible"] = _implausible(load, dp, torque, slip, speed, rw, r, quality.get("wheel_speed_lag"),
                                          label, warns, ripple=quality.get("wft_ripple"))

    df = pd.DataFrame({
        "t_s": t_grid, "slip": slip, "load_n": load, "drawbar_pull_n": dp, "torque_nm": torque,
        "speed_mps": speed, "omega_radps": omega, "phase": phase.astype(object), "valid": valid,
        "distance_m": _distance(speed, 1.0 / rate_hz), "fx_n": fx_f, "my_nm": my_f,
    }, columns=list(COLUMNS))
    return ProcessResult(
        signals=df,
        gnss_latency_s=None if latency is None else latency.latency_s,
        gnss_latency_stderr_s=None if latency is None else latency.stderr_s,
        gps_time_mapping=gps_map, lost_frames=lost_frames, warnings=warns, cycle=cycle,
        t0_ns=t0_ns, rate_hz=float(rate_hz), cutoff_hz=cutoff, wheel_radius_m=r,
        wheel_width_m=width,
        latency_reference=lat_ref if latency is not None else "", latency_detail=latency,
        wheel_radius_source=r_source, inertia=inertia_info, excluded=excluded, quality=quality,
    )


def unresolved_slip_sd(omega_raw: np.ndarray, omega: np.ndarray, slip: np.ndarray, rate_hz: float,
                       cutoff_hz: float) -> np.ndarray:
    """The slip's spread [-] within one filter window that the low-pass does not resolve, per grid sample.

    ``omega_raw`` (N,) the wheel speed [rad/s] as the sensor reports it and ``omega`` (N,) after the
    ``cutoff_hz`` low-pass, both on the grid of ``rate_hz``; ``slip`` (N,) Eq. (6) from ``omega``.  With
    s = 1 - V / (r omega), ds/domega = (1 - s) / omega, so the spread is (1 - s) RMS(omega_raw - omega) / omega,
    the RMS over a centred window of 1 / ``cutoff_hz`` seconds.  Sensor noise gives well under 0.01 at
    driving speeds; a wheel speed oscillating above the cutoff (stick-slip, wheel hop, a driveline
    oscillating) gives tenths.  NaN where an input is NaN or omega is 0.  Raises nothing.
    Source: paper Eq. (6); the filter of :func:`.filters.filter_to_grid`.
    """
    e2 = (np.asarray(omega_raw, float) - np.asarray(omega, float)) ** 2
    ok = np.isfinite(e2)
    k = max(int(round(rate_hz / cutoff_hz)) | 1, 1) if rate_hz > 0 and cutoff_hz > 0 else 1
    box = np.ones(k)
    num = np.convolve(np.where(ok, e2, 0.0), box, mode="same")
    den = np.convolve(ok.astype(float), box, mode="same")
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.sqrt(num / den)
        out = (1.0 - np.asarray(slip, float)) * rms / np.abs(np.asarray(omega, float))
    out[~ok | ~np.isfinite(out)] = np.nan
    return out


#: Physical limits a decoded run must keep (:func:`_implausible`): a wheel on soil transmits a driving torque
#: T <= mu r W with mu below about 1 (Wong 2008, ch. 2: c A + W tan(phi), phi < 45 deg; cohesion adds a
#: fraction of W at field loads): a median T/(r W) or |Dp|/W above ``TRACTION_MAX`` over the driving samples is
#: a scaling error of the force or moment signals, and above ``TRACTION_GROSS`` no fit of it means anything.
TRACTION_MAX = 1.2
TRACTION_GROSS = 2.0
#: The wheel-speed module and the transducer's wheel angle read one wheel's rotation [rad/s]: their gain
#: (:func:`_wheel_speed_lag`) is 1 but for the tooth count's tolerance; outside ``WHEEL_GAIN_MAX`` (and its
#: inverse) one of them is decoded in another unit or scale, or is another wheel's, and outside
#: ``WHEEL_GAIN_GROSS`` slip (Eq. 6) from it is meaningless.
WHEEL_GAIN_MAX = 1.1
WHEEL_GAIN_GROSS = 1.5
#: A transducer's bridges differ in gain by a few per cent, its crosstalk is a few per cent: a twice-per-revolution
#: part of the hub forces above this share of the load is two force signals decoded with different factors, signs
#: or byte orders (a rotating pair read with unequal gains, or mirrored, beats at twice the wheel angle), and the
#: load's level is then wrong too.  A once-per-revolution part is not: a rotating channel's offset (taken out with
#: the ripple) or a wheel out of round (its load and moment beat with the angle, as an independent generator's
#: 18 mm rim runout did at 20 % of the load) make one, and processing says so and takes it out.
RIPPLE_DECODE_REL = 0.2
#: A ground vehicle on a test track: a speed above this [m/s] (216 km/h) is a decoding error.
SPEED_MAX_MPS = 60.0
#: Driving samples (slip above this, r*omega and V defined) that the traction and torque-sign checks use.
PLAUSIBLE_SLIP_MIN = 0.1


def _implausible(load, dp, torque, slip, speed, rw, r, lag_q, label, warns: list[str], *,
                 ripple: dict | None = None) -> list[dict]:
    """What a decoded run says that no wheel on soil can do, as loud warnings (``warns``) and a list of
    ``{"check", "value", "gross", "text"}`` (``ProcessResult.quality["implausible"]``; ``gross``: no fit of the
    run means anything, and ``fit`` refuses it).  Each is what a vehicle configuration or DBC that does not
    match the recording produces (a factor, a unit, a sign, a byte order, a swapped signal or id), so each
    names the signals to check.  The arrays are the processing grid's (N,) [N, N m, -, m/s, m/s]; ``r`` [m];
    ``lag_q`` ``quality["wheel_speed_lag"]`` or None; ``ripple`` ``quality["wft_ripple"]`` or None; ``label(key)``
    names a configured signal.  Never raises.
    Checks: median load over the run > 0; median T/(r W) and |Dp|/W over the driving samples at most
    :data:`TRACTION_MAX`; the torque not opposing positive slip in most driving samples; the module's speed
    within :data:`WHEEL_GAIN_MAX` of the transducer's wheel-angle rate; the forces' part locked to the wheel
    angle at twice its rate under :data:`RIPPLE_DECODE_REL` of the load; V below :data:`SPEED_MAX_MPS` and not
    nil all the while the wheel turns.  Source: Wong 2008 ch. 2 (traction limit), hardware.md (frames and signs)."""
    out = []

    def add(check, value, gross, text):
        out.append({"check": check, "value": value, "gross": bool(gross), "text": text})
        warns.append("SIGNALS IMPLAUSIBLE: " + text)

    forces = f"{label('wft_fx_w')}, {label('wft_fz_w')}, {label('wft_my')}"
    with np.errstate(invalid="ignore", divide="ignore"):
        w_med = float(np.nanmedian(load)) if np.isfinite(load).any() else float("nan")
        if np.isfinite(w_med) and w_med <= 0:
            add("load", w_med, True, f"the vertical load's median over the run is {w_med:.3g} N (a wheel carries a "
                "positive load): check the sign and factor of the vertical force in the DBC, and that the configured "
                f"force signals ({forces}) are not swapped, nor the force and moment messages' ids")
        amp = max((float((ripple or {}).get(k) or 0.0) for k in ("fx_2x_n", "fz_2x_n")), default=0.0)
        if np.isfinite(w_med) and w_med > 0 and amp > RIPPLE_DECODE_REL * w_med:
            add("ripple", amp / w_med, True,
                f"the hub forces carry {amp:.0f} N ({100 * amp / w_med:.0f} % of the load) twice per wheel "
                "revolution, far beyond a transducer's bridge gains or crosstalk (a few per cent): the two in-plane "
                f"forces ({label('wft_fx_w')}, {label('wft_fz_w')}) are decoded with different factors, signs or "
                "byte orders, and the load's level is wrong too")
        drive = (np.isfinite(slip) & (slip > PLAUSIBLE_SLIP_MIN) & np.isfinite(load) & (load > 0)
                 & np.isfinite(torque) & np.isfinite(dp))
        if np.count_nonzero(drive) >= 50 and r > 0:
            mu_t = float(np.median(torque[drive] / (r * load[drive])))
            mu_d = float(np.median(np.abs(dp[drive]) / load[drive]))
            mu = max(abs(mu_t), mu_d)
            if mu > TRACTION_MAX:
                which = "T/(r W)" if abs(mu_t) >= mu_d else "|Dp|/W"
                add("traction", mu, mu > TRACTION_GROSS,
                    f"the median {which} over the driving samples (slip > {PLAUSIBLE_SLIP_MIN:g}) is {mu:.3g}, beyond "
                    f"what a wheel on soil transmits (about 1 at most): the force and moment signals ({forces}) are "
                    "scaled inconsistently (a factor or unit in the DBC or vehicle.toml)")
            if np.mean(torque[drive] < 0) > 0.8:
                add("torque_sign", float(np.mean(torque[drive] < 0)), True,
                    f"the torque opposes the slip in {100 * np.mean(torque[drive] < 0):.0f} % of the driving samples "
                    f"(slip > {PLAUSIBLE_SLIP_MIN:g} needs a driving torque, T > 0): check the sign of "
                    f"{label('wft_my')} (its DBC factor, or the transducer's mounting against hardware.md's frames)")
        g = (lag_q or {}).get("gain")
        if g is not None and np.isfinite(g) and g > 0 and max(g, 1 / g) > WHEEL_GAIN_MAX:
            add("wheel_speed", float(g), max(g, 1 / g) > WHEEL_GAIN_GROSS,
                f"the wheel speed {label('wheel_speed')} reads {g:.3g} times the transducer's wheel-angle rate "
                f"({label('wft_angle')}), which measures the same wheel's rotation: one of them is decoded in "
                "another unit or scale (rpm read as rad/s is 9.55; a factor; a byte order) or is another wheel's "
                "channel; slip (Eq. 6) takes the wheel speed")
        v = np.abs(speed[np.isfinite(speed)])
        if v.size and float(np.percentile(v, 95)) > SPEED_MAX_MPS:
            add("speed", float(np.percentile(v, 95)), True,
                f"the vehicle speed {label('gnss_forward_velocity')} reaches {np.percentile(v, 95):.3g} m/s (95th "
                "percentile), beyond a test vehicle's: check its factor and byte order in the DBC")
        turning = np.isfinite(rw) & (np.abs(rw) > 0.5) & np.isfinite(speed)
        # (a run may hold the vehicle while the wheel spins, slip 1, most of the time: only never moving counts)
        if np.count_nonzero(turning) >= 100 and float(np.percentile(np.abs(speed[turning]), 99)) < 0.05:
            add("speed", float(np.percentile(np.abs(speed[turning]), 99)), True,
                f"the vehicle speed stays nil (99th percentile {np.percentile(np.abs(speed[turning]), 99):.2g} m/s) "
                "all the while the wheel turns at r*omega > 0.5 m/s: the configured GNSS velocity signal is not the "
                "forward one (a sideways or vertical component?), or is not decoded; or the vehicle never moved")
    return out


def _distance(speed: np.ndarray, dt: float) -> np.ndarray:
    """Travelled distance [m] (N,): trapezoidal integral of V [m/s] (N,) on a grid of step ``dt``
    [s], from 0 at the first finite V; no distance accrues across NaN; NaN where V is NaN."""
    v = np.asarray(speed, dtype=np.float64)
    fin = np.isfinite(v)
    inc = np.where(fin[1:] & fin[:-1], 0.5 * (np.nan_to_num(v[1:]) + np.nan_to_num(v[:-1])) * dt, 0.0)
    d = np.concatenate([[0.0], np.cumsum(inc)])
    d[~fin] = np.nan
    return d


class _FrameScreen:
    """Screens each frame batch before decoding, for frames that look like a used message but
    are not what its DBC describes (``__call__`` returns the batch without them; ``warnings``
    says what was found, per bus and message).

    - A frame on a used message's id whose payload is *longer* than the DBC's message (beyond the
      CAN FD padding of that length) comes from another layout (a CAN FD variant of the device,
      another device on the id): not decoded, so its samples are lost, not misread.  (A shorter
      payload decodes to NaN where the signals are missing: lost samples downstream.)
    - A frame with a used message's id number but the other identifier format (29-bit where the
      DBC says 11-bit, as foreign loggers that mark every id extended write) is not the message;
      it is counted so that "no frames of X" can say where they went.
    """

    def __init__(self, messages: dict[str, list]):
        from can.util import dlc2len, len2dlc

        def longest(n: int) -> int:  # the message's length, padded to the next CAN FD length (ISO 11898-1)
            return max(dlc2len(len2dlc(n)), n)

        self._len = {bus: {int(frame_key(m.frame_id, m.is_extended_frame)): (m.name, longest(m.length)) for m in msgs}
                     for bus, msgs in messages.items()}
        self._twin = {bus: {int(frame_key(m.frame_id, not m.is_extended_frame)): m.name for m in msgs}
                      for bus, msgs in messages.items()}
        self._msg = {(bus, m.name): m for bus, msgs in messages.items() for m in msgs}
        self.too_long: dict[tuple[str, str], list[int]] = {}  # (bus, message) -> [frames, longest payload]
        self.twins: dict[tuple[str, str], int] = {}

    def __call__(self, b):
        lengths, twins = self._len.get(b.bus), self._twin.get(b.bus)
        if not lengths or not len(b):
            return b
        keys = frame_key(np.asarray(b.arbitration_id), np.asarray(b.is_extended))
        dlc = np.asarray(b.dlc)
        drop = None
        for key, (name, longest) in lengths.items():
            bad = (keys == key) & (dlc > longest)
            if bad.any():
                entry = self.too_long.setdefault((b.bus, name), [0, 0])
                entry[0] += int(bad.sum())
                entry[1] = max(entry[1], int(dlc[bad].max()))
                drop = bad if drop is None else drop | bad
        for key, name in twins.items():
            n = int(np.count_nonzero(keys == key))
            if n:
                self.twins[(b.bus, name)] = self.twins.get((b.bus, name), 0) + n
        if drop is None:
            return b
        keep = ~drop
        return dataclasses.replace(b, **{f.name: getattr(b, f.name)[keep] for f in dataclasses.fields(b)
                                         if isinstance(getattr(b, f.name), np.ndarray)})

    def warnings(self, found: set[str]) -> list[str]:
        """What the screen found; a message with a twin is named only when it is missing (``found``:
        the messages that decoded at least one frame)."""
        out = [f"{n} frame(s) of {name} on {bus} have a payload of up to {longest} bytes where its DBC says "
               f"{self._msg[bus, name].length} (a CAN FD variant of the device, or another device on the id?): "
               "not decoded, their samples are lost" for (bus, name), (n, longest) in self.too_long.items()]
        for (bus, name), n in self.twins.items():
            if name not in found:
                dbc, logged = ("29", "11") if self._msg[bus, name].is_extended_frame else ("11", "29")
                out.append(f"no frames of {name} on {bus}, but {n} frame(s) with its id number "
                           f"0x{self._msg[bus, name].frame_id:X} as a {logged}-bit identifier where the DBC says "
                           f"{dbc}-bit (a logger that marks every id extended?): not decoded; re-log with the "
                           "DBC's identifier format or give a DBC with the logged one")
        return out


def _imported_from(report) -> list[str]:
    """The log files an imported recording was made from (its provenance record), [] if unknown."""
    from wheelsoil.daq.provenance import PROVENANCE_RECORD, provenance_from_metadata

    try:
        prov = provenance_from_metadata((getattr(report, "metadata", None) or {}).get(PROVENANCE_RECORD)) or {}
    except Exception:  # noqa: BLE001 - only a hint depends on it
        return []
    if prov.get("kind") != "imported":
        return []
    return [str(s["path"]) for s in prov.get("sources") or [] if isinstance(s, dict) and s.get("path")]


def bus_mix_up(cfg, select, found: set, ids_seen: dict, path, sources=()) -> str | None:
    """The text saying which bus the configured messages of a bus are on, when they are on another one.

    For each configured bus none of whose messages processing reads (``select``: message name ->
    signals) decoded a frame (``found``: names that did), the other bus of the recording with the most
    of those messages' identifiers (``ids_seen``: bus -> set of the :func:`.decode.frame_key` of ids with
    frames) is named, with the ``wheelsoil import ... --map SRC=BUS`` to use (swapped can0/can1,
    ``vcan0``/``slcan0`` names) on ``sources`` (the logs the recording ``path`` was imported from; none
    known: ``LOG``, with how to export one). None when no such bus is found.
    """
    moves, parts = {}, []
    for bus in cfg.buses:
        msgs = [m for m in cfg.database(bus).messages if m.name in select]
        if not msgs or any(m.name in found for m in msgs):
            continue
        want = {frame_key(m.frame_id, m.is_extended_frame) for m in msgs}
        hits = sorted(((len(want & ids), src) for src, ids in ids_seen.items() if src != bus), reverse=True)
        if hits and hits[0][0]:
            k, src = hits[0]
            moves[src] = bus
            parts.append(f"the messages configured on {bus} ({', '.join(sorted(m.name for m in msgs))}) are "
                         f"not on {bus} but on {src} ({k} of their {len(want)} ids)")
    if not moves:
        return None
    maps = " ".join(f"--map {src}={bus}" for src, bus in moves.items())
    how = f"wheelsoil import {' '.join(sources) or 'LOG'} -o NEW.mcap {maps}"
    if not sources:
        how += f" (LOG: the log the recording was made from, or 'wheelsoil export {path} -o LOG.log' first)"
    elif len(sources) > 1:
        how += (f" (the recording was imported from {len(sources)} logs: when each holds one bus, as TRC 1.x files "
                "without a bus column do, map it in the file that holds it only, --map FILE:SRC=BUS; 'wheelsoil "
                "import' names the file)")
    return f"BUS NAMES MIXED UP: {'; '.join(parts)}: import the log with the bus names of the configuration: {how}"


def _foreign_channels(report) -> str:
    """What an MCAP without wheelsoil frame channels holds instead (for the error message): its
    channels' topics, schemas and encodings, and the layout wheelsoil reads."""
    chans = [c for c in (getattr(report, "channels", None) or {}).values()
             if c.get("topic") != "/wheelsoil/logger_status"]
    if not chans:
        return ""
    from wheelsoil.daq.recording import SCHEMA_NAME

    listed = ", ".join(f"{c.get('topic')} (schema {c.get('schema') or 'none'!r}, {c.get('encoding')})"
                       for c in chans[:8]) + (f" and {len(chans) - 8} more" if len(chans) > 8 else "")
    return (f" in the layout wheelsoil reads (channels of schema {SCHEMA_NAME}, docs/mcap-layout.md); it has "
            f"{listed}. Export such a recording's frames as a candump log, ASC, BLF or TRC file and run "
            "'wheelsoil import' on it")
