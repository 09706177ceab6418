#!/usr/bin/env python3
"""Writes shaders/bsdf/sheen_albedo.wgsl: a fit of the directional albedo E(cos_view, sheenRoughness) of the
KHR_materials_sheen BRDF (sheen colour 1), which its albedo scaling dims the base with. Standard library only.

E(mu) = integral over the hemisphere of D(h) V(v, l) cos(l) dl, with the extension's "Charlie" distribution
D = (2 + 1/alpha) sin(theta_h)^(1/alpha) / (2 pi) and the Charlie visibility
V = 1 / ((1 + Lambda(n.v) + Lambda(n.l)) 4 n.v n.l) (Estevez & Kulla 2017, the fit the extension quotes),
alpha = max(sheenRoughness^2, SHEEN_MIN_ALPHA). Integrated by the midpoint rule over (cos(theta_l), phi): in
those variables dl = d(cos) d(phi), and D V cos(l) = D / ((1 + Lambda_v + Lambda_l) 4 n.v) has no 1 / n.l left.

The shader gets a polynomial fit, not a table: a table is a constant array, which WGSL compilers copy to
private memory at every dynamic index (a lavapipe kernel with a 512-entry table took over 5 minutes to build).
ln(E + EPS) is fitted by weighted least squares (weights (E + EPS)^2, so the error is about absolute in E) as a
polynomial of degree COS_DEGREE in x = 2 cos_view - 1 and ROUGHNESS_DEGREE in y, ln(roughness) mapped from
[ln 0.1, 0] to [-1, 1], on a grid of cos_view in (0, 1] and roughness in [0.1, 1] (below 0.1 alpha is clamped, so
E is constant there). Run from the repository root:  python3 scripts/sheen_albedo_table.py
"""

import math
import os

COS_NODES = 48
ROUGHNESS_NODES = 19
COS_DEGREE = 8
ROUGHNESS_DEGREE = 5
EPS = 0.003
# The smallest alpha the renderer uses: sheenRoughness 0 would put the whole lobe on the horizon.
SHEEN_MIN_ALPHA = 0.01
SHEEN_MIN_ROUGHNESS = 0.1
OUT = os.path.join("shaders", "bsdf", "sheen_albedo.wgsl")


def fit_l(x, alpha):
    t = (1.0 - alpha) ** 2
    a = 21.5473 + (25.3245 - 21.5473) * t
    b = 3.82987 + (3.32435 - 3.82987) * t
    c = 0.19823 + (0.16801 - 0.19823) * t
    d = -1.97760 + (-1.27393 + 1.97760) * t
    e = -4.32054 + (-4.85967 + 4.32054) * t
    return a / (1.0 + b * x**c) + d * x + e


def sheen_lambda(cos_theta, alpha):
    c = abs(cos_theta)
    if c < 0.5:
        return math.exp(fit_l(c, alpha))
    return math.exp(2.0 * fit_l(0.5, alpha) - fit_l(1.0 - c, alpha))


def albedo(mu, roughness, n_cos=256, n_phi=128):
    alpha = max(roughness * roughness, SHEEN_MIN_ALPHA)
    norm = (2.0 + 1.0 / alpha) / (2.0 * math.pi)
    v = (math.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu)
    lambda_v = sheen_lambda(mu, alpha)
    cos_phi = [math.cos(math.pi * (j + 0.5) / n_phi) for j in range(n_phi)]
    total = 0.0
    for i in range(n_cos):
        cl = (i + 0.5) / n_cos
        sl = math.sqrt(1.0 - cl * cl)
        denom = (1.0 + lambda_v + sheen_lambda(cl, alpha)) * 4.0 * mu
        row = 0.0
        for cp in cos_phi:
            # h = normalize(v + l); phi over [0, pi] (the integrand is even in phi).
            hx, hz = v[0] + sl * cp, v[2] + cl
            hy2 = (sl * sl) * (1.0 - cp * cp)
            len2 = hx * hx + hy2 + hz * hz
            sin2h = max(0.0, 1.0 - hz * hz / len2)
            row += norm * sin2h ** (0.5 / alpha)
        total += row / denom
    # d(cos) = 1 / n_cos, d(phi) = pi / n_phi, twice for phi in [pi, 2 pi].
    return total * 2.0 * math.pi / (n_cos * n_phi)


