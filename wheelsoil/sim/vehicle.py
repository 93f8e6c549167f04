"""Longitudinal dynamics of the 4x4 test vehicle in accelerate-brake slip sweeps.

The vehicle (3.6 t, all four wheels driven through locked differentials, so
every wheel turns at the same omega and has the same slip) moves only by the
soil's drawbar pull on its four wheels (paper section 2.2; hardware.md):

    m dV/dt = 2 Dp(W_front, s) + 2 Dp(W_rear, s) - m g sin(grade) - 0.5 rho CdA V^2

Dp of a driving wheel (s >= 0) is the true soil model (:class:`~.effects.TruthModel`,
reference quadrature) tabulated on a (load, slip) grid and interpolated with
bicubic splines (error checked on random points: :meth:`ForceTable.max_error`);
braking (skid, s < 0) blends from the soil's Dp at s = 0 into a skid curve
-(f_rr + mu(s)) W, mu = 0.45 (1 - exp(s/0.08)). Loads: static (the front/rear
split of 3.6 t with the instrumented rear wheel's 8 kN, plus the added load
over the rear axle) plus the pitch load transfer m a h/L (body pitch mode
1.4 Hz, damping 0.35) and band-limited bumps.

The driver (a slip controller, as in a slip-sweep test): standstill with brakes
held; pull-away commanding a wheel speed ramp; an acceleration whose
commanded slip sweeps from ~0.04 to ~0.85-0.92 and back; a short hold; braking
with skid slip to a crawl or to a stop. The wheel speed is limited to the
wheel-speed sensor's range (slip <= 1 - V/(r omega_max)). Integrated with
explicit Euler at ``DT_S`` (10 ms); V >= 0 (the brakes hold the vehicle).
If the four wheels' summed drawbar pull cannot overcome the resistance at any
slip, :func:`check_can_move` refuses the run with a message saying so.

A second procedure, ``"tow"`` (or ``"tow-down"``), is the steady drawbar-pull
test of the field (Wong, *Theory of Ground Vehicles*, 4th ed., §4.1; the OECD
tractor test code's drawbar test): the vehicle pulls a towed load vehicle
whose brake holds the speed near a test speed v_test while the driver holds
the wheels' slip at one level after another, each for a few seconds:

    m dV/dt = 2 Dp_f + 2 Dp_r - resistance - F_tow,
    F_tow = max(0, 2 Dp_f + 2 Dp_r - resistance - m (v_test - V) / 1 s)

(a brake cannot push: where the wheels cannot pull the resistance, the vehicle slows).

There is no acceleration to speak of: the data are steady holds joined by
short slip transitions, a shape the slip sweeps never give.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["VehicleParams", "ForceTable", "check_can_move", "simulate_dynamics", "skid_forces", "DT_S", "PROCEDURES"]

DT_S = 0.01
G = 9.81
#: Test procedures of :func:`simulate_dynamics`: accelerate-brake slip sweeps; the steady drawbar-pull
#: test with the slip levels held from the lowest up, or from the highest down.
PROCEDURES = ("sweeps", "tow", "tow-down")
#: Largest wheel angular acceleration the driveline gives [rad/s^2] (I_w * 25 = 290 N m).
OMEGA_RATE_MAX = 25.0


@dataclass(frozen=True)
class VehicleParams:
    """The test vehicle (hardware.md, paper 2.2). Loads per wheel [N]; mass [kg]."""

    mass_kg: float = 3600.0
    rear_static_load_n: float = 8000.0   # per rear wheel (paper: left rear about 8 kN)
    wheelbase_m: float = 3.3
    cg_height_m: float = 0.95
    cda_m2: float = 3.0                  # drag coefficient x frontal area
    air_density: float = 1.2
    omega_max_radps: float = 600.0 * 2 * math.pi / 60  # wheel-speed sensor range (655 rpm) with margin
    rolling_skid: float = 0.06           # f_rr of the skid curve
    wheel_mass_kg: float = 80.0          # rim + tyre outboard of the WFT (hardware.md)
    wheel_inertia_kgm2: float = 11.5

    def loads(self, added_load_n: float) -> tuple[float, float, float]:
        """(total mass [kg], static front load per wheel, static rear load per wheel) [N]:
        the added load is ballast over the rear axle (each rear wheel +added_load_n)."""
        m = self.mass_kg + 2.0 * added_load_n / G
        front = (self.mass_kg * G - 2.0 * self.rear_static_load_n) / 2.0
        return m, front, self.rear_static_load_n + added_load_n


def skid_forces(dp0, t0, load_n, slip, radius_m, rolling=0.06):
    """Braking-wheel Dp [N], T [N m] for s < 0 blended from the driving values at s = 0.

    dp0, t0: soil Dp, T at s = 0 (N,); load (N,); slip (N,) <= 0. Skid curve
    Dp = -(rolling + mu) W, mu = 0.45 (1 - exp(s / 0.08)), T = r * (-mu W);
    blend weight smoothstep(-s / 0.05). Not a soil model (the paper's model is
    for driving), only a plausible deceleration.
    """
    s = np.minimum(np.asarray(slip, float), 0.0)
    x = np.clip(-s / 0.05, 0.0, 1.0)
    wgt = x * x * (3.0 - 2.0 * x)
    mu = 0.45 * (1.0 - np.exp(s / 0.08))
    dp_b = -(rolling + mu) * load_n
    t_b = -radius_m * mu * load_n
    return (1 - wgt) * dp0 + wgt * dp_b, (1 - wgt) * t0 + wgt * t_b


class ForceTable:
    """Dp(W, s) of the true soil on a (load, slip) grid, bicubic splines; slip -0.6..0.97.

    ``truth``: a :class:`~.effects.TruthModel`; ``load_range``: (lo, hi) [N];
    ``fracs``: distance fractions (terrain drift) tabulated, linear in between.
    """

    S_DRIVE = np.concatenate([np.linspace(0.0, 0.1, 11), np.linspace(0.12, 0.97, 44)])
    S_SKID = np.linspace(-0.6, -0.005, 30)

    def __init__(self, truth, load_range, fracs=(0.5,), n_loads: int = 14):
        from scipy.interpolate import RectBivariateSpline

        lo, hi = load_range
        self.truth = truth
        self.loads = np.linspace(lo, hi, n_loads)
        self.fracs = np.asarray(fracs, float)
        self.slips = np.concatenate([self.S_SKID, self.S_DRIVE])
        self.splines = []
        W, S = np.meshgrid(self.loads, self.S_DRIVE, indexing="ij")
        for f in self.fracs:
            drv = truth.drive_forces(W.ravel(), S.ravel(), frac=f)
            dp = drv["drawbar_pull_n"].reshape(W.shape)
            dp0 = dp[:, :1]
            Wk, Sk = np.meshgrid(self.loads, self.S_SKID, indexing="ij")
            dpk, _ = skid_forces(np.broadcast_to(dp0, Wk.shape), 0.0, Wk, Sk, truth.radius_m)
            table = np.concatenate([dpk, dp], axis=1)
            self.splines.append(RectBivariateSpline(self.loads, self.slips, table, kx=3, ky=3))

    def dp(self, load_n: float, slip: float, frac: float = 0.5) -> float:
        """Interpolated Dp [N] at one (load, slip, distance fraction)."""
        w = min(max(load_n, self.loads[0]), self.loads[-1])
        s = min(max(slip, self.slips[0]), self.slips[-1])
        if len(self.splines) == 1:
            return float(self.splines[0].ev(w, s))
        f = min(max(frac, self.fracs[0]), self.fracs[-1])
        i = min(int(np.searchsorted(self.fracs, f, side="right")) - 1, len(self.fracs) - 2)
        t = (f - self.fracs[i]) / (self.fracs[i + 1] - self.fracs[i])
        return float((1 - t) * self.splines[i].ev(w, s) + t * self.splines[i + 1].ev(w, s))

    def dp_many(self, load_n, slip, frac=0.5):
        """Vectorised :meth:`dp` (arrays (N,))."""
        w = np.clip(load_n, self.loads[0], self.loads[-1])
        s = np.clip(slip, self.slips[0], self.slips[-1])
        if len(self.splines) == 1:
            return self.splines[0].ev(w, s)
        f = np.clip(np.broadcast_to(frac, w.shape), self.fracs[0], self.fracs[-1])
        out = np.empty(w.shape)
        i = np.clip(np.searchsorted(self.fracs, f, side="right") - 1, 0, len(self.fracs) - 2)
        for k in range(len(self.fracs) - 1):
            sel = i == k
            t = (f[sel] - self.fracs[k]) / (self.fracs[k + 1] - self.fracs[k])
            out[sel] = (1 - t) * self.splines[k].ev(w[sel], s[sel]) + t * self.splines[k + 1].ev(w[sel], s[sel])
        return out

    def max_error(self, rng, n: int = 200) -> float:
        """Largest |interpolated - reference| Dp [N] on ``n`` random driving points (s in 0.01..0.95)."""
        w = rng.uniform(self.loads[0], self.loads[-1], n)
        s = rng.uniform(0.01, 0.95, n)
        f = rng.choice(self.fracs, n)
        err = 0.0
        for fv in np.unique(f):
            sel = f == fv
            ref = self.truth.drive_forces(w[sel], s[sel], frac=fv)["drawbar_pull_n"]
            err = max(err, float(np.max(np.abs(self.dp_many(w[sel], s[sel], fv) - ref))))
        return err


def resistance_n(veh: VehicleParams, mass_kg: float, speed_mps, grade: float):
    """Grade and aerodynamic resistance [N] (the soil's own resistance is in each wheel's Dp)."""
    return mass_kg * G * math.sin(grade) + 0.5 * veh.air_density * veh.cda_m2 * np.asarray(speed_mps) ** 2


def check_can_move(table: ForceTable, veh: VehicleParams, added_load_n: float, grade: float, *,
                   what: str = "") -> dict:
    """Refuse a run on which the 4x4 could not pull away.

    The summed drawbar pull of the four wheels at their static loads, maximised over slip
    0.05..0.95 and over the tabulated distance fractions' worst case, must give at least
    0.15 m/s^2 against the grade. Returns ``{max_net_force_n, slip_at_max, accel_max_mps2,
    net_force_full_slip_n, can_start}``: ``can_start`` False when the wheels dig in at s -> 1
    (from standstill every wheel speed is s = 1), then the runs start rolling and brake only to a
    crawl. Raises ValueError otherwise, with the numbers and what to change.
    """
    m, wf, wr = veh.loads(added_load_n)
    s = np.linspace(0.05, 0.95, 91)
    worst = None
    for f in table.fracs:
        net = (2 * table.dp_many(np.full_like(s, wf), s, f) + 2 * table.dp_many(np.full_like(s, wr), s, f)
               - resistance_n(veh, m, 1.0, grade))
        i = int(np.argmax(net))
        if worst is None or net[i] < worst[0]:
            worst = (float(net[i]), float(s[i]))
    full = min(float(2 * table.dp(wf, 0.97, f) + 2 * table.dp(wr, 0.97, f)) - float(resistance_n(veh, m, 0.0, grade))
               for f in table.fracs)
    a = worst[0] / m
    if a < 0.15:
        raise ValueError(
            f"the vehicle cannot move{what}: the four wheels' summed drawbar pull minus the grade/air "
            f"resistance peaks at {worst[0]:.0f} N (s = {worst[1]:.2f}), {a:.3f} m/s^2 for {m:.0f} kg "
            f"(front {wf:.0f} N, rear {wr:.0f} N per wheel; Wong's Dp < 0 means the compaction resistance "
            "exceeds the thrust). Choose a larger or wider wheel (--wheel-radius/--wheel-width), a smaller "
            "--added-load, or a firmer terrain.")
    # from standstill any wheel speed means s = 1: the vehicle can start only if Dp(s -> 1) pulls
    return {"max_net_force_n": worst[0], "slip_at_max": worst[1], "accel_max_mps2": a,
            "net_force_full_slip_n": full, "can_start": full / m > 0.1}


def _smooth(x):
    x = min(max(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


def simulate_dynamics(table: ForceTable, veh: VehicleParams, rng: np.random.Generator, *,
                      added_load_n: float, radius_m: float, duration_s: float | None, n_cycles: int,
                      grade: float = 0.0, bumps_front=None, bumps_rear=None, dist_total_guess_m: float = 300.0,
                      slip_noise=None, can_start: bool = True, slip_best: float = 0.5,
                      slip_max: float | None = None, procedure: str = "sweeps"):
    """Integrate the vehicle through accelerate-brake cycles (``procedure="sweeps"``) or through
    steady drawbar-pull passes against a towed load (``"tow"``, ``"tow-down"``; module doc).

    ``bumps_front/rear``: callables t -> load disturbance [N] (or None); ``slip_noise``:
    array of the slip controller's wobble per step (band-limited, or None); ``can_start``: False
    when the vehicle could not pull away from standstill (it then enters the test strip rolling
    at 1 m/s and brakes only to a crawl); ``slip_best``: the slip of the largest net pull. Below
    1 m/s the driver keeps the slip near ``slip_best`` (else a soil that digs in at high slip
    would bog the vehicle down). ``slip_max``: the highest slip the driver sweeps to (each sweep
    peaks at 0.925 .. 1 times it); None: 0.86 .. 0.93 (the paper's sweeps to s = 0.9). Returns a dict of
    arrays on the ``DT_S`` grid: ``t_s, speed_mps, accel_mps2, omega_radps, slip (s of the
    wheels; nan at standstill), slip_cmd, load_front_n, load_rear_n, dp_front_n, dp_rear_n
    (per wheel, as used), resistance_n, distance_m, phase (object), cycle (int)``, and
    ``mass_kg``. The distance fraction used for terrain drift is distance /
    ``dist_total_guess_m`` clipped to [0, 1] (the caller iterates to the true total).
    ``"tow"`` (``"tow-down"``: the same levels from the top down): each pass pulls away, then
    holds 6 to 9 slip levels from about 0.12 up to the sweeps' highest slip, 3 to 6 s each,
    joined by 0.8 to 1.5 s transitions, at a test speed of 1.0 to 1.6 m/s held by the towed
    vehicle's brake (``F_tow`` >= 0: where the wheels cannot pull the resistance the vehicle
    slows, and below 0.5 m/s the driver ends the pass), then brakes; ``phase`` is ``"tow"`` in
    the holds and transitions, ``cycle`` the pass; the arrays add ``tow_n``.
    Raises ValueError when the vehicle stalls in a pull-away for 20 s (cannot move), or for an
    unknown ``procedure``.
    """
    if procedure not in PROCEDURES:
        raise ValueError(f"procedure must be one of {PROCEDURES}, got {procedure!r}")
    m, wf0, wr0 = veh.loads(added_load_n)
    r = radius_m
    dt = DT_S
    t_end = duration_s if duration_s is not None else 1e9
    kt = m * veh.cg_height_m / veh.wheelbase_m / 2.0  # load transfer per wheel per m/s^2
    wn, zeta = 2 * math.pi * 1.4, 0.35  # body pitch mode
    out = {k: [] for k in ("t_s", "speed_mps", "accel_mps2", "omega_radps", "slip", "slip_cmd",
                           "load_front_n", "load_rear_n", "dp_front_n", "dp_rear_n", "resistance_n",
                           "distance_m", "phase", "cycle", "tow_n")}
    V = 0.0 if can_start else 1.0
    x = 0.0
    lt, lt_dot = 0.0, 0.0  # pitch load transfer state [N]
    om_state = [0.0 if can_start else V / (r * 0.96)]  # wheels' angular speed [rad/s] (rate-limited follower)
    a_prev = 0.0
    t = 0.0
    cycle = 0
    stop_next = can_start
    nstep = [0]

    def wobble():
        # the slip controller's wobble: band-limited noise given by the caller (index = step)
        if slip_noise is None:
            return 0.0
        return float(slip_noise[min(nstep[0], len(slip_noise) - 1)])

    def step(phase, cyc, s_cmd=None, rw_cmd=None, v_hold=None):
        """One Euler step with commanded slip or commanded wheel rim speed r*omega; ``v_hold``:
        the towed vehicle's brake holds this speed (its force >= 0)."""
        nonlocal V, x, lt, lt_dot, a_prev, t
        tow = 0.0
        frac = min(max(x / dist_total_guess_m, 0.0), 1.0)
        bf = bumps_front(t) if bumps_front else 0.0
        br = bumps_rear(t) if bumps_rear else 0.0
        w_f = max(wf0 - lt + bf * _smooth(V / 1.0), 0.3 * wf0)
        w_r = max(wr0 + lt + br * _smooth(V / 1.0), 0.3 * wr0)
        if phase == "standstill":
            s, om, dpf, dpr = float("nan"), 0.0, 0.0, 0.0
            om_state[0] = 0.0
            a = 0.0
            res = 0.0
        else:
            if rw_cmd is not None:
                om_cmd = max(rw_cmd, 0.0) / r
            else:
                sc = min(s_cmd, 0.97)
                if sc > slip_best and phase != "brake":  # slow: back off towards the best traction
                    sc = slip_best + (sc - slip_best) * _smooth((V - 0.4) / 0.6)
                om_cmd = max(V, 0.3) / (r * (1.0 - sc)) if phase != "brake" else V / (r * (1.0 - sc))
            om_cmd = min(om_cmd, veh.omega_max_radps)  # the wheel-speed sensor's range
            # driveline: first-order lag (0.12 s) with a rate limit of OMEGA_RATE_MAX
            d_om = (om_cmd - om_state[0]) * dt / 0.12
            lim = OMEGA_RATE_MAX * dt
            om = om_state[0] + min(max(d_om, -lim), lim)
            om_state[0] = om
            s = 1.0 - V / (om * r) if om * r > 1e-6 else (0.0 if V <= 0 else -0.6)
            s = min(max(s, -0.6), 0.97)
            dpf = table.dp(w_f, s, frac)
            dpr = table.dp(w_r, s, frac)
            res = float(resistance_n(veh, m, V, grade))
            a = (2 * dpf + 2 * dpr - res) / m
            if v_hold is not None:  # the load vehicle's brake: a speed controller (time constant 1 s)
                tow = max(m * (a - (v_hold - V) / 1.0), 0.0)
                a -= tow / m
            if V <= 0.0 and a < 0:
                a = 0.0  # brakes / static friction hold the vehicle
        # pitch load transfer: 2nd-order response to kt * a
        lt_dd = wn * wn * (kt * a_prev - lt) - 2 * zeta * wn * lt_dot
        lt_dot += lt_dd * dt
        lt += lt_dot * dt
        for k, v in (("t_s", t), ("speed_mps", V), ("accel_mps2", a), ("omega_radps", om), ("slip", s),
                     ("slip_cmd", s_cmd if s_cmd is not None else float("nan")), ("load_front_n", w_f),
                     ("load_rear_n", w_r), ("dp_front_n", dpf), ("dp_rear_n", dpr), ("resistance_n", res),
                     ("distance_m", x), ("phase", phase), ("cycle", cyc), ("tow_n", tow)):
            out[k].append(v)
        V = max(V + a * dt, 0.0)
        x += V * dt
        nstep[0] += 1
        a_prev = a
        t += dt
        return s

    cycles_done = 0
    want = n_cycles if duration_s is None else 10**6
    while cycles_done < want and t < t_end:
        if stop_next:
            T = rng.uniform(2.0, 4.0)
            t0 = t
            while t - t0 < T and t < t_end:
                step("standstill", -1)
            # pull-away: the wheel rim speed ramps up; the vehicle follows by traction
            v_pa = rng.uniform(0.7, 1.1)
            s_pa = min(max(slip_best, 0.2), 0.6)  # the driver pulls away near the best traction
            t0 = t
            while V < v_pa and t < t_end:
                if t - t0 > 20.0:
                    raise ValueError(f"the vehicle cannot move: after 20 s of pull-away at slip {s_pa:.2f} "
                                     f"its speed is {V:.2f} m/s (summed drawbar pull too small)")
                ramp = min((t - t0) / 1.5, 1.0) * 0.35
                step("other", -1, rw_cmd=max(V / (1.0 - s_pa), ramp))
        if procedure != "sweeps":
            _tow_pass(step, rng, cycle, lambda: t, lambda: V, t_end, out, slip_max, wobble,
                      down=procedure == "tow-down")
            cycle += 1
            cycles_done += 1
            stop_next = can_start
            _brake(step, rng, lambda: t, lambda: V, t_end, stop_next)
            continue
        # slip down to rolling slip before the sweep
        s_roll = rng.uniform(0.03, 0.06)
        s_now = out["slip"][-1] if out["slip"] and np.isfinite(out["slip"][-1]) else s_roll
        T = rng.uniform(1.0, 2.0)
        t0 = t
        while t - t0 < T and t < t_end:
            u = (t - t0) / T
            step("other", -1, s_cmd=s_now + (s_roll - s_now) * _smooth(2 * u) + wobble() * 0.3)
        # acceleration: the slip sweep
        T = rng.uniform(6.0, 9.0)
        s_max = rng.uniform(0.86, 0.93) if slip_max is None else rng.uniform(0.925, 1.0) * slip_max
        skew = rng.uniform(0.45, 0.8)  # the slip peaks early, while the vehicle is still slow
        t0 = t
        while t - t0 < T and t < t_end:
            u = (t - t0) / T
            shape = math.sin(math.pi * u ** skew) ** 1.3
            step("accel", cycle, s_cmd=max(s_roll + (s_max - s_roll) * shape + wobble(), 0.0))
        cycle += 1
        # short hold
        T = rng.uniform(0.5, 1.5)
        t0 = t
        while t - t0 < T and t < t_end:
            step("other", -1, s_cmd=s_roll + 0.3 * wobble())
        # braking (skid) to a crawl or to a stop
        cycles_done += 1
        last = cycles_done >= want
        stop_next = can_start and (last or rng.random() < 0.5)
        _brake(step, rng, lambda: t, lambda: V, t_end, stop_next)
    if duration_s is None and can_start:
        t0 = t
        while t - t0 < 2.0:
            step("standstill", -1)
    res = {k: np.asarray(v) for k, v in out.items()}
    res["phase"] = np.asarray(out["phase"], dtype=object)
    res["cycle"] = np.asarray(out["cycle"], dtype=int)
    res["mass_kg"] = m
    return res


