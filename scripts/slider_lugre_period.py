#!/usr/bin/env python3
# The slider study's eleventh-session check (docs/findings.md, "the slider's CPU and the
# pre-sliding stiffness"): LuGre friction on one mass and one spring at 4300 um/s,
# P/T0 against the bristle stiffness sigma0 (args, N/m). MUS=0.45 raises mu_s.
# python3 scripts/slider_lugre_period.py 100 1000 10000 300000
# LuGre (Canudas de Wit et al. 1995) pre-sliding stiffness sigma0 in parallel with the
# spring while the bristles are pinned: does one sigma0 shorten the inertial period
# at both springs at 4300 um/s? m x'' = k (V t - x) - F, F = sigma0 z + sigma1 z',
# z' = v - sigma0 |v| z / g(v), g = N (mu_k + (mu_s - mu_k) exp(-(v/vs)^2)).
import numpy as np, sys
m, g0 = 0.0307, 9.81; N = m*g0
def run(k, V, sigma0, mu_s=float(__import__("os").environ.get("MUS","0.37")), mu_k=0.35, vs=1e-3, sigma1_frac=0.0, T=None):
    T0 = 2*np.pi*np.sqrt(m/k)
    T = T or 40*T0
    rate = max(sigma0*max(V,1e-3)*10/(mu_k*N), 2*np.pi/T0*200)
    dt = min(T0/2000, 0.2/rate)
    n = int(T/dt)
    x = -mu_k*N/k; v = 0.0; z = 0.0  # spring preloaded at the kinetic level, slider at rest
    z = mu_k*N/sigma0
    sig1 = sigma1_frac*2*np.sqrt(sigma0*m)
    F_rec = np.empty(n//10+1); j=0
    for i in range(n):
        t = i*dt
        gv = N*(mu_k + (mu_s-mu_k)*np.exp(-(v/vs)**2))
        zd = v - sigma0*abs(v)*z/gv
        Ff = sigma0*z + sig1*zd
        a = (k*(V*t - x) - Ff)/m
        v += dt*a; x += dt*v; z += dt*zd
        if i % 10 == 0: F_rec[j] = k*(V*t-x)/N; j+=1
    F = F_rec[:j]; tt = np.arange(j)*10*dt
    F = F[tt > T/2]; tt = tt[tt > T/2]
    # period: mean spacing of upward mean crossings
    c = F - F.mean(); up = np.where((c[:-1] < 0) & (c[1:] >= 0))[0]
    if len(up) < 3 or F.std() < 1e-4: return T0, np.nan, F.std()
    P = np.mean(np.diff(tt[up]))
    return T0, P, F.std()
for k in (168.0, 2254.0):
    for s0 in [float(a) for a in sys.argv[1:]]:
        T0, P, sd = run(k, 4300e-6, s0)
        print(f"k={k:6.0f} sigma0={s0:9.0f} N/m  T0={T0:.4f}  P={P:.4f}  P/T0={P/T0:.3f}  force sd={sd:.4f}", flush=True)
