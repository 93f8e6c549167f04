"""Hidden effects of the simulator: what the true soil / wheel / sensor does differently from the lab model.

Each effect has a *family*: ``in`` (a cause the diagnosis has a hypothesis
for: the verdict should name it) or ``out`` (a cause no hypothesis models: the
honest verdict is ``unexplained``), and the list of verdicts (report.json
``diagnosis.effect``) that are *acceptable* for it (contract F). Effect sizes
are drawn from a ``size`` in [0, 1]: 0 is barely above the noise, 1 large.

In family
  ``none``                 Wong's model (paper Eqs. 1-10) on the lab soil.
  ``vasilev``              z = z0 + H s (Eq. 11).
  ``lyasko``               z = z0 (1 + m1 s)/(1 - m2 s) (Eq. 12).
  ``ding``                 N = n + n1 s (Eq. 13).
  ``terrain_mismatch``     one or two lab soil values wrong: k_eq = kc/b + kphi (kc and
                           kphi scaled together), n, c, phi or K.
  ``stress_distribution``  Wong-Reece normal stress, maximum at theta_m = (a1 + a2 s) theta1.
  ``terrain_drift``        a soil value changes along the run: ``compaction`` (linear in the
                           travelled distance: repeated passes) or ``patch`` (another patch of
                           ground from ``change_at`` x the distance on, tanh transition over 2 %
                           of it). The change runs from lab/f to lab*f (a factor f) or lab - d to
                           lab + d (a delta d): the lab value mid-run (compaction) or at the
                           patch boundary.

Out of family (``unexplained`` always acceptable)
  ``fx_gain``          the transducer's hub Fx reads g x the true value (calibration).
  ``my_gain``          its My reads g x the true value.
  ``load_gain``        its Fz (the load W) reads g x the true value. With Eq. (10) the model
                       depends on W only through W/k_eq: a load gain g is *exactly* a
                       k_eq of k_eq/g, so ``terrain_mismatch`` is acceptable too.
  ``angle_offset``     the WheelAngle encoder's zero is off by delta: the hub rotation mixes
                       W into Fx (Fx_meas = Fx cos d + W sin d): a load-proportional Dp offset.
  ``tyre_deflection``  a flexible tyre: the soil sees Wong's equivalent rigid wheel of
                       radius r_e = r (1 + kappa W / W_ref) (Wong, Theory of Ground
                       Vehicles, 4th ed., sec. 2.x, flexible tyre in the elastic mode), while
                       slip is still r omega based.
  ``bulldozing``       soil pushed ahead of the sunk wheel: Bekker's bulldozing resistance
                       R_b = f b (0.67 c z K_pc + 0.5 z^2 gamma K_pgamma) subtracted from Dp,
                       torque unchanged (Bekker 1969; Wong, Theory of Ground Vehicles, ch. 2).
  ``load_dependent``   the soil stiffens/softens with the wheel load (plate-size / pressure
                       effect): k_eq(W) = k_eq (W / W_static)^beta; the lab value holds at
                       the static load, so the mean soil is the lab's.
  ``width_error``      the tyre's effective contact width is b_e = f b, not the configured b
                       (bulging sidewalls, a lab/setup error in a wheel value no hypothesis
                       re-fits): Eqs. (2), (7)-(10) with b_e. The forces depend on b only
                       through b k_eq = kc + b kphi and b c, so a width factor f is *exactly*
                       the configured wheel on a soil of kphi f and c f (kc unchanged), and
                       ``terrain_mismatch`` is acceptable too.
  ``zero_drift``       the transducer's My zero drifts linearly with time over the run
                       (a bridge warming up with the hub): My_meas = My + d (t / t_end - 1/2);
                       drift d (``drift_nm``, end - start). Along the axle, so the wheel-angle
                       transformation does not average it out as it does the rotating Fx_w, Fz_w
                       zeros.
  ``vertical_balance`` the true static sinkage satisfies the vertical balance Eq. (7) = W
                       (with the shear term, at the sample's slip) instead of Eq. (10)'s
                       small-angle formula the models use.

Held out (out of family, added after the diagnosis' rule was last changed and never used to
develop it: ``bench_diagnosis.py --effects held-out`` scores the rule on causes it has never met)
  ``exit_angle``       a rebounding soil: the contact runs on behind the wheel's bottom to the
                       exit angle theta2 = lambda theta1 (Wong-Reece rear region from theta_m to
                       -theta2; Wong, Theory of Ground Vehicles, ch. 2). A normal-stress
                       distribution other than the model's, so ``stress_distribution`` is
                       acceptable too.
  ``shear_hump``       a compact soil whose shear stress peaks and falls to a residual Kr x the
                       strength (Wong's hump-shaped curve, peak at j = 2.5 K) instead of
                       Janosi-Hanamoto's Eq. (4).
  ``gnss_gain``        the GNSS speed reads g x the true speed (antenna lever arm, a receiver
                       setting): slip is computed from a wrong vehicle speed.

Held out, second batch (``--effects held-out-2``; added together with the stand-ins for the
first batch and scored once, after them)
  ``strength_softening`` the soil's shear strength falls with slip (remoulding at high shear
                       rates): tau = (c + sigma tan phi)(1 - beta s)(1 - exp(-j/K)).
  ``tyre_hysteresis``  the tyre's internal losses: the hub torque carries an extra f W r
                       (rolling-resistance coefficient f of the carcass) that the soil never
                       sees; Dp unchanged.
  ``inertia_error``    the wheel's true mass and inertia are (1 + e) x the configured ones
                       (another rim, mud in the tyre): processing's compensation leaves
                       e m_w dV/dt in Dp and e I_w domega/dt in T.

Held out, third batch (``--effects held-out-3``; added after the stand-ins for the first two,
scored once with the rule as it then stood)
  ``hard_layer``       a firm layer under the soil: the sinkage cannot pass a depth d =
                       0.8-1.3 x the static sinkage at the static load (smooth cap,
                       z = (z^-8 + d^-8)^(-1/8)).
  ``fz_crosstalk``     the transducer's load channel picks up k x its Fx (k 1-6 %, either sign).
  ``load_radius``      the tyre's rolling radius shrinks with the load: r_roll = r (1 - e (W - W0) /
                       W0), e 0.1-1, so slip from r omega is off by a load-dependent amount
                       (the left-rear wheel-speed channel reads omega r_roll / r).

Held out, fourth batch (``--effects held-out-4``; added after the third batch's score, with the rule
unchanged since it, and scored once)
  ``slip_angle``       the wheel runs at a slip angle alpha = 1-8 deg (toe or crabbing misalignment):
                       the soil is sheared sideways too, and only the longitudinal part of the
                       mobilised shear stress drives the wheel (terra.py; Wong, ch. 2).
  ``grouser``          lugs of height h = 1-8 % of r: the soil is sheared at the lug tips, radius
                       r + h, while the normal stress acts on the rim and slip is r omega based.
  ``wheel_latency``    the left-rear wheel-speed channel arrives 20-250 ms late (a gateway's
                       buffer, a filter in the sensor): slip is computed from an old omega.

Held out, fifth batch (``--effects held-out-5``; added with the rule that the five-value terrain
re-fit names no cause on its own, scored once with it)
  ``fx_gain_drift``    the transducer's Fx gain drifts over the run (a bridge warming up):
                       Fx_meas = Fx (1 + g (t / t_end - 1/2)), g 3-20 %, either sign.
  ``mud_buildup``      mud building up on the tyre: the wheel's radius grows along the run to
                       r (1 + e x), x the distance fraction, e 2-12 %; the soil sees that wheel and
                       its slip 1 - (1 - s)/(1 + e x), while slip is computed with r.
  ``curved_envelope``  a curved failure envelope: the strength c + tan phi sigma0 (sigma/sigma0)^beta,
                       beta 0.7-0.95, meeting the lab's straight line at sigma0, the peak normal
                       stress at the static load.

Held out, sixth batch (``--effects held-out-6``; added with the rule of the fifth unchanged after its
second round, scored once)
  ``load_lag``         the transducer's load channel lags: a first-order filter of time constant
                       0.1-1 s in the sensor's electronics.
  ``pressure_k``       the shear deformation modulus grows with the normal stress, K (sigma/sigma0)^gamma,
                       gamma 0.2-0.8, the lab's K at sigma0 (the static peak normal stress).
  ``radius_error``     the tyre's true rolling radius is (1 + e) r, e 2-8 %, either sign: the soil sees
                       that wheel and its slip (at least 0: Wong's driving model), while slip is
                       computed with the configured r.

Held out, seventh batch (``--effects held-out-7``; added with the rule of the sixth unchanged, scored
once)
  ``fz_zero_drift``    the transducer's load zero drifts over the run (a bridge warming up):
                       W_meas = W + d W0 (t / t_end - 1/2), d 2-10 % of the static load W0, either
                       sign: the model's input drifts, not its output.
  ``my_crosstalk``     the transducer's torque channel picks up its longitudinal force:
                       My_meas = My + k r Fx, k 1-6 %, either sign (bridge crosstalk).
  ``rate_shear``       a soil whose shear strength grows with the shear rate (viscous clays, wet
                       soils; Wong, Theory of Ground Vehicles, ch. 2): the strength is
                       (c + sigma tan phi)(1 + beta ln(1 + s / s_ref)), s_ref = 0.02, beta 0.02-0.12
                       (slip standing for the slip velocity r omega s at the sweep's wheel speed);
                       the lab's value at the shear box's slow rate.

Held out, eighth batch (``--effects held-out-8``; added with the stand-ins ``envelope`` and ``k_stress`` that
the fifth and sixth led to, scored once)
  ``loose_top``        a loose top layer: the shear strength grows with the depth d below the original
                       surface, (c + sigma tan phi)(d/z0)^a, a 0.05-0.5, the lab's at the static
                       sinkage z0 (softer near the surface: the front of the contact and the rut's rim).
  ``interface``        the tyre-soil interface is weaker than the soil at the higher stresses: friction
                       f tan phi, f 0.9-0.5, above half the static peak stress sigma0/2 (the soil's
                       line below it, the two joined smoothly; ``wheelsoil.sim.terra``).
  ``bouncing``         the vehicle bounces on rough ground: each wheel's load oscillates at 1.5-3 Hz by
                       5-30 % of its static load (measured by the transducer as it is: the soil model's
                       input is right, the soil sees a rapidly changing load).

Held out, ninth batch (``--effects held-out-9``; added with the rule of the eighth unchanged, scored once)
  ``fx_saturation``    the transducer's Fx channel saturates smoothly (an amplifier near its range, a
                       bridge's nonlinearity): Fx_meas = F_s tanh(Fx / F_s), F_s such that the run's
                       largest |Fx| reads 2-25 % low.
  ``tyre_compliance``  the tyre's tread deforms under the tractive force (longitudinal tyre compliance):
                       part of the slip computed from omega is the tread's deformation slip
                       e T / (r W0), e 0.02-0.15 (W0 the static load), and the soil is sheared at the
                       rest, max(s - e T/(r W0), 0) (T from a first pass at s: a one-step fixed point).
  ``slip_sinkage_lag`` slip sinkage that builds up with the excavation, not at once: Vasil'ev's
                       z0 + H s_lag (Eq. 11, H 0.01-0.10 m), s_lag the slip through a first-order lag
                       of 0.3-2 s (the instrumented wheel; the vehicle's dynamics use H s). A listed
                       cause with a twist: ``slip_sinkage`` or ``unexplained`` are acceptable.

Held out, tenth batch (``--effects held-out-10``; added with the rule of ``c97d54e`` unchanged, scored
once).  The first causes that depend on the forward speed V, which no hypothesis takes as an input:
  ``speed_resistance`` a resistance growing with the square of the forward speed (the soil the tread and
                       the bow wave throw forward, its inertia; Wong, Theory of Ground Vehicles, ch. 4, on
                       speed effects): Dp less e W (V / 5 m/s)^2, e 0.3-5 %; the torque as Wong's.
  ``rate_sinkage``     a pressure-sinkage relation that stiffens with the loading rate (viscous clays,
                       wet soils; the lab's plate pressed at 25 mm/s): kc and kphi x
                       (1 + e ln(1 + V / 0.025 m/s)), e 0.5-10 %.
  ``my_lag``           the transducer's torque channel lags its force channels: a first-order filter of
                       time constant 0.03-0.5 s (a different anti-alias filter in the My bridge's amplifier).
The vehicle's dynamics use Wong's forces for the two speed effects (the force table has no speed axis);
the instrumented wheel's forces carry them.

Held out, eleventh batch (``--effects held-out-11``; added with the rule of ``9cc7f4a`` unchanged, scored
once).  A soil value changing along the run in shapes the drifting hypotheses do not follow (they are
linear in the distance, or a step): the cause is a terrain drift, so ``terrain_drift`` or
``unexplained`` are acceptable.  One value (k_eq, n, c, phi or K) changes by the ranges of
``terrain_drift``, from lab/f to lab*f (a factor) or lab - d to lab + d (a delta), g the change's
fraction in [-1/2, 1/2] at the distance fraction x:
  ``saturating_drift`` repeated passes compacting the soil fast at first, then slowly:
                       g = (1 - exp(-x/L)) / (1 - exp(-1/L)) - 1/2, L 0.08-0.3 of the run.
  ``gradual_patch``    another patch of ground reached over a long transition:
                       g = tanh((x - x0)/w) / 2, x0 0.3-0.7, w 0.08-0.25 of the run.
  ``patchy_ground``    two kinds of ground alternating along the track: g = sin(2 pi (k x + p)) / 2,
                       k 1-2 periods over the run, p a random phase.

Held out, twelfth batch (``--effects held-out-12``; added with the rule of ``354913b`` unchanged, scored
once)
  ``rut``              the instrumented left-rear wheel runs in the rut of the left-front wheel, which
                       sank its Eq. (10) sinkage z_f at ``load_ratio`` 0.15-1 x the static load (the
                       rut's depth sets the effect's size): the soil below the rut's bottom reloads
                       on a line R = 3-20 times stiffer than the virgin curve's secant up to the
                       front wheel's peak pressure, then follows the virgin curve; the
                       sinkage from the vertical balance (``wheelsoil.sim.terra``, Wong ch. 2,
                       repetitive loading).  The vehicle's dynamics see the same forces on all wheels.
  ``tyre_pressure_loss`` a tyre losing pressure along the run (a slow puncture): its deflection grows
                       from none to Wong's equivalent rigid wheel r (1 + kappa W / W_static) at the
                       end, kappa 0.04-0.4 (``tyre_deflection`` growing with the distance fraction x).
  ``moisture``         the soil wetter (or drier) along the run (rain, a wetter stretch, drying in the
                       sun): k_eq, c and phi fall (rise) together, linear in the distance, each by half
                       of ``terrain_drift``'s range at the size (the lab values mid-run; three values
                       at once leave the wheel less margin): a terrain drift in three values, which no
                       one-value drifting form follows, so ``terrain_drift`` or ``unexplained`` are
                       acceptable.

Held out, thirteenth batch (``--effects held-out-13``; added with the rule of ``e4fa602`` unchanged, scored
once).  Causes that act through the wheel's or the vehicle's speed in ways no stand-in follows:
  ``speed_sinkage``    a sinkage that grows with the tread's speed r omega, not with slip (a spinning tyre
                       vibrating loose sand under it, dynamic sinkage): z0 + H r omega / (5 m/s),
                       H 0.005-0.04 m; in a slip sweep r omega rises with slip, so slip sinkage is its
                       look-alike, but it also grows with the forward speed at a given slip.
  ``gnss_offset``      the GNSS speed reads V + b (a receiver's Doppler bias, a velocity filter's
                       offset), b +-0.02-0.3 m/s, faded in over the first 0.5 m/s (a receiver's
                       zero-velocity clamp holds it at 0 at standstill): slip is off most at low speed.
  ``tyre_growth``      the tyre's rolling radius grows with its speed (centrifugal growth of the
                       tread): r (1 + kappa (r omega / 10 m/s)^2), kappa 0.005-0.05; slip is computed
                       with r, the soil sees the grown wheel at its own slip.
As for the tenth batch, the vehicle's dynamics use Wong's forces for the two tyre/soil effects.

Held out, fourteenth batch (``--effects held-out-14``; added with the rule of ``459ed20`` unchanged, scored
once).  A wheel that is not round, a speed reading with bursts of error, a tyre warming up:
  ``runout``           an out-of-round tyre or an eccentric rim: the rolling radius is r (1 + e sin psi), psi
                       the wheel's angle, e 0.005-0.05, so the slip the soil sees, 1 - V / (r (1 + e sin psi)
                       omega), oscillates once per revolution about the slip computed with r; its mean
                       effect on the forces follows their curvature in slip.  ``none`` or ``unexplained``.
  ``gnss_multipath``   the GNSS speed jumps by b for a few seconds at times (multipath off trees or buildings,
                       a receiver re-acquiring) and is still flagged valid: 3-10 bursts of 1-5 s at random
                       times, each b = +-(0.5-1) b_max, b_max 0.05-0.5 m/s.  ``none`` or ``unexplained``.
  ``tyre_warmup``      a cold tyre's rolling resistance fading as the tyre warms: the torque plus
                       f W r exp(-x / L) (x the distance fraction, L 0.05-0.3 of the run, f 0.005-0.05;
                       ``tyre_hysteresis`` fading along the run).  ``unexplained``.
The vehicle's dynamics use Wong's forces for the out-of-round tyre (the force table has no angle axis).

Held out, fifteenth batch (``--effects held-out-15``; added with the rule of ``459ed20`` unchanged after batch
14's score, scored once).  Causes chosen to look like a listed one:
  ``crust``            a cohesive surface crust (dried, cemented or frozen): the shear strength plus
                       dc exp(-d / d_c), d the depth below the original surface, dc = a (c + sigma0 tan phi),
                       a 0.1-1 (sigma0 the static peak stress), d_c 0.1-0.5 z0: more strength where the contact
                       is shallow, so its share falls as the wheel sinks (a cohesion mismatch's look-alike).
  ``slip_k``           a shear deformation modulus growing with slip, K (1 + a s), a 0.3-3 (the shear band
                       thickening as the wheel spins; a K mismatch's look-alike).
  ``gnss_lag``         the receiver smooths the velocity it reports: a first-order filter of time constant
                       0.05-0.5 s on top of its latency (processing estimates a pure delay).

Sensor effects (``fx_gain``, ``my_gain``, ``load_gain``, ``angle_offset``, ``zero_drift``) change only
what the transducer reports; the soil forces (and the vehicle) are Wong's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from .terra import sinkage_eq10, wheel_forces

__all__ = ["EFFECTS", "IN_FAMILY", "OUT_OF_FAMILY", "HELD_OUT", "HELD_OUT_2", "HELD_OUT_3", "HELD_OUT_4",
           "HELD_OUT_5", "HELD_OUT_6", "HELD_OUT_7", "HELD_OUT_8", "HELD_OUT_9", "HELD_OUT_10", "HELD_OUT_11",
           "HELD_OUT_12", "HELD_OUT_13", "HELD_OUT_14", "HELD_OUT_15",
           "HELD_OUT_BATCHES", "ALONG_RUN",
           "ALL_HELD_OUT", "ACCEPTABLE", "VERDICTS", "SENSOR_EFFECTS", "draw_effect", "TruthModel", "family_of"]

#: The verdicts a report can give (report.json ``diagnosis.effect``).
VERDICTS = ("none", "slip_sinkage", "terrain_mismatch", "stress_distribution", "terrain_drift", "unexplained")

IN_FAMILY = ("none", "vasilev", "lyasko", "ding", "terrain_mismatch", "stress_distribution", "terrain_drift")
OUT_OF_FAMILY = ("fx_gain", "my_gain", "load_gain", "angle_offset", "tyre_deflection", "bulldozing",
                 "load_dependent", "vertical_balance", "width_error", "zero_drift")
EFFECTS = IN_FAMILY + OUT_OF_FAMILY
#: out of family, never used to develop the rule (not in EFFECTS: the benchmark's rotation is unchanged)
HELD_OUT = ("exit_angle", "shear_hump", "gnss_gain")
#: the second held-out batch, scored once after the stand-ins the first one led to
HELD_OUT_2 = ("strength_softening", "tyre_hysteresis", "inertia_error")
#: the third, scored once after the stand-ins the first two led to
HELD_OUT_3 = ("hard_layer", "fz_crosstalk", "load_radius")
#: the fourth, scored once with the rule unchanged since the third's score
HELD_OUT_4 = ("slip_angle", "grouser", "wheel_latency")
#: the fifth, scored once with the rule that the five-value terrain re-fit names no cause on its own
HELD_OUT_5 = ("fx_gain_drift", "mud_buildup", "curved_envelope")
#: the sixth, scored once with the rule of the fifth (catch-alls and their drifts)
HELD_OUT_6 = ("load_lag", "pressure_k", "radius_error")
#: the seventh, scored once with the rule of the sixth
HELD_OUT_7 = ("fz_zero_drift", "my_crosstalk", "rate_shear")
#: the eighth, scored once with the stand-ins the fifth and sixth led to (envelope, k_stress)
HELD_OUT_8 = ("loose_top", "interface", "bouncing")
#: the ninth, scored once with the rule of the eighth
HELD_OUT_9 = ("fx_saturation", "tyre_compliance", "slip_sinkage_lag")
#: the tenth, scored once with the rule of c97d54e (the first causes that depend on the forward speed)
HELD_OUT_10 = ("speed_resistance", "rate_sinkage", "my_lag")
#: the eleventh, scored once with the rule of 9cc7f4a (a soil drifting in shapes no drifting form follows)
HELD_OUT_11 = ("saturating_drift", "gradual_patch", "patchy_ground")
#: the twelfth, scored once with the rule of 354913b (the wheel in the front wheel's rut, a tyre losing
#: pressure along the run, the soil's moisture changing along the run in three values at once)
HELD_OUT_12 = ("rut", "tyre_pressure_loss", "moisture")
#: the thirteenth, scored once with the rule of e4fa602 (speed-driven sinkage, a GNSS speed offset, a
#: tyre growing with its speed)
HELD_OUT_13 = ("speed_sinkage", "gnss_offset", "tyre_growth")
#: the fourteenth, scored once with the rule of 459ed20 (an out-of-round tyre, bursts of GNSS speed error,
#: a tyre warming up)
HELD_OUT_14 = ("runout", "gnss_multipath", "tyre_warmup")
#: the fifteenth, scored once with the rule of 459ed20 (a cohesive crust, a K growing with slip, a GNSS
#: velocity smoothed by the receiver)
HELD_OUT_15 = ("crust", "slip_k", "gnss_lag")
#: the batches by their ``bench_diagnosis.py --effects`` name, and all held-out effects
HELD_OUT_BATCHES = {"held-out": HELD_OUT, "held-out-2": HELD_OUT_2, "held-out-3": HELD_OUT_3,
                    "held-out-4": HELD_OUT_4, "held-out-5": HELD_OUT_5, "held-out-6": HELD_OUT_6,
                    "held-out-7": HELD_OUT_7, "held-out-8": HELD_OUT_8, "held-out-9": HELD_OUT_9,
                    "held-out-10": HELD_OUT_10, "held-out-11": HELD_OUT_11,
                    "held-out-12": HELD_OUT_12, "held-out-13": HELD_OUT_13,
                    "held-out-14": HELD_OUT_14, "held-out-15": HELD_OUT_15}
ALL_HELD_OUT = tuple(e for batch in HELD_OUT_BATCHES.values() for e in batch)
SENSOR_EFFECTS = ("fx_gain", "my_gain", "load_gain", "angle_offset", "zero_drift", "gnss_gain", "inertia_error",
                  "fz_crosstalk", "load_radius", "wheel_latency", "fx_gain_drift", "load_lag",
                  "fz_zero_drift", "my_crosstalk", "fx_saturation", "my_lag", "gnss_offset", "gnss_multipath", "gnss_lag")
#: effects whose truth changes along the run (the simulator tabulates their forces against distance too)
ALONG_RUN = ("terrain_drift", "mud_buildup", "tyre_pressure_loss", "moisture") + HELD_OUT_11

#: ``rate_shear``'s reference slip: the strength is the lab's at slips well below it
RATE_SLIP_REF = 0.02
#: ``speed_resistance``'s reference speed [m/s]: the extra resistance is e W at it
SPEED_REF_MPS = 5.0
#: ``rate_sinkage``'s reference loading rate [m/s]: the lab plate's penetration speed
PLATE_RATE_MPS = 0.025
#: ``speed_sinkage``'s reference tread speed [m/s]: the extra sinkage is H at it
SPEED_SINKAGE_REF_MPS = 5.0
#: ``tyre_growth``'s reference tread speed [m/s]: the radius is r (1 + kappa) at it
TYRE_GROWTH_REF_MPS = 10.0
#: ``gnss_offset`` fades in over this forward speed [m/s] (a receiver's zero-velocity clamp)
GNSS_OFFSET_FADE_MPS = 0.5

#: Acceptable verdicts per effect (contract F). See the module docstring for the two
#: out-of-family effects with an exact in-family equivalent (load_gain, width_error).
ACCEPTABLE: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "vasilev": ("slip_sinkage",),
    "lyasko": ("slip_sinkage",),
    "ding": ("slip_sinkage",),
    "terrain_mismatch": ("terrain_mismatch",),
    "stress_distribution": ("stress_distribution",),
    "terrain_drift": ("terrain_drift",),
    "fx_gain": ("unexplained",),
    "my_gain": ("unexplained",),
    "load_gain": ("unexplained", "terrain_mismatch"),
    "angle_offset": ("unexplained",),
    "tyre_deflection": ("unexplained",),
    "bulldozing": ("unexplained",),
    "load_dependent": ("unexplained",),
    "vertical_balance": ("unexplained",),
    "width_error": ("unexplained", "terrain_mismatch"),
    "zero_drift": ("unexplained",),
    "exit_angle": ("unexplained", "stress_distribution"),
    "shear_hump": ("unexplained",),
    "gnss_gain": ("unexplained",),
    "strength_softening": ("unexplained",),
    "tyre_hysteresis": ("unexplained",),
    "inertia_error": ("unexplained",),
    "hard_layer": ("unexplained",),
    "fz_crosstalk": ("unexplained",),
    "load_radius": ("unexplained",),
    "slip_angle": ("unexplained",),
    "grouser": ("unexplained",),
    "wheel_latency": ("unexplained",),
    "fx_gain_drift": ("unexplained",),
    "mud_buildup": ("unexplained",),
    "curved_envelope": ("unexplained",),
    "load_lag": ("unexplained",),
    "pressure_k": ("unexplained",),
    "radius_error": ("unexplained",),
    "fz_zero_drift": ("unexplained",),
    "my_crosstalk": ("unexplained",),
    "rate_shear": ("unexplained",),
    "loose_top": ("unexplained",),
    "interface": ("unexplained",),
    "bouncing": ("none", "unexplained"),
    "fx_saturation": ("unexplained",),
    "tyre_compliance": ("unexplained",),
    "slip_sinkage_lag": ("slip_sinkage", "unexplained"),
    "speed_resistance": ("unexplained",),
    "rate_sinkage": ("unexplained",),
    "my_lag": ("unexplained",),
    **{e: ("terrain_drift", "unexplained") for e in HELD_OUT_11},
    "rut": ("unexplained",),
    "tyre_pressure_loss": ("unexplained",),
    "moisture": ("terrain_drift", "unexplained"),
    "speed_sinkage": ("unexplained",),
    "gnss_offset": ("unexplained",),
    "tyre_growth": ("unexplained",),
    "runout": ("none", "unexplained"),
    "gnss_multipath": ("none", "unexplained"),
    "tyre_warmup": ("unexplained",),
    "crust": ("unexplained",),
    "slip_k": ("unexplained",),
    "gnss_lag": ("unexplained",),
}

#: Terrain parameters a mismatch / drift may change, with the relative (or absolute) range
#: of the change at size 0 and size 1.
_MISMATCH = {  # name: (kind, small, large)
    "k_eq": ("rel", 0.10, 0.60),
    "n": ("abs", 0.04, 0.20),
    "c": ("rel", 0.15, 0.70),
    "phi": ("abs_deg", 1.5, 7.0),
    "K": ("rel", 0.20, 1.20),
}


#: Effects of one parameter: (name, value at size 0, at size 1, log-uniform, form). Forms: ``plain``
#: the magnitude, ``signed`` with a random sign, ``gain`` 1 +- it, ``one_minus`` 1 - it.
_ONE_PARAM: dict[str, tuple[str, float, float, bool, str]] = {
    "fx_gain": ("gain", 0.03, 0.20, False, "gain"),
    "my_gain": ("gain", 0.03, 0.20, False, "gain"),
    "load_gain": ("gain", 0.02, 0.12, False, "gain"),
    "angle_offset": ("offset_deg", 0.15, 2.0, True, "signed"),
    "tyre_deflection": ("kappa", 0.04, 0.40, True, "plain"),
    "bulldozing": ("factor", 0.02, 0.30, True, "plain"),
    "load_dependent": ("beta", 0.5, 3.0, False, "signed"),
    "width_error": ("factor", 0.05, 0.30, False, "gain"),
    "zero_drift": ("drift_nm", 20.0, 200.0, True, "signed"),  # 0.2-2 % of a 10 kN m channel over a run
    "exit_angle": ("exit_frac", 0.03, 0.25, False, "plain"),
    "shear_hump": ("Kr", 0.05, 0.40, False, "one_minus"),
    "gnss_gain": ("gain", 0.005, 0.05, True, "gain"),
    "strength_softening": ("beta", 0.03, 0.30, True, "plain"),
    "tyre_hysteresis": ("f", 0.005, 0.05, True, "plain"),
    "inertia_error": ("e", 0.1, 0.6, False, "signed"),
    "hard_layer": ("depth_ratio", 1.3, 0.8, False, "plain"),
    "fz_crosstalk": ("k", 0.01, 0.06, False, "signed"),
    "load_radius": ("e", 0.1, 1.0, False, "plain"),
    "slip_angle": ("angle_deg", 1.0, 8.0, False, "plain"),
    "grouser": ("height_ratio", 0.01, 0.08, False, "plain"),
    "wheel_latency": ("delay_s", 0.02, 0.25, True, "plain"),
    "fx_gain_drift": ("g", 0.03, 0.20, False, "signed"),
    "mud_buildup": ("e", 0.02, 0.12, False, "plain"),
    "curved_envelope": ("beta", 0.95, 0.7, False, "plain"),
    "load_lag": ("tau_s", 0.1, 1.0, True, "plain"),
    "pressure_k": ("gamma", 0.2, 0.8, False, "plain"),
    "radius_error": ("e", 0.02, 0.08, False, "signed"),
    "fz_zero_drift": ("drift_ratio", 0.02, 0.10, False, "signed"),
    "my_crosstalk": ("k", 0.01, 0.06, False, "signed"),
    "rate_shear": ("beta", 0.02, 0.12, True, "plain"),
    "loose_top": ("a", 0.05, 0.5, True, "plain"),
    "interface": ("f", 0.9, 0.5, False, "plain"),
    "bouncing": ("amplitude", 0.05, 0.30, True, "plain"),
    "fx_saturation": ("compression", 0.02, 0.25, True, "plain"),
    "tyre_compliance": ("e", 0.02, 0.15, True, "plain"),
    "speed_resistance": ("e", 0.003, 0.05, True, "plain"),
    "rate_sinkage": ("e", 0.005, 0.10, True, "plain"),
    "my_lag": ("tau_s", 0.03, 0.5, True, "plain"),
    "tyre_pressure_loss": ("kappa", 0.04, 0.40, True, "plain"),
    "speed_sinkage": ("H", 0.005, 0.04, True, "plain"),
    "gnss_offset": ("offset_mps", 0.02, 0.3, True, "signed"),
    "tyre_growth": ("kappa", 0.005, 0.05, True, "plain"),
    "runout": ("e", 0.005, 0.05, True, "plain"),
    "slip_k": ("a", 0.3, 3.0, True, "plain"),
    "gnss_lag": ("tau_s", 0.05, 0.5, True, "plain"),
}


#: Parameter names each effect takes (``size`` always allowed).
PARAM_NAMES: dict[str, tuple[str, ...]] = {
    "none": (), "vasilev": ("H",), "lyasko": ("m1", "m2"), "ding": ("n1",),
    "terrain_mismatch": ("changes",), "terrain_drift": ("changes", "mode", "change_at"),
    "stress_distribution": ("a1", "a2"), "vertical_balance": (), "slip_sinkage_lag": ("H", "tau_s"),
    "saturating_drift": ("changes", "length"), "gradual_patch": ("changes", "change_at", "width"),
    "patchy_ground": ("changes", "cycles", "phase"), "moisture": ("changes",),
    "rut": ("load_ratio", "R"), "gnss_multipath": ("bursts",), "tyre_warmup": ("f", "length"),
    "crust": ("a", "depth_ratio"),
    **{e: (v[0],) for e, v in _ONE_PARAM.items()},
}


def family_of(effect: str) -> str:
    """``"in"`` or ``"out"``; ValueError for an unknown effect."""
    if effect in IN_FAMILY:
        return "in"
    if effect in OUT_OF_FAMILY + ALL_HELD_OUT:
        return "out"
    raise ValueError(f"unknown effect {effect!r}; choose one of {', '.join(EFFECTS + ALL_HELD_OUT)}")


def _mag(size, lo, hi, log=False):
    if log:
        return float(math.exp(math.log(lo) + size * (math.log(hi) - math.log(lo))))
    return float(lo + size * (hi - lo))


def draw_effect(effect: str, rng: np.random.Generator, *, size: float | None = None,
                given: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Random parameters of ``effect`` at effect ``size`` in [0, 1] (drawn uniform when None).

    Returns the params dict (JSON-serialisable, SI with unit suffixes where ambiguous), plus
    ``size``. Values in ``given`` override the drawn ones. Raises ValueError for an unknown effect.
    """
    family_of(effect)
    given = dict(given or {})
    bad = set(given) - set(PARAM_NAMES[effect]) - {"size"}
    if bad:
        raise ValueError(f"effect {effect!r} has no parameter(s) {sorted(bad)}; known: "
                         f"{', '.join(PARAM_NAMES[effect]) or 'none'}")
    for name, ch in (given.get("changes") or {}).items():
        if name not in _MISMATCH or not isinstance(ch, Mapping) or ch.get("kind") not in ("factor", "delta", "delta_deg"):
            raise ValueError(f"{effect}: change {name!r}: {ch!r}; expected one of {', '.join(_MISMATCH)} with "
                             "{'kind': factor|delta|delta_deg, 'value': ...}")
    u = float(rng.uniform(0.0, 1.0)) if size is None else float(size)
    if not 0.0 <= u <= 1.0:
        raise ValueError(f"effect size {u} outside [0, 1]")
    sign = 1.0 if rng.random() < 0.5 else -1.0
    p: dict[str, Any] = {}
    if effect == "none":
        return {**given, "size": 0.0}
    if effect == "vasilev":
        p = {"H": _mag(u, 0.01, 0.10, log=True)}
    elif effect == "lyasko":
        p = {"m1": _mag(u, 0.08, 0.8, log=True), "m2": float(rng.uniform(0.0, 0.08))}
    elif effect == "ding":
        p = {"n1": _mag(u, 0.06, 0.6, log=True)}
    elif effect in ("terrain_mismatch", "terrain_drift") + HELD_OUT_11:
        names = list(_MISMATCH)
        k = 1 if (effect != "terrain_mismatch" or rng.random() < 0.7) else 2
        chosen = [str(x) for x in rng.choice(names, size=k, replace=False)]
        changes = {}
        for name in chosen:
            kind, lo, hi = _MISMATCH[name]
            mag = _mag(u, lo, hi)
            s = 1.0 if rng.random() < 0.5 else -1.0
            if kind == "rel":
                changes[name] = {"kind": "factor", "value": float(1.0 + mag) if s > 0 else float(1.0 / (1.0 + mag))}
            elif kind == "abs":
                changes[name] = {"kind": "delta", "value": s * mag}
            else:
                changes[name] = {"kind": "delta_deg", "value": s * mag}
        p = {"changes": changes}
        if effect == "terrain_drift":
            p["mode"] = "compaction" if rng.random() < 0.5 else "patch"
            p["change_at"] = float(rng.uniform(0.3, 0.7))  # fraction of the distance (patch)
        elif effect == "saturating_drift":
            p["length"] = float(rng.uniform(0.08, 0.3))
        elif effect == "gradual_patch":
            p["change_at"], p["width"] = float(rng.uniform(0.3, 0.7)), float(rng.uniform(0.08, 0.25))
        elif effect == "patchy_ground":
            p["cycles"], p["phase"] = float(rng.uniform(1.0, 2.0)), float(rng.uniform(0.0, 1.0))
    elif effect == "stress_distribution":
        p = {"a1": _mag(u, 0.08, 0.45), "a2": float(rng.uniform(0.0, 0.3))}
    elif effect == "vertical_balance":
        p = {}
    elif effect == "rut":  # the rut's depth grows with the front wheel's load; its reloading stiffness drawn
        p = {"load_ratio": _mag(u, 0.15, 1.0), "R": float(rng.uniform(3.0, 20.0))}
    elif effect == "moisture":  # k_eq, c and phi falling (wetter) or rising (drier) together along the run
        m = {k: 0.5 * _mag(u, *_MISMATCH[k][1:]) for k in ("k_eq", "c", "phi")}
        p = {"changes": {"k_eq": {"kind": "factor", "value": (1.0 + m["k_eq"]) ** sign},
                         "c": {"kind": "factor", "value": (1.0 + m["c"]) ** sign},
                         "phi": {"kind": "delta_deg", "value": sign * m["phi"]}}}
    elif effect == "slip_sinkage_lag":
        p = {"H": _mag(u, 0.01, 0.10, log=True), "tau_s": float(rng.uniform(0.3, 2.0))}
    elif effect == "gnss_multipath":  # [start (fraction of the run), duration [s], offset [m/s]] per burst
        b_max = _mag(u, 0.05, 0.5, log=True)
        p = {"bursts": [[float(rng.uniform(0.02, 0.98)), float(rng.uniform(1.0, 5.0)),
                         float((1.0 if rng.random() < 0.5 else -1.0) * b_max * rng.uniform(0.5, 1.0))]
                        for _ in range(int(rng.integers(3, 11)))]}
    elif effect == "tyre_warmup":
        p = {"f": _mag(u, 0.005, 0.05, log=True), "length": float(rng.uniform(0.05, 0.3))}
    elif effect == "crust":
        p = {"a": _mag(u, 0.1, 1.0, log=True), "depth_ratio": float(rng.uniform(0.1, 0.5))}
    else:  # one parameter: _ONE_PARAM's range at size u
        name, lo, hi, log, form = _ONE_PARAM[effect]
        m = _mag(u, lo, hi, log=log)
        p = {name: {"plain": m, "signed": sign * m, "gain": 1.0 + sign * m, "one_minus": 1.0 - m}[form]}
    p.update(given)
    p["size"] = u
    return p


