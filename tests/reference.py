"""Independent truth for the tests: docs/method.md section 7's closed form of the planar system.

Nothing here uses freefloat: the formulas are typed from docs/method.md, and the yaw integral uses
SciPy's adaptive quadrature on the polynomials as printed there.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.integrate import quad

M0, M1, M2 = 400.0, 40.0, 30.0
I0, I1, I2 = 66.67, 3.33, 2.50
R0 = 0.5
L1 = R1 = 0.5
L2 = R2 = 0.5
M = M0 + M1 + M2

D1 = I0 + M0 * (M1 + M2) * R0**2 / M
D2 = D5 = M0 * R0 * ((M1 + M2) * L1 + M2 * R1) / M
D3 = D9 = M0 * R0 * M2 * L2 / M
D4 = I1 + (M0 * M1 * L1**2 + M1 * M2 * R1**2 + M0 * M2 * (L1 + R1) ** 2) / M
D6 = D8 = M2 * L2 * (M0 * (L1 + R1) + M1 * R1) / M
D7 = I2 + M2 * (M0 + M1) * L2**2 / M

A = R0 * M0 / M
B = (R1 * (M0 + M1) + L1 * M0) / M
C = L2 * (M0 + M1) / M + R2


def gains(q1: float, q2: float) -> tuple[float, float]:
    """g1, g2 with dyaw = g1 dq1 + g2 dq2."""
    d0 = D1 + D2 * math.cos(q1) + D3 * math.cos(q1 + q2)
    d1 = D4 + D5 * math.cos(q1) + D6 * math.cos(q2)
    d2 = D7 + D8 * math.cos(q2) + D9 * math.cos(q1 + q2)
    total = d0 + d1 + d2
    return -(d1 + d2) / total, -d2 / total


def end_effector(yaw: float, q1: float, q2: float) -> tuple[float, float]:
    """End-effector (x, y) in m, origin at the system CM."""
    t1, t2 = yaw + q1, yaw + q1 + q2
    return (
        A * math.cos(yaw) + B * math.cos(t1) + C * math.cos(t2),
        A * math.sin(yaw) + B * math.sin(t1) + C * math.sin(t2),
    )


def worked_example_coefficients(b26: float) -> tuple[np.ndarray, np.ndarray]:
    """q1, q2 coefficients (highest power of t first) as printed in docs/method.md section 8."""
    pi = math.pi
    q1 = np.array([-7 * pi / 150000, 7 * pi / 6000, -7 * pi / 900, 0.0, 0.0, 4 * pi / 9])
    q2 = np.array(
        [
            b26,
            (-1500000 * b26 + pi) / 50000,
            (600000 * b26 - pi) / 2000,
            (-300000 * b26 + pi) / 300,
            0.0,
            0.0,
            pi / 6,
        ]
    )
    return q1, q2


def yaw_change(c1: np.ndarray, c2: np.ndarray, duration: float) -> float:
    """Yaw change (rad) along polynomial joint paths (highest power first), adaptive quadrature."""
    p1, p2 = np.poly1d(c1), np.poly1d(c2)
    v1, v2 = p1.deriv(), p2.deriv()

    def rate(t: float) -> float:
        g1, g2 = gains(p1(t), p2(t))
        return g1 * v1(t) + g2 * v2(t)

    return quad(rate, 0.0, duration, epsabs=1e-13, epsrel=1e-13, limit=500)[0]


def central_jacobian(fun, x: np.ndarray, eps: float) -> np.ndarray:
    """Central finite differences of ``fun`` at ``x``; columns are the derivatives (last axis)."""
    x = np.asarray(x, dtype=float)
    columns = [(fun(x + eps * e) - fun(x - eps * e)) / (2 * eps) for e in np.eye(x.shape[-1])]
    return np.stack(columns, axis=-1)


def planar_gains(
    q1: float,
    q2: float,
    masses: tuple[float, float, float] = (M0, M1, M2),
    inertias: tuple[float, float, float] = (I0, I1, I2),
    lengths: tuple[float, float, float, float, float] = (R0, L1, R1, L2, R2),
) -> tuple[float, float]:
    """g1, g2 of docs/method.md section 7 for any masses (kg), inertias (kg m^2), lengths (m).

    ``lengths`` are r0 (base CM to joint 1), l1 (joint 1 to body 1's CM), r1 (body 1's CM to
    joint 2), l2 (joint 2 to body 2's CM), r2 (body 2's CM to the tip).
    """
    m0, m1, m2 = masses
    i0, i1, i2 = inertias
    r0, l1, r1, l2, _ = lengths
    m = m0 + m1 + m2
    d1 = i0 + m0 * (m1 + m2) * r0**2 / m
    d2 = m0 * r0 * ((m1 + m2) * l1 + m2 * r1) / m
    d3 = m0 * r0 * m2 * l2 / m
    d4 = i1 + (m0 * m1 * l1**2 + m1 * m2 * r1**2 + m0 * m2 * (l1 + r1) ** 2) / m
    d6 = m2 * l2 * (m0 * (l1 + r1) + m1 * r1) / m
    d7 = i2 + m2 * (m0 + m1) * l2**2 / m
    c0 = d1 + d2 * math.cos(q1) + d3 * math.cos(q1 + q2)
    c1 = d4 + d2 * math.cos(q1) + d6 * math.cos(q2)
    c2 = d7 + d6 * math.cos(q2) + d3 * math.cos(q1 + q2)
    total = c0 + c1 + c2
    return -(c1 + c2) / total, -c2 / total


def _gain_arrays(q1: np.ndarray, q2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`gains` on arrays (the same formulas, vectorised)."""
    d0 = D1 + D2 * np.cos(q1) + D3 * np.cos(q1 + q2)
    d1 = D4 + D5 * np.cos(q1) + D6 * np.cos(q2)
    d2 = D7 + D8 * np.cos(q2) + D9 * np.cos(q1 + q2)
    total = d0 + d1 + d2
    return -(d1 + d2) / total, -d2 / total


