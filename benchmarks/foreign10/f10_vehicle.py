"""foreign10: the hill track, the 4x4 tractor and its driver.

Longitudinal dynamics of a 4x4 with a locked drivetrain (all four wheels turn
at one angular speed omega), an engine governor and a human driver:

    M dV/dt = 2 Dp_f(s, W_f) + 2 Dp_r(s, W_r) - M g sin(alpha)
    J dw/dt = T_drive - 2 T_f(s, W_f) - 2 T_r(s, W_r),   J = 4 I_w + J_driveline
    s = (r w - V) / (r w)

with load transfer from grade and acceleration (CG height h, wheelbase L).
The soil forces come from tables of the run's soil model (f10_model.forces);
the instrumented wheel's signals are recomputed exactly afterwards.
"""
import math
import numpy as np

G = 9.81

VEHICLE = dict(
    mass_kg=4200.0,          # incl. wheels, driver, ballast
    wheelbase_m=2.50,
    cg_to_front_m=1.35,      # rear axle static share 0.54
    cg_height_m=1.05,
    J_driveline=40.0,        # engine + driveline reflected to the wheels, kg m^2 (total)
    T_max_Nm=45000.0,        # total wheel torque limit (low range)
    P_max_W=90000.0,
    T_brake_Nm=26000.0,
    gov_gain=5000.0,         # N m per rad/s
    front_track_m=1.55,
    rear_track_m=2.15,       # rear wheels run outside the front ruts (offset 0.30 m > half... see README)
)

WHEEL = dict(r=0.585, b=0.40, m=125.0, I=23.0)   # 400/70R24-class tractor wheel