def _drift_fraction(effect: str, p: Mapping[str, Any], x: np.ndarray) -> np.ndarray:
    """The fraction g in [-1/2, 1/2] of a drift's change at distance fraction x (module doc)."""
    if effect == "saturating_drift":
        length = float(p["length"])
        return np.expm1(-x / length) / math.expm1(-1.0 / length) - 0.5
    if effect == "gradual_patch":
        return 0.5 * np.tanh((x - float(p["change_at"])) / float(p["width"]))
    if effect == "patchy_ground":
        return 0.5 * np.sin(2.0 * math.pi * (float(p["cycles"]) * x + float(p["phase"])))
    if effect == "moisture" or p["mode"] == "compaction":  # linear in distance, centred: the lab value mid-run
        return x - 0.5
    return 0.5 * np.tanh((x - float(p["change_at"])) / 0.02)  # another patch (2 % of the run transition)


def _apply_change(soil: dict, wheel_width_m: float, name: str, kind: str, value: float, frac=1.0) -> dict:
    """Soil with one value changed by ``frac`` x the change (frac (N,) or scalar; 1 = the full change)."""
    out = dict(soil)
    frac = np.asarray(frac, float)
    if name == "k_eq":  # kc and kphi scaled together: k_eq = kc/b + kphi scales by the factor
        f = value ** frac if kind == "factor" else 1.0 + frac * value
        out["kc"] = soil["kc"] * f
        out["kphi"] = soil["kphi"] * f
    elif name == "phi":
        out["phi"] = soil["phi"] + np.radians(value) * frac
    elif name == "n":
        out["n"] = soil["n"] + value * frac
    else:  # c, K
        out[name] = soil[name] * (value ** frac if kind == "factor" else 1.0 + frac * value)
    return out