def yaw_change_bounds_deg(
    delta_q1: float, delta_q2: float, points: int = 361
) -> tuple[float, float]:
    """The reachable yaw-change interval (deg) of the worked example's arm, independently.

    docs/method.md section 6: ``g_i,min dq_i .. g_i,max dq_i`` summed. The extremes of the
    closed-form gains come from a dense grid over both continuous joints, each refined by
    Nelder-Mead on the closed form (SciPy; no freefloat code).
    """
    from scipy.optimize import minimize

    grid = np.linspace(-math.pi, math.pi, points)
    a, b = np.meshgrid(grid, grid, indexing="ij")
    values = _gain_arrays(a, b)
    extremes = []
    for i in range(2):
        pair = []
        for sign in (1.0, -1.0):  # minimum, then maximum
            k = np.unravel_index(int(np.argmin(sign * values[i])), a.shape)
            found = minimize(
                lambda x, i=i, sign=sign: sign * gains(x[0], x[1])[i],
                np.array([a[k], b[k]]),
                method="Nelder-Mead",
                options={"xatol": 1e-12, "fatol": 1e-15, "maxiter": 4000},
            )
            pair.append(sign * float(found.fun))
        extremes.append(pair)
    lo = hi = 0.0
    for (g_min, g_max), dq in zip(extremes, (delta_q1, delta_q2), strict=True):
        lo += min(g_min * dq, g_max * dq)
        hi += max(g_min * dq, g_max * dq)
    return math.degrees(lo), math.degrees(hi)


@functools.cache
def worked_bounds_deg() -> tuple[float, float]:
    """The worked example's interval (deg): start q = (80, 30) deg, goal (-60, 90) deg.

    The paper prints 1.4 and 72.2 deg.
    """
    return yaw_change_bounds_deg(math.radians(-140.0), math.radians(60.0))


def worked_bounds_text() -> str:
    """:func:`worked_bounds_deg` as freefloat prints an interval: ``(lo, hi)`` to 3 decimals."""
    lo, hi = worked_bounds_deg()
    return f"({lo:.3f}, {hi:.3f})"