# ---------------------------------------------------------------------------
def smooth_step(u):
    u = np.clip(u, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(math.pi * u)


class Track:
    """Hill track, horizontal coordinate x from end A (0) to end B (102 m).
    Face A climbs to grade gA, face B (climbed when driving B->A) to gB."""

    def __init__(self, gA, gB):
        self.gA, self.gB = gA, gB
        self.length = 102.0
        x = np.linspace(0.0, self.length, 4081)
        g = (gA * smooth_step((x - 6.0) / 10.0) * (1 - smooth_step((x - 38.0) / 10.0))
             - gB * smooth_step((x - 54.0) / 10.0) * (1 - smooth_step((x - 86.0) / 10.0)))
        self.x, self.g = x, g
        ds = np.sqrt(1.0 + g ** 2) * (x[1] - x[0])
        self.path = np.concatenate([[0.0], np.cumsum(0.5 * (ds[1:] + ds[:-1]))])
        self.path_len = self.path[-1]

    def grade_at_x(self, x):
        return np.interp(x, self.x, self.g)

    def x_of_path(self, p):
        return np.interp(p, self.path, self.x)


# ---------------------------------------------------------------------------
class ForceTable:
    """Dp(s, W) and T(s, W) of one wheel on one soil state, bilinear lookup."""

    def __init__(self, fn, smin=-1.0, smax=1.0, ns=121, Wmin=2000.0, Wmax=22000.0, nW=11):
        self.s = np.linspace(smin, smax, ns)
        self.W = np.linspace(Wmin, Wmax, nW)
        S, Wg = np.meshgrid(self.s, self.W, indexing="ij")
        Dp, T = fn(S.ravel(), Wg.ravel())
        self.Dp = Dp.reshape(S.shape)
        self.T = T.reshape(S.shape)
        self.ds = self.s[1] - self.s[0]
        self.dW = self.W[1] - self.W[0]
        self.ns, self.nW = ns, nW
        self.smin, self.Wmin = smin, Wmin
        self.Dpl = self.Dp.tolist()
        self.Tl = self.T.tolist()

    def __call__(self, s, W):
        fi = (min(max(s, self.smin), self.s[-1]) - self.smin) / self.ds
        i = min(int(fi), self.ns - 2)
        u = fi - i
        fj = (min(max(W, self.Wmin), self.W[-1]) - self.Wmin) / self.dW
        j = min(int(fj), self.nW - 2)
        v = fj - j
        D, T = self.Dpl, self.Tl
        d = (D[i][j] * (1 - u) * (1 - v) + D[i + 1][j] * u * (1 - v)
             + D[i][j + 1] * (1 - u) * v + D[i + 1][j + 1] * u * v)
        t = (T[i][j] * (1 - u) * (1 - v) + T[i + 1][j] * u * (1 - v)
             + T[i][j + 1] * (1 - u) * v + T[i + 1][j + 1] * u * v)
        return d, t


def axle_loads(alpha, acc, veh=VEHICLE):
    M = veh["mass_kg"]
    L = veh["wheelbase_m"]
    b_r = L - veh["cg_to_front_m"]
    h = veh["cg_height_m"]
    Nf = (M * G * np.cos(alpha) * b_r - (M * G * np.sin(alpha) + M * acc) * h) / L
    Nr = M * G * np.cos(alpha) - Nf
    return Nf, Nr


# ---------------------------------------------------------------------------
class Refused(Exception):
    pass


def simulate(track, plan, tables_for, veh=VEHICLE, wheel=WHEEL, dt=0.005):
    """Drive the plan.  plan: list of passes, each dict(direction=+1|-1,
    v_climb, v_desc, launch_rate, hill_stop (path fraction or None),
    hold_s, turn_s).  tables_for(pass_idx, x) -> (front_table, rear_table).
    Returns dict of time series at dt."""
    r = wheel["r"]
    M = veh["mass_kg"]
    J = 4 * wheel["I"] + veh["J_driveline"]
    L = veh["wheelbase_m"]
    cg_back = L - veh["cg_to_front_m"]
    out = {k: [] for k in ("t", "V", "w", "dV", "dw", "p", "x", "alpha", "pass", "Tdrive",
                           "hold", "Nf", "Nr", "wset", "s")}
    t = 0.0
    acc_prev = 0.0
    s_prev = 0.0
    for ip, ps in enumerate(plan):
        d = ps["direction"]
        plen = track.path_len
        # path position of the vehicle's CG along its direction of travel
        p = 6.0
        p_end = plen - 6.0
        V = 0.0
        w = 0.0
        wset = 0.0
        mode = "hold"
        hold_until = t + ps["hold_s"]
        stop_at = ps.get("hill_stop")
        stop_done = stop_at is None
        stall_t = 0.0
        ended = False
        push_t0 = None
        pushing = False
        while True:
            # position and grade along the direction of travel
            pp = p if d > 0 else plen - p
            x = float(track.x_of_path(pp))
            g = d * float(track.grade_at_x(x))
            alpha = math.atan(g)
            ft, rt = tables_for(ip, x)
            # driver's target speed
            if not stop_done and p >= stop_at * plen - 4.0:
                vt = 0.0
                if mode == "drive" and V < 0.04 and w < 0.15:
                    mode = "hold"
                    hold_until = t + ps["hill_hold_s"]
                    stop_done = True
            elif p >= p_end - 5.0:
                vt = 0.0
            else:
                vt = ps["v_climb"] if g > 0.02 else (ps["v_desc"] if g < -0.02 else ps["v_flat"])
                vt = min(vt, ps["v_crest"]) if abs(g) < 0.02 and p > 0.3 * plen else vt
                # a push on the climb: the driver asks for more speed for a few seconds
                if push_t0 is None and ps.get("push_at") is not None and p >= ps["push_at"] * plen:
                    push_t0 = t
                if push_t0 is not None and t - push_t0 < ps["push_s"]:
                    vt = ps["v_climb"] + ps["push_dv"]
                    pushing = True
                else:
                    pushing = False
            if mode == "hold":
                # brakes on: vehicle and wheels at rest
                V = 0.0
                w = 0.0
                wset = 0.0
                accel = 0.0
                dw = 0.0
                Nf, Nr = axle_loads(alpha, 0.0, veh)
                Td = 0.0
                s = 0.0
                if t >= hold_until:
                    if ended:
                        break
                    mode = "drive"
                    stall_t = 0.0
            else:
                # driver sets the governor's wheel-speed set point
                err = vt - V
                rate = ps["launch_rate"] if ((V < 1.0 or pushing) and vt > 0) else 1.2
                if err < -0.3:
                    # lifting off: the set point drops at once to the wheel speed of the vehicle speed
                    wset = min(wset, (max(V, 0.0) + 0.3) / r)
                dws = max(min(1.4 * err / r, rate), -ps["brake_rate"])
                if pushing and V < vt - 0.3:
                    # push: the driver floors the throttle until the wheels spin (~0.7), then holds it
                    dws = rate if s_prev < 0.7 else 0.0
                elif vt > 0 and V < 1.0 and s_prev < 0.75:
                    dws = rate          # launch from rest
                wset = max(wset + dws * dt, 0.0)
                # the driver eases off when the wheels spin
                cap = (max(V, 0.0) + 0.35) / (r * (1.0 - ps["s_cap"]))
                if wset > cap and V > 0.3:
                    wset = max(cap, wset - 2.0 * dt)
                # wheelspin without progress on a climb: ease off to regain traction
                if vt > 0 and V > 0.05 and s_prev > 0.6 and acc_prev < -0.05:
                    wset = max(V / (r * 0.7), wset - 4.0 * dt)
                Nf, Nr = axle_loads(alpha, acc_prev, veh)

                def soil(wv, Vv):
                    if wv * r > 1e-3:
                        sl = (wv * r - Vv) / (wv * r)
                    else:
                        sl = -1.0 if Vv > 1e-3 else 0.0
                    sl = max(sl, -1.0)
                    df, tf = ft(sl, 0.5 * Nf)
                    dr, tr = rt(sl, 0.5 * Nr)
                    return sl, 2 * df + 2 * dr, 2 * tf + 2 * tr

                def tdrive(wv):
                    if wset <= 0.0 and vt <= 0.0:
                        # stopping: the driver holds the brake pedal (friction brake)
                        return -veh["T_brake_Nm"] if wv > 1e-3 else -veh["T_brake_Nm"] * wv / 1e-3
                    lim = min(veh["T_max_Nm"], veh["P_max_W"] / max(wv, 0.5))
                    return max(min(veh["gov_gain"] * (wset - wv), lim), -veh["T_brake_Nm"])

                # implicit Euler on omega (stiff at low speed), explicit on V
                wn = w
                for _ in range(4):
                    _, _, Ts = soil(wn, V)
                    fres = wn - w - dt / J * (tdrive(wn) - Ts)
                    h_ = 1e-4
                    _, _, Ts2 = soil(wn + h_, V)
                    fres2 = wn + h_ - w - dt / J * (tdrive(wn + h_) - Ts2)
                    der = (fres2 - fres) / h_
                    if der <= 0:
                        der = 1.0
                    wn = max(wn - fres / der, 0.0)
                s, Dsum, Ts = soil(wn, V)
                Td = tdrive(wn)
                accel = (Dsum - M * G * math.sin(alpha)) / M
                dw = (wn - w) / dt
                w = wn
                Vn = V + accel * dt
                if Vn < 0.0:
                    # the soil cannot hold the vehicle: it would slide back
                    Vn = 0.0
                    accel = (Vn - V) / dt
                V = Vn
                s_prev = s
                acc_prev = 0.8 * acc_prev + 0.2 * accel
                if vt > 0 and V < 0.05 and w * r > 0.5:
                    stall_t += dt
                    if stall_t > 4.0:
                        raise Refused(f"the vehicle cannot climb: wheels spinning at standstill on grade "
                                      f"{100 * g:.1f} % (pass {ip + 1}, x = {x:.1f} m)")
                else:
                    stall_t = 0.0
                if p >= p_end - 5.0 and V < 0.04 and w < 0.15:
                    mode = "hold"
                    ended = True
                    hold_until = t + ps["turn_s"]
            out["t"].append(t)
            out["V"].append(V)
            out["w"].append(w)
            out["dV"].append(accel)
            out["dw"].append(dw)
            out["p"].append(p)
            out["x"].append(x)
            out["alpha"].append(alpha)
            out["pass"].append(ip)
            out["Tdrive"].append(Td)
            out["hold"].append(mode == "hold")
            out["Nf"].append(Nf)
            out["Nr"].append(Nr)
            out["wset"].append(wset)
            out["s"].append(s)
            p += V * dt
            t += dt
            if t > 400:
                raise Refused("run did not finish (vehicle stuck)")
    res = {k: np.asarray(v) for k, v in out.items()}
    res["cg_back"] = cg_back
    return res
