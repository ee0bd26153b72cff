#!/usr/bin/env python3
"""Independent check of an approximation study's Gram condition numbers and power-function sups.

Runs `rkhs-study run STUDY --out DIR`, then recomputes every trial of the study with NumPy from
the formulas of the model (docs/model.md, sections 3-5), written independently of the C++
code: B-splines by the Cox-de Boor recursion and an explicit sum over levels and wrapped
indices, the periodised Gaussian by its Fourier series, eigenvalues by LAPACK's eigh. Values
that double precision cannot resolve are not compared, and the script says so: condition
numbers above 1e8 (the smallest eigenvalue then carries a relative error above 1e-8) and
power-function sups within a factor 1000 of their round-off floor.

Usage: gram_and_power_reference.py RKHS_STUDY_EXECUTABLE STUDY.toml OUT_DIR
Exit status 0 when every compared value agrees to 1e-6 relative.
"""
import csv
import math
import subprocess
import sys
import tomllib

import numpy as np

TOLERANCE = 1e-6


def cardinal_bspline(p, x):
    """N_p(x) with knots 0..p+1 by the Cox-de Boor recursion (vectorised)."""
    x = np.asarray(x, dtype=float)
    if p == 0:
        return ((x >= 0) & (x < 1)).astype(float)
    return (x * cardinal_bspline(p - 1, x) + (p + 1 - x) * cardinal_bspline(p - 1, x - 1)) / p


def bspline_features(s, L, p, r, n0, J):
    """Columns: every (level j, index k) of the periodic multiscale kernel, weight included."""
    h0 = L / n0
    blocks = []
    for j in range(J + 1):
        nj = n0 * 2 ** j
        x = (2 ** j) * np.asarray(s)[:, None] / h0
        k = np.arange(nj)[None, :]
        blocks.append(2 ** (j * (1 - 2 * r) / 2) * cardinal_bspline(p, np.mod(x - k, nj)))
    return np.hstack(blocks)


def gaussian_fourier(d, L, sigma, convention):
    """Periodised Gaussian by its Fourier series (Poisson summation)."""
    s = sigma if convention == "2sigma2" else sigma / math.sqrt(2)
    K = 1
    while math.exp(-2 * math.pi ** 2 * s ** 2 * K ** 2 / L ** 2) > 1e-18:
        K += 1
    k = np.arange(1, K + 1)
    weights = np.exp(-2 * math.pi ** 2 * s ** 2 * k ** 2 / L ** 2)
    d = np.asarray(d)
    return s * math.sqrt(2 * math.pi) / L * (1 + 2 * np.tensordot(np.cos(2 * math.pi * d[..., None] * k / L), weights, axes=1))


def kernel_matrices(row, L, points, centres):
    name = row["kernel"]
    if name == "bspline":
        p, r, n0, J = int(row["degree"]), float(row["r"]), int(row["n0"]), int(row["J"])
        phi_c = bspline_features(centres, L, p, r, n0, J)
        phi_x = bspline_features(points, L, p, r, n0, J)
        return phi_c @ phi_c.T, phi_x @ phi_c.T, np.sum(phi_x ** 2, axis=1)
    if name == "gaussian":
        sigma, convention = float(row["sigma"]), row["convention"]
        gram = gaussian_fourier(centres[:, None] - centres[None, :], L, sigma, convention)
        cross = gaussian_fourier(points[:, None] - centres[None, :], L, sigma, convention)
        return gram, cross, gaussian_fourier(np.zeros(len(points)), L, sigma, convention)
    raise SystemExit(f"no reference implementation for kernel '{name}'")


def main():
    executable, study_file, out_dir = sys.argv[1:4]
    subprocess.run([executable, "run", study_file, "--out", out_dir, "--quiet"], check=True)
    with open(study_file, "rb") as f:
        study = tomllib.load(f)
    domain = study["domain"]
    L = domain["length"] if "length" in domain else 2 * math.pi * domain["radius"]
    if not domain.get("periodic", True):
        raise SystemExit("the reference handles periodic domains only")
    M = study["study"].get("evaluation_points", 4096)
    points = L * np.arange(M) / M

    compared = skipped = failures = 0
    with open(f"{out_dir}/trials.csv", newline="") as f:
        for row in csv.DictReader(f):
            if row["centres"] != "uniform" or float(row["centres_offset"]) != 0:
                raise SystemExit("the reference handles uniform centres only")
            n = int(row["n"])
            centres = L * np.arange(n) / n
            gram, cross, diagonal = kernel_matrices(row, L, points, centres)
            eigenvalues = np.linalg.eigvalsh(gram)
            threshold = n * np.finfo(float).eps * eigenvalues[-1]  # docs/model.md section 5
            condition = eigenvalues[-1] / eigenvalues[0] if eigenvalues[0] > threshold else math.inf
            label = f"{row['kernel']} {row.get('degree') or row.get('sigma')} n={n}"
            if eigenvalues[0] < 0.1 * threshold:
                # Clearly singular: the tool must say so (inf and the gram_singular flag).
                compared += 1
                if row["gram_condition_number"] != "inf" or "gram_singular" not in row["flags"]:
                    failures += 1
                    print(f"MISMATCH {label}: reference singular, tool reports "
                          f"{row['gram_condition_number']!r} with flags {row['flags']!r}")
            elif condition < 1e8:
                ours = float(row["gram_condition_number"])
                compared += 1
                if abs(ours - condition) > TOLERANCE * condition:
                    failures += 1
                    print(f"MISMATCH {label} gram_condition_number: {ours!r} vs reference {condition!r}")
            else:
                skipped += 1
            ours_power = float(row["power_function_sup"])
            floor = float(row["power_function_floor"])
            if condition < 1e12 and ours_power > 1000 * floor:
                solution = np.linalg.solve(gram, cross.T)
                power = math.sqrt(max(0.0, np.max(diagonal - np.sum(cross.T * solution, axis=0))))
                compared += 1
                if abs(ours_power - power) > TOLERANCE * power:
                    failures += 1
                    print(f"MISMATCH {label} power_function_sup: {ours_power!r} vs reference {power!r}")
            else:
                skipped += 1
    print(f"reference check: {compared} values compared to {TOLERANCE:g} relative, "
          f"{skipped} not resolvable in double precision skipped, {failures} mismatches")
    sys.exit(1 if failures or compared == 0 else 0)


if __name__ == "__main__":
    main()