def _bulldozing_resistance(soil, width_m, z, gamma_n_m3=16000.0):
    """Bekker's bulldozing resistance [N] of a wheel of width b sunk z (N,), soil dict.

    R_b = b (0.67 c z K_pc + 0.5 z^2 gamma K_pgamma), K_pc = (N_c - tan phi) cos^2 phi,
    K_pgamma = (2 N_gamma / tan phi + 1) cos^2 phi; bearing factors N_q = e^(pi tan phi)
    tan^2(45 deg + phi/2), N_c = (N_q - 1) cot phi, N_gamma = 2 (N_q + 1) tan phi (Vesic).
    Source: Bekker, Introduction to Terrain-Vehicle Systems (1969); Wong, Theory of Ground
    Vehicles, ch. 2.
    """
    phi = np.maximum(np.asarray(soil["phi"], float), math.radians(1.0))
    tp = np.tan(phi)
    nq = np.exp(math.pi * tp) * np.tan(math.pi / 4 + phi / 2) ** 2
    nc = (nq - 1.0) / tp
    ng = 2.0 * (nq + 1.0) * tp
    kpc = (nc - tp) * np.cos(phi) ** 2
    kpg = (2.0 * ng / tp + 1.0) * np.cos(phi) ** 2
    return width_m * (0.67 * np.asarray(soil["c"], float) * z * kpc + 0.5 * z * z * gamma_n_m3 * kpg)


