#!/usr/bin/env python3
"""How far the lambda_min bound on the round-off floors is from the floors themselves.

The power function's and the errors' floors of an approximation trial (docs/metrics.md) are
    power_function_floor = sqrt(n eps lambda_max max_m |G^-1 k_X(s_m)|^2)
    error_floor          = n eps lambda_max max_m |G^-1 k_X(s_m)| |alpha|
and |G^-1 k_X(s)|^2 = |L^-T y|^2 with y = L^-1 k_X(s) is the second triangular solve per point.
Its cheap bound |G^-1 k|^2 <= |y|^2 / lambda_min (|y|^2 comes from the first solve) could replace
the second solve wherever it decides a flag. This prints, for the 2-D Matern trial of
matern_2d_peer.toml (Matern 5/2, l = 0.2, m x m grid centres, p x p grid points on the unit
square): the spread of |G^-1 k(s_m)|^2 over the points, the bound, and which flags the bound
decides (docs/performance.md, "The round-off floors").

Measuring only (NumPy and SciPy, provided as in README.md of this folder):
    /usr/bin/python3 floor_bound_probe.py [--m 64] [--p 128]
"""
import argparse

import numpy as np
import scipy.linalg as sl


def matern52(a_points, b_points, length_scale=0.2):
    distance = np.sqrt(((a_points[:, None, :] - b_points[None, :, :]) ** 2).sum(-1))
    a = np.sqrt(5.0) * distance / length_scale
    return (1.0 + a + a * a / 3.0) * np.exp(-a)


def grid(m):
    axis = np.linspace(0.0, 1.0, m)
    return np.array([(x1, x2) for x2 in axis for x1 in axis])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--m", type=int, default=64, help="centres per axis (n = m^2)")
    parser.add_argument("--p", type=int, default=128, help="evaluation points per axis")
    args = parser.parse_args()
    centres, points = grid(args.m), grid(args.p)
    n, eps = len(centres), np.finfo(float).eps
    gram = matern52(centres, centres)
    lower = np.linalg.cholesky(gram)
    cross = matern52(points, centres)
    y = sl.solve_triangular(lower, cross.T, lower=True)
    quadratic = (y * y).sum(0)
    cardinal = sl.solve_triangular(lower.T, y, lower=False)
    cardinal_squared = (cardinal * cardinal).sum(0)
    eigenvalues = np.linalg.eigvalsh(gram)
    lambda_min, lambda_max = eigenvalues[0], eigenvalues[-1]
    target = lambda x: np.exp(x[:, 0]) * np.cos(x[:, 1]) + x[:, 0] * x[:, 1]
    alpha = sl.cho_solve((lower, True), target(centres))
    residual = target(points) - cross @ alpha
    weights = np.outer(*(2 * [np.full(args.p, 1.0 / (args.p - 1))]))
    weights[[0, -1], :] /= 2
    weights[:, [0, -1]] /= 2
    l2 = np.sqrt((weights.ravel() * residual**2).sum())
    round_off = n * eps * lambda_max
    bound_squared = (quadratic / lambda_min).max()
    power_sup = np.sqrt(max(0.0, (1.0 - quadratic).max()))
    print(f"n = {n}, M = {len(points)}: lambda_min {lambda_min:.3e}, lambda_max {lambda_max:.4g}")
    print(f"|G^-1 k(s_m)|^2: min {cardinal_squared.min():.4f}, median "
          f"{np.median(cardinal_squared):.4f}, max {cardinal_squared.max():.4f}; points within "
          f"10 % of the max: {(cardinal_squared > 0.9 * cardinal_squared.max()).mean():.0%}")
    print(f"bound max_m |y_m|^2 / lambda_min: {bound_squared:.4g} "
          f"({bound_squared / cardinal_squared.max():.3g} times the max)")
    for name, value, floor, bound in (
            ("power_function_sup", power_sup, np.sqrt(round_off * cardinal_squared.max()),
             np.sqrt(round_off * bound_squared)),
            ("sup_error", np.abs(residual).max(),
             round_off * np.sqrt(cardinal_squared.max()) * np.linalg.norm(alpha),
             round_off * np.sqrt(bound_squared) * np.linalg.norm(alpha)),
            ("l2_error", l2, round_off * np.sqrt(cardinal_squared.max()) * np.linalg.norm(alpha),
             round_off * np.sqrt(bound_squared) * np.linalg.norm(alpha))):
        decided = "decides the flag (not at floor)" if value > bound else "does not decide the flag"
        print(f"{name} {value:.4e}: floor {floor:.4e}, bound {bound:.4e}: the bound {decided}")


if __name__ == "__main__":
    main()
