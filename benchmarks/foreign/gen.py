#!/usr/bin/env python3
"""A second, independent field-run generator: candump logs of the vehicle's buses with a known truth.

Written by a helper session from the hardware contract (hardware.md), the DBC files and the seed
paper alone, without reading any of wheelsoil's code, and kept so: it imports nothing from
wheelsoil (its own Wong model in wong.py, quad integrals; cantools encodes the frames). Its
choices differ from wheelsoil.sim's where the contract leaves room: the front wheels turn with
the instrumented one (locked) or roll freely; in the braking phases the instrumented wheel coasts
(no torque) while the vehicle is braked elsewhere; the sinkage follows Eq. 10 at the wheel's load
or the vertical balance; noise, load transfer and resistance of its own. benchmarks/bench_foreign.py
scores the pipeline on its runs; tests/test_foreign_generator.py runs one.

usage: gen.py CASE [--fronts locked|free] [--gain-frame hub|wheel] [--sinkage eq10|balance] [--out NAME]
              [--outdir DIR] [--seed N] [--latency S] [--H M] [--m1 X --m2 X] [--phi-field DEG] [--fx-gain G]
CASE: a (none) | b (vasilev) | c (lyasko) | d (terrain phi-4deg) | e (Fx gain +8 %)
Writes DIR/NAME.log (candump -L), DIR/NAME_truth.csv and DIR/NAME_truth.json.
"""
import argparse, json, math
from pathlib import Path

import numpy as np
import cantools
from scipy.optimize import brentq
from wong import SAND, R, B, forces, z0_eq10

DBC = str(Path(__file__).resolve().parents[2] / 'dbc') + '/'  # the project's copies of the sensors' DBCs
M_VEH, M_W, I_W = 3600.0, 80.0, 11.5
W0 = 13000.0            # 8 kN static + 5 kN added (sand runs)
R_OTHER = 1500.0        # resistance not in 4*Dp (driveline, other losses) [N]
K_LT = 540.0            # rear-wheel load transfer per m/s^2 of acceleration [N/(m/s^2)]
FS_WFT, FS_WSS, FS_GNSS = 500, 100, 20

CASES = {
    'a': dict(effect='none', model='wong', params={}, latency=0.08, seed=11),
    'b': dict(effect='slip_sinkage', model='vasilev', params={'H': 0.035}, latency=0.12, seed=22),
    'c': dict(effect='slip_sinkage', model='lyasko', params={'m1': 0.10, 'm2': 0.04}, latency=0.05, seed=33),
    'd': dict(effect='terrain_mismatch', model='terrain_phi', params={'phi_field_deg': 21.0, 'phi_lab_deg': 25.0}, latency=0.15, seed=44),
    'e': dict(effect='unexplained', model='sensor_gain', params={'fx_gain': 1.08}, latency=0.08, seed=55),
}


def build_tables(case, sinkage_mode):
    """Dp(s, W), T(s, W), Weq7 on a grid, for the field truth and for the lab soil."""
    sg = np.linspace(0.0, 0.95, 58)
    wg = np.linspace(10500.0, 15500.0, 6)
    soil = dict(SAND)
    eff, p = 'none', None
    if case['model'] in ('vasilev', 'lyasko'):
        eff, p = case['model'], case['params']
    if case['model'] == 'terrain_phi':
        soil['phi'] = math.radians(case['params']['phi_field_deg'])

    def tab(soil, eff, p):
        Dp = np.zeros((len(sg), len(wg))); T = np.zeros_like(Dp); We = np.zeros_like(Dp)
        for j, W in enumerate(wg):
            Wz = W
            if sinkage_mode == 'balance':   # choose the Eq.10 'load' so that Eq.7 at s=0 returns W
                Wz = brentq(lambda x: forces(x, 0.0, soil)[0] - W, 0.5 * W, 1.5 * W)
            for i, s in enumerate(sg):
                We[i, j], Dp[i, j], T[i, j], _ = forces(Wz, s, soil, eff, p)
        return Dp, T, We
    return sg, wg, tab(soil, eff, p), tab(dict(SAND), 'none', None)


