"""Independent Wong rigid-wheel model (paper Eqs 1-13, typos fixed per hardware.md)."""
import numpy as np
from scipy.integrate import quad

SAND = dict(c=1.0e3, phi=np.radians(25.0), K=0.025, n=1.04, kc=1.0e3, kphi=580.0e3)
R, B = 0.47, 0.32

def z0_eq10(W, soil, r=R, b=B, n=None):
    n = soil['n'] if n is None else n
    return (3*W/(np.sqrt(2*r)*(soil['kc'] + b*soil['kphi'])*(3 - n)))**(2/(2*n + 1))

def sinkage(W, s, soil, effect='none', p=None, r=R, b=B):
    """returns (z, n_used)"""
    p = p or {}
    n = soil['n']
    if effect == 'ding':
        n = n + p['n1']*s
        return z0_eq10(W, soil, r, b, n=n), n
    z0 = z0_eq10(W, soil, r, b)
    if effect == 'vasilev':
        return z0 + p['H']*s, n
    if effect == 'lyasko':
        return (1 + p['m1']*s)/(1 - p['m2']*s)*z0, n
    return z0, n

def forces(W, s, soil, effect='none', p=None, r=R, b=B):
    """Wong's W (Eq7), Dp (Eq8), T (Eq9) for load W (sets sinkage) and slip s."""
    z, n = sinkage(W, s, soil, effect, p, r, b)
    th1 = np.arccos(1 - z/r)
    keq = soil['kc']/b + soil['kphi']
    tphi = np.tan(soil['phi'])
    def sig(t):
        zz = r*(np.cos(t) - np.cos(th1))
        return keq*max(zz, 0.0)**n
    def tau(t):
        j = r*((th1 - t) - (1 - s)*(np.sin(th1) - np.sin(t)))
        return (soil['c'] + sig(t)*tphi)*(1 - np.exp(-j/soil['K']))
    Wm = r*b*(quad(lambda t: sig(t)*np.cos(t), 0, th1)[0] + quad(lambda t: tau(t)*np.sin(t), 0, th1)[0])
    Dp = r*b*(quad(lambda t: tau(t)*np.cos(t), 0, th1)[0] - quad(lambda t: sig(t)*np.sin(t), 0, th1)[0])
    T = r*r*b*quad(tau, 0, th1)[0]
    return Wm, Dp, T, z

if __name__ == '__main__':
    W = 13000.0
    for eff, p in [('none', None), ('vasilev', {'H': 0.05}), ('lyasko', {'m1': 0.6, 'm2': 0.03})]:
        print(eff, p)
        for s in [0.0, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 0.9]:
            Wm, Dp, T, z = forces(W, s, SAND, eff, p)
            print(f"  s={s:.2f} z={z*1000:6.1f}mm W_eq7={Wm:8.0f} Dp={Dp:8.0f} T={T:7.0f}")
    s2 = dict(SAND); s2['phi'] = np.radians(21)
    print('phi21'); [print(s, ["%.0f" % v for v in forces(W, s, s2)]) for s in [0.1, 0.5, 0.9]]
