#!/usr/bin/env python3
"""Separate numpy/scipy implementation of the full-car ride model at the truth
parameters: prints the static equilibrium and the channels at t = 0.3, 1.5 and
3 s of the bump that test_model_full_car.cpp compares against. Run by hand
(needs python3-scipy, which the build does not)."""
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

ms, Ixx, Iyy, a, b, w = 1200.0, 400.0, 1600.0, 1.1, 1.5, 1.5
mu = np.array([40.0, 40.0, 35.0, 35.0])
k = np.array([20000.0, 20000.0, 22000.0, 22000.0])
k3 = np.full(4, 1e5)
c = np.array([1500.0, 1500.0, 1400.0, 1400.0])
kt, g = 2e5, 9.81
M = 200 * (1 + 0.5 * 0.2326)
xM = 1.3 * (1 + 0.4 * -0.3875) - b
yM = 0.75 * (1 + 0.25 * 0.3) - w / 2
X = np.array([a, a, -b, -b])
Y = np.array([w / 2, -w / 2, w / 2, -w / 2])


def spring(d):
    return k * d + k3 * d**3


def residuals(v):
    z, th, ph, zu = v[0], v[1], v[2], v[3:]
    F = spring(zu - (z + X * th + Y * ph))
    body = [F.sum() - g * (ms + M), (F * X).sum() - g * M * xM, (F * Y).sum() - g * M * yM]
    return np.concatenate([body, F + mu * g + kt * zu])


eq = fsolve(residuals, np.array([-0.17, 0, 0, -0.02, -0.02, -0.02, -0.02]), xtol=1e-15)
delta = eq[3:] - (eq[0] + X * eq[1] + Y * eq[2])
Mb = np.array([[ms + M, M * xM, M * yM],
               [M * xM, Iyy + M * xM**2, M * xM * yM],
               [M * yM, M * xM * yM, Ixx + M * yM**2]])
Mi = np.linalg.inv(Mb)
V = 16 / 3.6
OFFSETS = (0.0, 0.6, 2.6, 3.2)
HEIGHTS = np.array([0.10, 0.08, 0.10, 0.08])


def bump(s):
    return 0.0 if s <= 0 or s >= 3 else s if s < 1 else 1.0 if s <= 2 else 3 - s


def rhs(t, y):
    q, zu, qd, zud = y[:3], y[3:7], y[7:10], y[10:]
    u = q[0] + X * q[1] + Y * q[2] - zu
    v = qd[0] + X * qd[1] + Y * qd[2] - zud
    f = -(spring(delta) - spring(delta - u)) - c * 1.0 * np.tanh(1.0 * v)
    road = HEIGHTS * np.array([bump(V * t - o) for o in OFFSETS])
    return np.concatenate([qd, zud, Mi @ [f.sum(), (f * X).sum(), (f * Y).sum()],
                           (-f + kt * (road - zu)) / mu])


samples = [0.3 * j for j in range(1, 11)]
stops = sorted(set([(o + s) / V for o in OFFSETS for s in (0, 1, 2, 3)] + samples))
y, t0, channels = np.zeros(14), 0.0, []
for t1 in [t for t in stops if 0 < t <= 3.0 + 1e-12]:
    y = solve_ivp(rhs, (t0, t1), y, method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]
    t0 = t1
    if any(abs(t1 - s) < 1e-12 for s in samples):
        q, zu, qd, zud = y[:3], y[3:7], y[7:10], y[10:]
        channels.append(np.concatenate([q[0] + X * q[1] + Y * q[2] - zu,
                                        qd[0] + X * qd[1] + Y * qd[2] - zud]))
print("equilibrium", repr(list(eq)), "max |residual|", np.abs(residuals(eq)).max())
channels = np.array(channels)
print("max |channel|", np.abs(channels).max(axis=0))
for j in (0, 4, 9):
    print("t = %.1f:" % samples[j], repr(list(channels[j])))