@dataclass
class TruthModel:
    """The true soil-wheel physics of a run: lab soil + hidden effect.

    ``soil`` (SI dict, the lab values), ``radius_m``/``width_m`` the wheel, ``effect``,
    ``params`` (from :func:`draw_effect`), ``static_load_n`` (the instrumented wheel's
    static load, reference of load-dependent effects). All wheels of the vehicle run on
    the same soil with the same soil/tyre effects; sensor effects only touch the transducer.
    """

    soil: dict
    radius_m: float
    width_m: float
    effect: str = "none"
    params: dict = field(default_factory=dict)
    static_load_n: float = 11000.0
    epsrel: float = 1e-8  # quadrature tolerance of the truth (the sensor noise is ~1e-3 of the forces)

    def soil_at(self, frac=0.5, variability=None) -> dict:
        """The true soil at distance fraction ``frac`` (0..1, (N,) or scalar) of the run, with the
        relative soil variability factor ``variability`` (N,) on c, kc, kphi (None: none)."""
        soil = {k: np.asarray(v, float) for k, v in self.soil.items()}
        if self.effect == "terrain_mismatch":
            for name, ch in self.params["changes"].items():
                soil = _apply_change(soil, self.width_m, name, ch["kind"], ch["value"])
        elif self.effect in ("terrain_drift", "moisture") or self.effect in HELD_OUT_11:
            g = _drift_fraction(self.effect, self.params, np.asarray(frac, float))
            for name, ch in self.params["changes"].items():
                soil = _apply_change(soil, self.width_m, name, ch["kind"], ch["value"], frac=2.0 * g)
        if variability is not None:
            v = np.asarray(variability, float)
            soil["c"] = soil["c"] * v
            soil["kc"] = soil["kc"] * v
            soil["kphi"] = soil["kphi"] * v
        return soil

    def drive_forces(self, load_n, slip, frac=0.5, variability=None, slip_lag=None,
                     speed_mps=None) -> dict[str, np.ndarray]:
        """True soil forces of a driven wheel, 0 <= s < 1: dict of (N,) ``drawbar_pull_n``,
        ``torque_nm``, ``sinkage_m`` (soil/tyre effects applied, not sensor effects).
        ``slip_lag`` (N,): the lagged slip of ``slip_sinkage_lag`` (None: the slip itself).
        ``speed_mps`` (N,) the forward speed V of the speed effects (None: they are left out).
        Raises ValueError when the wheel buries itself (sinkage >= r)."""
        w = np.atleast_1d(np.asarray(load_n, float))
        s = np.broadcast_to(np.atleast_1d(np.asarray(slip, float)), w.shape)
        soil = self.soil_at(frac, variability)
        e, p = self.effect, self.params
        kw: dict[str, Any] = {}
        r = self.radius_m
        b = self.width_m
        # the tread's speed r omega from V and s (Eq. 6), for the effects that follow it
        rw = None if speed_mps is None else np.abs(np.asarray(speed_mps, float)) / np.maximum(1.0 - s, 0.03)
        if e == "vasilev":
            kw["H"] = p["H"]
        elif e == "slip_sinkage_lag":  # z0 + H s_lag: H scaled per sample so that H_eff s = H s_lag
            lag = s if slip_lag is None else np.asarray(slip_lag, float)
            kw["H"] = p["H"] * np.clip(lag, 0.0, None) / np.maximum(s, 1e-6)
        elif e == "tyre_compliance":  # the soil sees the slip less the tread's deformation slip
            t0 = wheel_forces(soil, r, b, w, s, epsrel=self.epsrel)["torque_nm"]
            s = np.maximum(s - p["e"] * t0 / (r * self.static_load_n), 0.0)
        elif e == "lyasko":
            kw["m1"], kw["m2"] = p["m1"], p["m2"]
        elif e == "ding":
            kw["n1"] = p["n1"]
        elif e == "stress_distribution":
            kw["stress"] = (p["a1"], p["a2"])
        elif e == "vertical_balance":
            kw["sinkage"] = "balance"
        elif e == "exit_angle":
            kw["exit_frac"] = p["exit_frac"]
        elif e == "shear_hump":
            kw["hump"] = (p["Kr"], 2.5)
        elif e == "strength_softening":
            kw["tau_scale"] = 1.0 - p["beta"] * s
        elif e == "rate_shear":
            kw["tau_scale"] = 1.0 + p["beta"] * np.log1p(s / RATE_SLIP_REF)
        elif e == "slip_angle":
            kw["slip_angle"] = math.radians(p["angle_deg"])
        elif e == "grouser":
            kw["grouser"] = p["height_ratio"] * self.radius_m
        elif e == "curved_envelope":
            kw["envelope"] = (self.static_peak_stress(), p["beta"])
        elif e == "pressure_k":
            kw["k_pressure"] = (self.static_peak_stress(), p["gamma"])
        elif e == "loose_top":
            kw["depth_power"] = (float(self.static_sinkage(self.static_load_n)), p["a"])
        elif e == "interface":
            kw["interface"] = (0.5 * self.static_peak_stress(), p["f"])
        elif e == "crust":  # dc = a (c + sigma0 tan phi) at the surface, fading over d_c = depth_ratio z0
            sig0 = self.static_peak_stress()
            kw["crust"] = (p["depth_ratio"] * float(self.static_sinkage(self.static_load_n)),
                           p["a"] * (float(self.soil["c"]) + sig0 * math.tan(float(self.soil["phi"]))))
        elif e == "slip_k":  # the shear band thickening with slip
            soil = dict(soil)
            soil["K"] = soil["K"] * (1.0 + p["a"] * s)
        elif e == "speed_sinkage" and rw is not None:  # z0 + H r omega / V_ref (Eq. 11's H s form)
            kw["H"] = p["H"] * (rw / SPEED_SINKAGE_REF_MPS) / np.maximum(s, 1e-6)
        elif e in ("mud_buildup", "radius_error") or (e == "tyre_growth" and rw is not None):
            # another wheel; slip is computed with the configured r
            if e == "tyre_growth":
                g = 1.0 + p["kappa"] * (rw / TYRE_GROWTH_REF_MPS) ** 2
            else:
                g = 1.0 + p["e"] * (np.asarray(frac, float) if e == "mud_buildup" else 1.0)
            r = self.radius_m * g
            s = np.maximum(1.0 - (1.0 - s) / g, 0.0)  # a smaller wheel at the lowest slips: rolling, s = 0
        elif e == "rut":  # the front wheel's rut, of its Eq. (10) sinkage at the static load on this soil
            kw["rut"] = (sinkage_eq10(soil, r, b, p["load_ratio"] * self.static_load_n), p["R"])
        elif e == "tyre_pressure_loss":  # the tyre deflects more along the run: a larger equivalent wheel
            r = self.radius_m * (1.0 + p["kappa"] * np.asarray(frac, float) * w / self.static_load_n)
        elif e == "hard_layer":
            kw["z_cap"] = p["depth_ratio"] * float(self.static_sinkage(self.static_load_n))
        elif e == "width_error":
            b = self.width_m * p["factor"]
        elif e == "tyre_deflection":
            r = self.radius_m * (1.0 + p["kappa"] * w / self.static_load_n)
        elif e == "load_dependent" or (e == "rate_sinkage" and speed_mps is not None):
            f = ((w / self.static_load_n) ** p["beta"] if e == "load_dependent"
                 else 1.0 + p["e"] * np.log1p(np.abs(speed_mps) / PLATE_RATE_MPS))
            soil = dict(soil)
            soil["kc"] = soil["kc"] * f
            soil["kphi"] = soil["kphi"] * f
        out = wheel_forces(soil, r, b, w, s, epsrel=self.epsrel, **kw)
        if e == "speed_resistance" and speed_mps is not None:
            out["drawbar_pull_n"] = out["drawbar_pull_n"] - p["e"] * w * (np.asarray(speed_mps) / SPEED_REF_MPS) ** 2
        if e == "tyre_hysteresis":
            out["torque_nm"] = out["torque_nm"] + p["f"] * w * r
        if e == "tyre_warmup":  # the hysteresis of a cold tyre, fading with the distance rolled
            out["torque_nm"] = out["torque_nm"] + p["f"] * np.exp(-np.asarray(frac, float) / p["length"]) * w * r
        if e == "bulldozing":
            out["drawbar_pull_n"] = out["drawbar_pull_n"] - p["factor"] * _bulldozing_resistance(
                soil, b, out["sinkage_m"])
        return out

    def static_sinkage(self, load_n) -> np.ndarray:
        """Eq. (10) sinkage of the lab soil [m] for ``load_n`` (N,) (for messages and checks)."""
        return sinkage_eq10(self.soil, self.radius_m, self.width_m, load_n)

    def static_peak_stress(self) -> float:
        """The lab soil's peak normal stress sigma0 [Pa] under the wheel at the static load: Eq. (2)
        at the Eq. (10) sinkage z0, (kc/b + kphi) z0^n (the reference of the stress-dependent effects)."""
        z0 = float(self.static_sinkage(self.static_load_n))
        return float((self.soil["kc"] / self.width_m + self.soil["kphi"]) * z0 ** self.soil["n"])