def _brake(step, rng, now, speed, t_end, stop):
    """Brake with skid slip (-0.08 .. -0.25) to a stop (``stop``) or to a crawl of 0.8 .. 1.4 m/s."""
    v_stop = 0.0 if stop else rng.uniform(0.8, 1.4)
    s_br = rng.uniform(0.08, 0.25)
    t0 = now()
    while now() < t_end:
        tb = now() - t0
        if tb > 0.3 and ((stop and speed() <= 0.0) or (not stop and speed() <= v_stop)):
            break
        if tb > 30.0:
            break
        step("brake", -1, s_cmd=-s_br * _smooth(tb / 0.6))


def _tow_pass(step, rng, cycle, now, speed, t_end, out, slip_max, wobble, down=False):
    """One steady drawbar-pull pass of the ``"tow"`` procedure (module doc): slip levels held in
    turn against the towed load at a held test speed, from the lowest up (``down``: from the
    highest down); ends early when the vehicle bogs down."""
    v_test = rng.uniform(1.0, 1.6)
    top = rng.uniform(0.86, 0.93) if slip_max is None else rng.uniform(0.925, 1.0) * slip_max
    levels = np.linspace(rng.uniform(0.10, 0.15), top, int(rng.integers(6, 10)))
    if down:
        levels = levels[::-1]
    s_prev = out["slip"][-1] if out["slip"] and np.isfinite(out["slip"][-1]) else 0.05
    for lvl in levels:
        t_tr, t_hold = rng.uniform(0.8, 1.5), rng.uniform(3.0, 6.0)
        t0 = now()
        while now() - t0 < t_tr + t_hold and now() < t_end:
            u = min((now() - t0) / t_tr, 1.0)
            step("tow", cycle, s_cmd=s_prev + (lvl - s_prev) * _smooth(u) + 0.5 * wobble(), v_hold=v_test)
            if speed() < 0.5 and now() - t0 > t_tr:
                return  # bogged down: the driver ends the pass
        s_prev = lvl
