"""Beam theory for the cantilever (cantilever.py): the reference tip of a cantilever of square
section under its own weight, at a small and at a large load.

The beam is scenes/cantilever.yaml's: length L = 0.5 m, square section of side h = 5 cm (E 1e7 Pa,
ν 0.3, ρ 1000 kg/m³), clamped at s = 0, under gravity scaled per load case (LOADS). The line load is
q = ρ g A, A = h², I = h⁴/12, G = E / (2 (1 + ν)).

(a) Small load, g = 0.981 m/s² (δ/L ≈ 0.7 %): linear beam theory with the shear term,
        δ = q L⁴ / (8 E I)  +  q L² / (2 κ G A)
    the first term Euler–Bernoulli's (Timoshenko & Gere, Mechanics of Materials, table of beam
    deflections: cantilever under a uniform load), the second Timoshenko's shear deflection
    (Timoshenko, Strength of Materials, Part I, "effect of shearing force on the deflection of
    beams"), with the shear coefficient κ = 5/6 of a rectangular section (Cowper, J. Appl. Mech.
    1966, would give 10 (1 + ν) / (12 + 11 ν) = 0.85; the difference is 0.02 % of δ). The shear
    term is 1.0 % of δ here.
(b) Large load, g = 5 × 9.81 m/s² (δ/L ≈ 34 %): the elastica of a cantilever under its own weight
    as a dead load (Rohde, "Large deflections of a cantilever beam with uniformly distributed
    load", Q. Appl. Math. 11, 1953; Frisch-Fay, Flexible Bars, 1962). With s the arclength from
    the clamp and θ(s) the slope, measured downwards, the part of the beam beyond s weighs
    q (L − s) and its moment about the section at s is
    M(s) = q ∫_s^L (x(ξ) − x(s)) dξ; the curvature is θ' = M / (E I), and differentiating with
    x' = cos θ:
        E I θ''(s) = −q (L − s) cos θ(s),   θ(0) = 0 (clamped),   θ'(L) = 0 (free end, no moment),
        x_tip = ∫_0^L cos θ ds,   z_tip = −∫_0^L sin θ ds.
    Solved by shooting on θ'(0) (RK4, 4,000 steps; Illinois regula falsi on θ'(L) = 0, bracketed by
    θ'(0) ∈ [0, q L² / (2 E I)], the linear value, which the shortened lever arm can only reduce).
    So that (a) and (b) are measured against one beam theory, the reference of (b) carries the same
    Timoshenko shear and the (negligible) axial stretch (Reissner's geometrically exact beam,
    ZAMP 23, 1972): with the section force n = (0, −q (L − s)), N = n·t = q (L − s) sin θ,
    V = n·ν = −q (L − s) cos θ (t = (cos θ, −sin θ), ν = (sin θ, cos θ)), ε = N / (E A),
    γ = V / (κ G A):
        x' = (1 + ε) cos θ + γ sin θ,   z' = −(1 + ε) sin θ + γ cos θ,
        E I θ'' = −(1 + ε) q (L − s) cos θ − γ q (L − s) sin θ;
    the plain inextensible elastica (ε = γ = 0) is reported beside it.

Checked by references() before any run (BenchError otherwise): at a small load the elastica gives
Euler–Bernoulli's q L⁴ / (8 E I) and the shear version adds Timoshenko's term (each within 0.1 %),
and at the large load the shooting agrees with a second, independent solution (Picard iteration on
the moment integral above, trapezoid rule) within 0.05 %.
"""
import math

import numpy as np

from common import BenchError

L_M, H_M = 0.5, 0.05                       # beam length, side of the square section
E_PA, NU, RHO = 1.0e7, 0.3, 1000.0
KAPPA = 5.0 / 6.0                          # Timoshenko shear coefficient (rectangle)
A_M2, I_M4 = H_M * H_M, H_M ** 4 / 12.0
G_PA = E_PA / (2.0 * (1.0 + NU))
G0 = 9.81
LOADS = {"small": {"g": 0.1 * G0, "title": "small load (g/10, δ/L ≈ 0.7 %)"},
         "large": {"g": 5.0 * G0, "title": "large load (5 g, δ/L ≈ 34 %)"}}


def euler_bernoulli_m(q):
    return q * L_M ** 4 / (8.0 * E_PA * I_M4)


def timoshenko_shear_m(q):
    return q * L_M ** 2 / (2.0 * KAPPA * G_PA * A_M2)