_IC = {}
def interp2(sg, wg, tab, s, W):
    from scipy.interpolate import RegularGridInterpolator
    key = id(tab)
    if key not in _IC:
        _IC[key] = RegularGridInterpolator((sg, wg), tab, bounds_error=False, fill_value=None)
    return _IC[key](np.column_stack([np.clip(s, 0, 0.95), np.clip(W, wg[0], wg[-1])]))


def smoothstep(x):
    x = np.clip(x, 0, 1)
    return 0.5 - 0.5 * np.cos(np.pi * x)


def simulate_truth(case, rng, sg, wg, field, lab):
    """Integrate the vehicle at 500 Hz. Returns dict of arrays on the WFT grid."""
    dt = 1.0 / FS_WFT
    lead_in, lead_out = 5.0, 4.0
    ncyc = 7
    # per-cycle plan
    cycles = []
    for k in range(ncyc):
        cycles.append(dict(t_up=rng.uniform(2.6, 3.4), t_down=rng.uniform(7.0, 9.0),
                           s_pk=rng.uniform(0.86, 0.92), a_brake=rng.uniform(0.55, 0.8),
                           v_low=rng.uniform(0.8, 1.1), hold=rng.uniform(1.5, 3.0)))
    V = 1.0
    t = 0.0
    out = {k: [] for k in ('t', 'V', 's', 'phase', 'Dp', 'T', 'W', 'Weq7')}
    Dpf, Tf, Wef = field
    Dpl = lab[0]

    def step(s, phase, brake_a=None):
        nonlocal V, t
        W = W0 + K_LT * (out['_a'] if '_a' in out else 0.0)
        if phase == 'traction':
            dp = float(interp2(sg, wg, Dpf, [s], [W])[0]); tq = float(interp2(sg, wg, Tf, [s], [W])[0])
            we = float(interp2(sg, wg, Wef, [s], [W])[0])
            if case['model'] == 'terrain_phi':   # only the instrumented wheel's track is on the weaker sand
                F = 3 * float(interp2(sg, wg, Dpl, [s], [W])[0]) + dp
            else:
                F = 4 * dp
            a = (F - R_OTHER) / M_VEH
        else:   # coast/brake: torque ~0, wheel rolls freely (s=0), small rolling resistance on this wheel
            dp, tq, we = -300.0, 0.0, W
            a = -brake_a
        out['_a'] = a
        for k, v in (('t', t), ('V', V), ('s', s), ('phase', phase), ('Dp', dp), ('T', tq), ('W', W), ('Weq7', we)):
            out[k].append(v)
        V = V + a * dt
        t += dt

    # lead-in: slow creep at low slip, traction (V grows slowly)
    def traction_segment(duration, sfun):
        n = int(round(duration / dt))
        for i in range(n):
            step(sfun(i * dt), 'traction')

    def brake_to(vtarget, a_b, hold):
        while V > vtarget:
            step(0.0, 'brake', a_b)
        for i in range(int(hold / dt)):
            step(0.0, 'brake', 0.0)

    # start: rolling slowly
    for i in range(int(lead_in / dt)):
        step(0.0, 'brake', 0.0)
    for c in cycles:
        tu, td, sp = c['t_up'], c['t_down'], c['s_pk']
        # slip: 0.02 -> s_pk in t_up (smooth), then s_pk -> 0.03 in t_down
        traction_segment(tu, lambda x: 0.02 + (sp - 0.02) * smoothstep(x / tu))
        traction_segment(td, lambda x: sp - (sp - 0.03) * smoothstep(x / td))
        # release torque smoothly: slip 0.03 -> 0 within 0.5 s (still traction-model)
        traction_segment(0.5, lambda x: 0.03 * (1 - smoothstep(x / 0.5)))
        brake_to(c['v_low'], c['a_brake'], c['hold'])
    for i in range(int(lead_out / dt)):
        step(0.0, 'brake', 0.0)
    out.pop('_a')
    d = {k: np.asarray(v) for k, v in out.items()}
    # smooth the hard phase switches of Dp/T a little (the hub can't jump): 50 ms moving average
    ker = np.ones(25) / 25
    for k in ('Dp', 'T', 'W'):
        d[k] = np.convolve(np.pad(d[k], 12, mode='edge'), ker, mode='valid')
    d['omega'] = d['V'] / (R * (1 - d['s']))
    d['dVdt'] = np.gradient(d['V'], dt)
    d['domega'] = np.gradient(d['omega'], dt)
    return d


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('case')
    ap.add_argument('--fronts', default='locked', choices=['locked', 'free'])
    ap.add_argument('--gain-frame', default='hub', choices=['hub', 'wheel'])
    ap.add_argument('--sinkage', default='eq10', choices=['eq10', 'balance'])
    ap.add_argument('--out', default=None)
    ap.add_argument('--outdir', default='.')
    # case parameters from the command line (default: the CASES values)
    ap.add_argument('--seed', type=int, default=None)
    ap.add_argument('--latency', type=float, default=None)
    ap.add_argument('--H', type=float, default=None)
    ap.add_argument('--m1', type=float, default=None)
    ap.add_argument('--m2', type=float, default=None)
    ap.add_argument('--phi-field', type=float, default=None)
    ap.add_argument('--fx-gain', type=float, default=None)
    a = ap.parse_args()
    case = dict(CASES[a.case])
    case['params'] = dict(case['params'])
    if a.seed is not None: case['seed'] = a.seed
    if a.latency is not None: case['latency'] = a.latency
    for opt, key, model in ((a.H, 'H', 'vasilev'), (a.m1, 'm1', 'lyasko'), (a.m2, 'm2', 'lyasko'),
                            (a.phi_field, 'phi_field_deg', 'terrain_phi'), (a.fx_gain, 'fx_gain', 'sensor_gain')):
        if opt is not None:
            if case['model'] != model:
                ap.error(f'--{key} does not apply to case {a.case} ({case["model"]})')
            case['params'][key] = opt
    name = a.out or a.case
    out = Path(a.outdir)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(case['seed'])
    sg, wg, field, lab = build_tables(case, a.sinkage)
    d = simulate_truth(case, rng, sg, wg, field, lab)
    n = len(d['t'])
    print(f"{name}: {n} WFT samples, {d['t'][-1]:.1f} s, V {d['V'].min():.2f}..{d['V'].max():.2f} m/s, "
          f"rpm max {d['omega'].max()*60/2/np.pi:.1f}, slip max {d['s'].max():.3f}, Dp {d['Dp'].min():.0f}..{d['Dp'].max():.0f}")

    wft = cantools.database.load_file(DBC + 'wft.dbc')
    wss = cantools.database.load_file(DBC + 'wheel_speed.dbc')
    gps = cantools.database.load_file(DBC + 'gps_rt_speedbox.dbc')

    t0_host = 1718035200.0 + rng.uniform(0, 1000)      # host (unix) clock at t=0
    gps_minus_host = 18.0 - 315964800.0 + 2.371          # leap s, GPS epoch, + host clock error 2.371 s
    lat = case['latency']
    frames = []   # (host_ts, bus, msg, data_bytes)

    def enc(db, msg, sig):
        m = db.get_message_by_name(msg)
        return m.frame_id, m.is_extended_frame, m.encode(sig, scaling=True, padding=False, strict=True)

    # --- WFT, 500 Hz
    ang = np.cumsum(d['omega']) / FS_WFT * 180 / np.pi
    ang = np.mod(ang + rng.uniform(0, 360), 360.0)
    q = 360.0 / 65536
    ang = np.minimum(np.round(ang / q), 65535) * q
    ar = np.radians(ang)
    Fx = d['Dp'] - M_W * d['dVdt']
    Fz = d['W'] + rng.normal(0, 20, n)  # load noise handled as sensor noise below too
    My = d['T'] + I_W * d['domega']
    if case['model'] == 'sensor_gain' and a.gain_frame == 'hub':
        Fx = Fx * case['params']['fx_gain']
    Fy = 150 * np.sin(2 * np.pi * 0.13 * d['t'])          # small lateral force
    Mx = -Fy * 0.05                                         # hub frame
    Mz = np.zeros(n)
    c_, s_ = np.cos(ar), np.sin(ar)
    Fxw = Fx * c_ - Fz * s_ + rng.normal(0, 20, n)
    Fzw = Fx * s_ + Fz * c_ + rng.normal(0, 20, n)
    if case['model'] == 'sensor_gain' and a.gain_frame == 'wheel':
        Fxw = Fxw * case['params']['fx_gain']
    Fyw = Fy + rng.normal(0, 20, n)
    Mxw = Mx * c_ - Mz * s_ + rng.normal(0, 4, n)
    Mzw = Mx * s_ + Mz * c_ + rng.normal(0, 4, n)
    Myn = My + rng.normal(0, 4, n)
    cnt0 = int(rng.integers(0, 256))
    for i in range(n):
        th = t0_host + d['t'][i] + abs(rng.normal(0.0002, 0.00005))
        cnt = (cnt0 + i) % 256
        fid, ext, data = enc(wft, 'WFT_RL_Force', dict(Fx_w=round(Fxw[i] * 2) / 2, Fy_w=round(Fyw[i] * 2) / 2,
                                                      Fz_w=round(Fzw[i]), Counter=cnt, Status=0))
        frames.append((th, 'can0', fid, ext, data))
        fid, ext, data = enc(wft, 'WFT_RL_Moment', dict(Mx_w=round(Mxw[i] * 4) / 4, My=round(Myn[i] * 4) / 4,
                                                       Mz_w=round(Mzw[i] * 4) / 4, Counter=cnt, Status=0))
        frames.append((th + 0.00013 + abs(rng.normal(0, 0.00002)), 'can0', fid, ext, data))
        fid, ext, data = enc(wft, 'WFT_RL_Angle', dict(WheelAngle=ang[i], Counter=cnt, Status=0))
        frames.append((th + 0.00024 + abs(rng.normal(0, 0.00002)), 'can0', fid, ext, data))
    # WFT diag: each mux value at 1 Hz
    for k in range(int(d['t'][-1])):
        for mux in range(3):
            sig = {0: dict(DiagMux=0, BridgeTemp=24.5 + 0.01 * k, SupplyVoltage=12.05),
                   1: dict(DiagMux=1, SerialNumber=20140123),
                   2: dict(DiagMux=2, FirmwareMajor=2, FirmwareMinor=1, CalibrationId=7)}[mux]
            fid, ext, data = enc(wft, 'WFT_RL_Diag', sig)
            frames.append((t0_host + k + 0.3 + 0.333 * mux + rng.uniform(0, 1e-4), 'can0', fid, ext, data))

    # --- wheel speeds, 100 Hz (RL instrumented; RR = RL (rear axle locked);
    #     fronts: 'locked' -> same omega as RL (4x4, locked centre diff), 'free' -> free rolling s=0)
    tw = np.arange(0, d['t'][-1], 1 / FS_WSS)
    om = np.interp(tw, d['t'], d['omega'])
    Vw = np.interp(tw, d['t'], d['V'])
    rpm_r = om * 60 / (2 * np.pi)
    rpm_f = rpm_r if a.fronts == 'locked' else Vw / R * 60 / (2 * np.pi)
    for i, tt in enumerate(tw):
        th = t0_host + tt + 0.0031 + abs(rng.normal(0.0003, 0.0001))
        def r_(x):
            return float(np.clip(round((x + rng.normal(0, 0.05)) * 100) / 100, 0, 655.35))
        fid, ext, data = enc(wss, 'WSS_WheelSpeeds', dict(WheelSpeed_FL=r_(rpm_f[i]), WheelSpeed_FR=r_(rpm_f[i]),
                                                          WheelSpeed_RL=r_(rpm_r[i]), WheelSpeed_RR=r_(rpm_r[i])))
        frames.append((th, 'can1', fid, ext, data))
        if i % 10 == 5:
            fid, ext, data = enc(wss, 'WSS_Status', dict(RollingCounter=(i // 10) % 16, SensorFault_FL=0,
                                                         SensorFault_FR=0, SensorFault_RL=0, SensorFault_RR=0))
            frames.append((th + 0.0002, 'can1', fid, ext, data))

    # --- GNSS, 20 Hz epochs aligned to GPS time; frames arrive 'lat' after the epoch they describe
    g0 = t0_host + gps_minus_host
    e_first = math.ceil(g0 / 0.05) * 0.05
    epochs = np.arange(e_first, g0 + d['t'][-1] - lat - 0.05, 0.05)
    for k, eg in enumerate(epochs):
        t_rel = eg - g0                   # host-relative time of the epoch
        v = float(np.interp(t_rel, d['t'], d['V']))
        th = t0_host + t_rel + lat + abs(rng.normal(0.0005, 0.0002))
        week = int(eg // 604800); tow = round(eg - week * 604800, 3)
        fid, ext, data = enc(gps, 'RT_SB_GPS_Time', dict(GPS_Week=week, GPS_Time=tow, Accuracy_GPS_Time=2,
                                                         Validity_GPS_Week=1, Validity_GPS_Time=1))
        frames.append((th, 'can1', fid, ext, data))
        vn = v + rng.normal(0, 0.02); vs = rng.normal(0, 0.02)
        fid, ext, data = enc(gps, 'RT_SB_GPS_Speed', dict(GPS_Speed_3D=round(abs(vn), 4), GPS_Speed_2D=round(abs(vn), 4),
                                                          Accuracy_GPS_Speed=3, Validity_GPS_Speed_3D=1,
                                                          Validity_GPS_Speed_2D=1))
        frames.append((th + 0.00025, 'can1', fid, ext, data))
        fid, ext, data = enc(gps, 'RT_SB_INS_Vel_Body_Axes', dict(INS_Vel_Sideways_2D=round(vs, 4),
                                                                  INS_Vel_Forwards_2D=round(vn, 4),
                                                                  Accuracy_INS_Vel_Body=3,
                                                                  Validity_INS_Vel_Sideways=1,
                                                                  Validity_INS_Vel_Forwards=1))
        frames.append((th + 0.0005, 'can1', fid, ext, data))
        if k % 20 == 0:
            fid, ext, data = enc(gps, 'RT_SB_GPS_Status', dict(GPS_Status=11, GPS_nSv=12, GPS_nSv_2=0, GPS_nSv_RTK=0,
                                                               RTK_Status=0, Firmware_Version_Major=1,
                                                               Firmware_Version_Intermediate=4,
                                                               Firmware_Version_Minor=2))
            frames.append((th + 0.00075, 'can1', fid, ext, data))

    frames.sort(key=lambda f: f[0])
    with open(out / f'{name}.log', 'w') as fh:
        for th, bus, fid, ext, data in frames:
            ids = f'{fid:08X}' if ext else f'{fid:03X}'
            fh.write(f'({th:.6f}) {bus} {ids}#{data.hex().upper()}\n')

    # truth on a 100 Hz grid
    import csv
    tg = np.arange(0, d['t'][-1], 0.01)
    with open(out / f'{name}_truth.csv', 'w', newline='') as fh:
        w = csv.writer(fh)
        w.writerow(['t_s', 'slip', 'speed_mps', 'omega_radps', 'load_n', 'drawbar_pull_n', 'torque_nm',
                    'weq7_n', 'phase', 'fx_hub_n', 'my_nm'])
        for tt in tg:
            i = int(round(tt * FS_WFT))
            w.writerow([f'{tt:.2f}', f"{d['s'][i]:.5f}", f"{d['V'][i]:.4f}", f"{d['omega'][i]:.4f}", f"{d['W'][i]:.1f}",
                        f"{d['Dp'][i]:.1f}", f"{d['T'][i]:.1f}", f"{d['Weq7'][i]:.1f}", d['phase'][i],
                        f"{Fx[i]:.1f}", f"{My[i]:.1f}"])
    truth = dict(case=a.case, name=name, effect=case['effect'], model=case['model'], params=case['params'],
                 gnss_latency_s=lat, gps_minus_host_s=gps_minus_host, host_t0=t0_host,
                 terrain_lab=dict(c_kpa=1.0, phi_deg=25.0, K_m=0.025, n=1.04, kc_kn=1.0, kphi_kn=580.0),
                 wheel=dict(r_m=R, b_m=B, m_w_kg=M_W, I_w_kgm2=I_W), static_load_n=W0,
                 z0_eq10_m=z0_eq10(W0, SAND), fronts=a.fronts, sinkage_mode=a.sinkage,
                 gain_frame=a.gain_frame if case['model'] == 'sensor_gain' else None,
                 duration_s=float(d['t'][-1]), seed=case['seed'],
                 notes='truth time series in NAME_truth.csv; t_s relative to host_t0 (host clock)')
    json.dump(truth, open(out / f'{name}_truth.json', 'w'), indent=1)


if __name__ == '__main__':
    main()