def fit_x(mu):
    return 2.0 * mu - 1.0


def fit_y(roughness):
    return 2.0 * math.log(roughness) / -math.log(SHEEN_MIN_ROUGHNESS) + 1.0


def solve(a, b):
    """Gauss-Jordan elimination with partial pivoting."""
    n = len(a)
    m = [row[:] + [bb] for row, bb in zip(a, b)]
    for c in range(n):
        p = max(range(c, n), key=lambda k: abs(m[k][c]))
        m[c], m[p] = m[p], m[c]
        for k in range(n):
            if k != c:
                f = m[k][c] / m[c][c]
                for q in range(c, n + 1):
                    m[k][q] -= f * m[c][q]
    return [m[k][n] / m[k][k] for k in range(n)]


def basis(mu, roughness):
    x, y = fit_x(mu), fit_y(roughness)
    return [x**i * y**j for j in range(ROUGHNESS_DEGREE + 1) for i in range(COS_DEGREE + 1)]


def main():
    points = []
    for j in range(ROUGHNESS_NODES):
        r = SHEEN_MIN_ROUGHNESS + (1.0 - SHEEN_MIN_ROUGHNESS) * j / (ROUGHNESS_NODES - 1)
        for i in range(COS_NODES):
            mu = (i + 0.5) / COS_NODES
            points.append((mu, r, albedo(mu, r)))
    rows = [basis(mu, r) for mu, r, _ in points]
    weights = [(e + EPS) ** 2 for _, _, e in points]
    targets = [math.log(e + EPS) for _, _, e in points]
    n = len(rows[0])
    normal = [[sum(w * row[a] * row[b] for row, w in zip(rows, weights)) for b in range(n)] for a in range(n)]
    rhs = [sum(w * row[a] * t for row, w, t in zip(rows, weights, targets)) for a in range(n)]
    c = solve(normal, rhs)

    def fitted(mu, r):
        return math.exp(sum(ci * bi for ci, bi in zip(c, basis(mu, r)))) - EPS

    worst = max((abs(fitted(mu, r) - e), mu, r) for mu, r, e in points if mu >= 0.05)
    per_y = []
    for j in range(ROUGHNESS_DEGREE + 1):
        coefficients = c[j * (COS_DEGREE + 1) : (j + 1) * (COS_DEGREE + 1)]
        horner = f"{coefficients[-1]:.9g}"
        for k in reversed(coefficients[:-1]):
            horner = f"({horner}) * x + {k:.9g}"
        per_y.append(f"    let c{j} = {horner};")
    in_y = f"c{ROUGHNESS_DEGREE}"
    for j in reversed(range(ROUGHNESS_DEGREE)):
        in_y = f"({in_y}) * y + c{j}"
    lines = [
        "// Generated by scripts/sheen_albedo_table.py: do not edit. A fit of the directional albedo E(cos_view,",
        "// sheenRoughness) of the KHR_materials_sheen BRDF (Charlie distribution and visibility, sheen colour 1):",
        f"// ln(E + {EPS}) as a polynomial in x = 2 cos_view - 1 (degree {COS_DEGREE}) and y = ln(roughness) mapped from",
        f"// [ln {SHEEN_MIN_ROUGHNESS}, 0] to [-1, 1] (degree {ROUGHNESS_DEGREE}); alpha = max(roughness^2, {SHEEN_MIN_ALPHA}).",
        f"// Largest error on the fitting grid (cos_view >= 0.05): {worst[0]:.4f} at cos_view {worst[1]:.3f}, roughness {worst[2]:.3f}.",
        "",
        f"const SHEEN_MIN_ALPHA: f32 = {SHEEN_MIN_ALPHA};",
        f"const SHEEN_ALBEDO_MIN_ROUGHNESS: f32 = {SHEEN_MIN_ROUGHNESS};",
        "",
        "fn sheen_albedo_fit(x: f32, y: f32) -> f32 {",
        *per_y,
        f"    return exp({in_y}) - {EPS};",
        "}",
    ]
    with open(OUT, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"wrote {OUT}; largest error {worst[0]:.4f} at cos_view {worst[1]:.3f}, roughness {worst[2]:.3f}")


if __name__ == "__main__":
    main()