def _shoot(kappa0, q, shear, steps):
    """RK4 from the clamp with θ(0) = 0, θ'(0) = kappa0; returns (θ, θ', x, z) at s = L."""
    w = q / (E_PA * I_M4)
    c_shear = E_PA * I_M4 / (KAPPA * G_PA * A_M2) if shear else 0.0   # γ = −c_shear w (L−s) cos θ
    c_stretch = I_M4 / A_M2 if shear else 0.0                          # ε = c_stretch w (L−s) sin θ

    def f(s, th, k):
        c, sn = math.cos(th), math.sin(th)
        load = w * (L_M - s)
        eps = c_stretch * load * sn
        gam = -c_shear * load * c
        return (k, -(1.0 + eps) * load * c - gam * load * sn,
                (1.0 + eps) * c + gam * sn, -(1.0 + eps) * sn + gam * c)

    h = L_M / steps
    th, k, x, z = 0.0, kappa0, 0.0, 0.0
    for i in range(steps):
        s = i * h
        a = f(s, th, k)
        b = f(s + 0.5 * h, th + 0.5 * h * a[0], k + 0.5 * h * a[1])
        c = f(s + 0.5 * h, th + 0.5 * h * b[0], k + 0.5 * h * b[1])
        d = f(s + h, th + h * c[0], k + h * c[1])
        th += h / 6.0 * (a[0] + 2.0 * b[0] + 2.0 * c[0] + d[0])
        k += h / 6.0 * (a[1] + 2.0 * b[1] + 2.0 * c[1] + d[1])
        x += h / 6.0 * (a[2] + 2.0 * b[2] + 2.0 * c[2] + d[2])
        z += h / 6.0 * (a[3] + 2.0 * b[3] + 2.0 * c[3] + d[3])
    return th, k, x, z


def elastica(q, shear=False, steps=4000):
    """Tip of the cantilever under the dead line load q: (axial u_x, vertical u_z, tip slope)."""
    scale = q * L_M * L_M / (2.0 * E_PA * I_M4)
    lo, hi = 0.0, scale * (1.0 + 1e-6)
    f_lo, f_hi = _shoot(lo, q, shear, steps)[1], _shoot(hi, q, shear, steps)[1]
    if not (f_lo < 0.0 < f_hi):
        raise BenchError(f"elastica: θ'(L) not bracketed ({f_lo:g}, {f_hi:g}) at q {q:g} N/m")
    for _ in range(200):                   # Illinois: regula falsi that halves the stale end
        mid = hi - f_hi * (hi - lo) / (f_hi - f_lo)
        th, k, x, z = _shoot(mid, q, shear, steps)
        if abs(k) < 1e-11 * scale or hi - lo < 1e-14 * scale:
            return x - L_M, z, th
        if k > 0.0:
            hi, f_hi = mid, k
            f_lo *= 0.5
        else:
            lo, f_lo = mid, k
            f_hi *= 0.5
    raise BenchError(f"elastica: shooting did not converge at q {q:g} N/m")


def elastica_picard(q, points=4001, iterations=2000):
    """The same elastica by fixed-point iteration on θ'(s) = M(s) / (E I), M from the current shape:
    an independent check of the shooting (no ODE, no root finding)."""
    s = np.linspace(0.0, L_M, points)

    def cumulative(f):
        return np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(s))])

    theta = np.zeros_like(s)
    for _ in range(iterations):
        x = cumulative(np.cos(theta))
        moment = q * (cumulative(x)[-1] - cumulative(x) - x * (L_M - s))
        new = cumulative(moment / (E_PA * I_M4))
        change = np.max(np.abs(new - theta))
        theta = 0.5 * theta + 0.5 * new
        if change < 1e-13:
            break
    return cumulative(np.cos(theta))[-1] - L_M, -cumulative(np.sin(theta))[-1]


def references():
    """Both load cases' reference tips, after checking the solver against the closed forms."""
    q_check = RHO * 0.01 * G0 * A_M2
    _, z_plain, _ = elastica(q_check)
    _, z_shear, _ = elastica(q_check, shear=True)
    for name, got, want in [("elastica", -z_plain, euler_bernoulli_m(q_check)),
                            ("elastica with shear", -z_shear,
                             euler_bernoulli_m(q_check) + timoshenko_shear_m(q_check))]:
        if abs(got / want - 1.0) > 1e-3:
            raise BenchError(f"{name} at a small load: tip {got:.6g} m, closed form {want:.6g} m")
    refs = {}
    for load, case in LOADS.items():
        q = RHO * case["g"] * A_M2
        x_plain, z_plain, th_plain = elastica(q)
        x_shear, z_shear, _ = elastica(q, shear=True)
        ref = {"g_m_s2": case["g"], "q_N_m": q,
               "euler_bernoulli_m": euler_bernoulli_m(q),
               "timoshenko_shear_m": timoshenko_shear_m(q),
               "elastica_m": [x_plain, z_plain], "elastica_tip_slope_deg": math.degrees(th_plain),
               "elastica_with_shear_m": [x_shear, z_shear]}
        if load == "small":
            ref["tip_m"] = [x_shear, -(euler_bernoulli_m(q) + timoshenko_shear_m(q))]
            ref["what"] = "Euler–Bernoulli + Timoshenko shear (vertical only)"
        else:
            x_picard, z_picard = elastica_picard(q)
            if math.hypot(x_picard - x_plain, z_picard - z_plain) > 5e-4 * abs(z_plain):
                raise BenchError(f"elastica: shooting ({x_plain:.6g}, {z_plain:.6g}) m and Picard "
                                 f"({x_picard:.6g}, {z_picard:.6g}) m disagree")
            ref["elastica_picard_m"] = [x_picard, z_picard]
            ref["tip_m"] = [x_shear, z_shear]
            ref["what"] = "elastica with Timoshenko shear (axial and vertical)"
        refs[load] = ref
    return refs
