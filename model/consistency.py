"""Physical consistency of a model's forces: does it carry the wheel, and is its sinkage in range?

A fitted model can lower the drawbar-pull error while breaking the physics the
equations rest on. Two checks, both from the paper's own equations:

1. **Vertical balance (Eq. 7).** The model's vertical load
   W_model = r b (int sigma cos theta + int tau sin theta) should equal the
   measured load W. The ratio W_model / W is taken per slip bin (median of the
   samples in the bin, so a noisy load sample does not decide). A model whose
   W is off by more than ``load_tol`` (default 10 %) integrates a contact
   stress that does not carry the wheel: its sinkage, and with it Dp and T,
   belong to a different load. Why 10 %: Eq. (10) itself is a small-angle
   closed form that ignores the shear term of Eq. (7), and inside its validity
   bound (z0 < D/6) it misses W by at most 3.5 % on the paper's clay, 10.4 %
   on its sand, and by a median 6.3 % over the 19 library soils that have
   loads inside the bound (worst case per soil; default wheel, W 1-20 kN,
   s 0-0.95; 15 of 19 within 10 %, up to 18 % on dry sand, sandy loam 22 %
   and upland sandy loam; measured with ``wong_forces``). 10 % is above that
   approximation error on most soils and far above the load measurement's own
   uncertainty (an assumption: ~1-2 % for a wheel force transducer after
   calibration; hardware.md states none), so a deviation beyond it is a
   broken vertical balance rather than Eq. (10)'s approximation. With
   ``sinkage="balance"`` Wong's model has W_model = W by construction; a
   slip-sinkage transform on top (Vasil'ev Eq. 11, Lyasko Eq. 12) breaks it
   again, which is exactly what this check shows.

2. **Sinkage against the limits of Eq. (10).** Eq. (10) (Bekker's rigid-wheel
   sinkage, Wong, Theory of Ground Vehicles, 4th ed., ch. 2) is derived with
   the small-angle approximation 1 - cos theta ~ theta^2/2 over the contact;
   Bekker and Wong state its predictions are reasonable for sinkage
   z0 < D/6 = r/3, i.e. an entrance angle (Eq. 1) theta1 below
   arccos(2/3) = 48.2 deg (at 48 deg the small-angle term is already 6 % off).
   The sinkage that enters Eqs. (1)-(9) (after any slip-sinkage transform) is
   checked against that bound per slip bin (median); z < r (theta1 < 90 deg)
   always. The static sinkage of Eq. (10) at the measured load is reported
   too.

``physical_consistency`` returns plain Python types (JSON-ready).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .terrain import Terrain, Wheel
from .wong import WheelForces, sinkage_eq10

__all__ = ["physical_consistency", "LOAD_TOLERANCE", "SINKAGE_LIMIT_FRACTION_OF_D"]

#: Default tolerance on |median(W_model / W) - 1| per slip bin (see module docstring).
LOAD_TOLERANCE = 0.10
#: Validity bound of Eq. (10): sinkage below D/6 (Bekker; Wong, Theory of Ground Vehicles, ch. 2).
SINKAGE_LIMIT_FRACTION_OF_D = 1.0 / 6.0


def _vector(name: str, value, size: int) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    try:
        arr = np.broadcast_to(arr, (size,))
    except ValueError:
        raise ValueError(f"{name} shape {arr.shape} does not match the forces' ({size},) samples") from None
    return arr


def _first(mask: np.ndarray) -> int:
    return int(np.flatnonzero(mask)[0])


def physical_consistency(
    forces: WheelForces,
    load_n,
    slip,
    terrain: Terrain,
    wheel: Wheel,
    *,
    n_bins: int = 10,
    load_tol: float = LOAD_TOLERANCE,
    sinkage_limit_m: float | None = None,
    min_count: int = 10,
) -> dict[str, Any]:
    """Vertical balance (Eq. 7) and sinkage limits (Eq. 10) of a model's forces, by slip bin.

    Inputs: ``forces`` the model's ``WheelForces`` (N samples), ``load_n`` the
    measured vertical load W [N] and ``slip`` s [-] of the same samples, shape
    (N,) (scalars broadcast); ``terrain``/``wheel`` the ones the forces were
    computed with (for Eq. 10's static sinkage and D = 2r). Options:
    ``n_bins`` equal-width slip bins on [0, 1); ``load_tol`` the tolerance on
    |median(W_model/W) - 1| per bin (default 0.10, reasoned in the module
    docstring); ``sinkage_limit_m`` (default D/6 = r/3); ``min_count`` the
    samples a bin needs to take part in the verdict (bins with fewer are
    listed, marked ``used: False``; if no bin has enough, the medians over all
    samples are judged).

    Returns a dict:

    - ``load_ratio_by_slip``: list of ``{slip_lo, slip_hi, count, used,
      ratio_median, sinkage_median_m}`` for the non-empty bins;
    - ``max_load_ratio_dev``: max |ratio_median - 1| over the used bins;
      ``load_tolerance``; ``load_ok``;
    - ``max_sinkage_m`` (over all samples), ``max_sinkage_bin_median_m`` (over
      the used bins; this one is judged), ``sinkage_limit_m``,
      ``max_theta1_deg``, ``theta1_limit_deg``, ``max_static_sinkage_m``
      (Eq. 10 at the measured load, terrain's n, bin medians), ``sinkage_ok``;
    - ``consistent`` (``load_ok and sinkage_ok``) and ``reasons`` (sentences,
      one per failed check; empty when consistent).

    Samples with a non-finite model load or measured load/slip are ignored
    (counted in ``n_ignored``). Raises ``ValueError`` for mismatched shapes,
    a measured load <= 0 (naming the element), ``n_bins`` or ``min_count`` < 1, a negative or
    non-finite ``load_tol``, a non-positive ``sinkage_limit_m`` or no usable
    sample. Source: paper Eqs. (1), (7), (10); Bekker (1956), Wong, Theory of
    Ground Vehicles, 4th ed., Wiley 2008, ch. 2 (validity z0 < D/6).
    """
    size = len(forces)
    w = _vector("load_n", load_n, size)
    s = _vector("slip", slip, size)
    if n_bins < 1:
        raise ValueError(f"n_bins must be >= 1, got {n_bins!r}")
    if min_count < 1:
        raise ValueError(f"min_count must be >= 1, got {min_count!r}")
    if not (math.isfinite(load_tol) and load_tol >= 0):
        raise ValueError(f"load_tol must be a finite number >= 0, got {load_tol!r}")
    r = wheel.radius
    limit = SINKAGE_LIMIT_FRACTION_OF_D * 2.0 * r if sinkage_limit_m is None else float(sinkage_limit_m)
    if not (math.isfinite(limit) and limit > 0):
        raise ValueError(f"sinkage_limit_m must be a finite number > 0 m, got {sinkage_limit_m!r}")
    bad = np.isfinite(w) & (w <= 0)
    if bad.any():
        i = _first(bad)
        raise ValueError(f"load_n[{i}] = {float(w[i])!r}: measured vertical load must be > 0 N")
    w_model = np.asarray(forces.load_model_n, dtype=float)
    z = np.asarray(forces.sinkage_m, dtype=float)
    ok = np.isfinite(w) & np.isfinite(s) & np.isfinite(w_model) & np.isfinite(z)
    if not ok.any():
        raise ValueError("physical_consistency: no sample with finite model load, measured load and slip")
    n_ignored = int(size - ok.sum())
    w, s, w_model, z = w[ok], s[ok], w_model[ok], z[ok]
    ratio = w_model / w
    z_static = sinkage_eq10(terrain, wheel, w)

    edges = np.linspace(0.0, 1.0, n_bins + 1)
    idx = np.clip(np.searchsorted(edges, s, side="right") - 1, 0, n_bins - 1)
    bins: list[dict[str, Any]] = []
    used_ratio, used_z, used_z0 = [], [], []
    for k in range(n_bins):
        sel = idx == k
        count = int(sel.sum())
        if count == 0:
            continue
        used = count >= min_count
        rm, zm = float(np.median(ratio[sel])), float(np.median(z[sel]))
        bins.append({"slip_lo": float(edges[k]), "slip_hi": float(edges[k + 1]), "count": count,
                     "used": bool(used), "ratio_median": rm, "sinkage_median_m": zm})
        if used:
            used_ratio.append(rm)
            used_z.append(zm)
            used_z0.append(float(np.median(z_static[sel])))
    if not used_ratio:  # too few samples for any bin: judge on all samples together
        used_ratio = [float(np.median(ratio))]
        used_z = [float(np.median(z))]
        used_z0 = [float(np.median(z_static))]
    dev = np.abs(np.asarray(used_ratio) - 1.0)
    k_dev = int(np.argmax(dev))
    max_dev = float(dev[k_dev])
    load_ok = max_dev <= load_tol
    z_judged = float(max(used_z))
    max_z = float(z.max())
    sinkage_ok = z_judged <= limit and max_z < r
    theta1_limit = math.degrees(math.acos(1.0 - min(limit, 2.0 * r) / r))
    max_theta1 = math.degrees(math.acos(max(-1.0, 1.0 - min(max_z, 2.0 * r) / r)))
    z0_max = float(max(used_z0))

    reasons: list[str] = []
    if not load_ok:
        worst_bins = [b for b in bins if b["used"] and abs(b["ratio_median"] - 1.0) > load_tol]
        worst = max(worst_bins, key=lambda b: abs(b["ratio_median"] - 1.0)) if worst_bins else None
        where = (f"in {len(worst_bins)} of {len(used_z)} slip bins between s = {worst_bins[0]['slip_lo']:.2f} "
                 f"and {worst_bins[-1]['slip_hi']:.2f}, worst at s = {worst['slip_lo']:.2f}-"
                 f"{worst['slip_hi']:.2f}" if worst else "over all samples")
        sense = "more" if used_ratio[k_dev] > 1 else "less"
        reasons.append(
            f"vertical balance (Eq. 7): the model carries {used_ratio[k_dev]:.2f}x the measured load "
            f"({sense} than W by {100 * max_dev:.0f} %, tolerance {100 * load_tol:.0f} %) {where}; its "
            f"contact stress does not carry the wheel, so its sinkage, Dp and T belong to another load."
        )
    if not sinkage_ok:
        if max_z >= r:
            reasons.append(f"sinkage reaches the wheel radius r = {r} m (theta1 >= 90 deg): outside the model.")
        else:
            reasons.append(
                f"sinkage {1000 * z_judged:.0f} mm (slip-bin median; max {1000 * max_z:.0f} mm, "
                f"theta1 up to {max_theta1:.0f} deg) exceeds the validity bound of Eq. (10) and of the "
                f"rigid-wheel theory, {1000 * limit:.0f} mm (D/6, theta1 = {theta1_limit:.0f} deg)."
            )
    if z0_max > limit:
        reasons.append(
            f"static sinkage of Eq. (10) at the measured load, {1000 * z0_max:.0f} mm, is already above "
            f"{1000 * limit:.0f} mm (D/6): the terrain is too soft for this load and wheel for the "
            f"small-angle theory."
        )
    return {
        "load_ratio_by_slip": bins,
        "max_load_ratio_dev": max_dev,
        "load_tolerance": float(load_tol),
        "load_ok": bool(load_ok),
        "max_sinkage_m": max_z,
        "max_sinkage_bin_median_m": z_judged,
        "sinkage_limit_m": float(limit),
        "max_theta1_deg": max_theta1,
        "theta1_limit_deg": theta1_limit,
        "max_static_sinkage_m": z0_max,
        "sinkage_ok": bool(sinkage_ok),
        "consistent": bool(load_ok and sinkage_ok),
        "reasons": reasons,
        "n_samples": int(ok.sum()),
        "n_ignored": n_ignored,
    }
