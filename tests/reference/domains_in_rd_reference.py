#!/usr/bin/env python3
"""Independent check of an approximation study on a box in R^2 (studies/wendland_2d.toml).

Runs `rkhs-study run STUDY --out DIR`, then recomputes every trial with NumPy from the formulas
(docs/study-files.md, "Domains in R^d"; docs/metrics.md), written independently of the C++
code: the grid and Halton centres (radical inverses in bases 2 and 3), Wendland's phi_{3,k}
from its polynomial, f from the study's expression (NumPy's own functions), and

  separation_distance   half the smallest pairwise distance                 (1e-12 relative)
  fill_distance         bracketed: not below the largest distance from a fine grid (8 points
                        per centre spacing and axis) to the centres, and not above it by more
                        than that grid's half-diagonal (the tool's value is exact to 1e-9)
  gram_min_eigenvalue,  LAPACK's eigh, when the condition number is below 1e8  (1e-6 relative)
  gram_condition_number
  power_function_sup    sqrt(max(k(x,x) - k_X^T G^-1 k_X)) on the evaluation grid, when above
                        1000 times its round-off floor                        (1e-6 relative)
  l2_error              the tensor trapezoid rule of f - Pi f on that grid   (1e-6 relative)
                        (these two for n <= LARGEST_SOLVED)

Usage: domains_in_rd_reference.py RKHS_STUDY_EXECUTABLE STUDY.toml OUT_DIR
Exit status 0 when every compared value agrees.
"""
import csv
import math
import subprocess
import sys
import tomllib

import numpy as np

TOLERANCE = 1e-6
# The power function and the L2 error need G^-1 at every evaluation point, O(n^2 M); beyond this
# n the reference leaves them out (NumPy's reference LAPACK would take minutes), and compares
# the geometry and the eigenvalues only.
LARGEST_SOLVED = 576


def radical_inverse(i, base):
    value, scale = 0.0, 1.0 / base
    while i > 0:
        value += (i % base) * scale
        i //= base
        scale /= base
    return value


def centres_of(row, n, lengths):
    if row["centres"] == "halton":
        skip = int(row.get("centres_skip") or 0)
        return np.array([[radical_inverse(skip + p + 1, 2) * lengths[0],
                          radical_inverse(skip + p + 1, 3) * lengths[1]] for p in range(n)])
    if row["centres"] == "uniform":
        m = round(math.sqrt(n))
        if m * m != n:
            raise SystemExit(f"uniform centres need a square n, found {n}")
        axes = [np.linspace(0.0, length, m) for length in lengths]
        return np.array([[axes[0][i % m], axes[1][i // m]] for i in range(n)])
    raise SystemExit(f"no reference placement for centres '{row['centres']}'")


def wendland_3(k, r):
    """phi_{3,k}(r), Wendland's Table 9.1, normalised to phi(0) = 1; 0 for r >= 1."""
    s = np.clip(1.0 - r, 0.0, None)
    polynomial = {0: lambda: s ** 2,
                  1: lambda: s ** 4 * (4 * r + 1),
                  2: lambda: s ** 6 * (35 * r ** 2 + 18 * r + 3) / 3,
                  3: lambda: s ** 8 * (32 * r ** 3 + 25 * r ** 2 + 8 * r + 1)}[k]()
    return np.where(r < 1.0, polynomial, 0.0)


def kernel(row, x, y):
    if row["kernel"] != "wendland":
        raise SystemExit(f"no reference implementation for kernel '{row['kernel']}'")
    distance = np.sqrt(((x[:, None, :] - y[None, :, :]) ** 2).sum(axis=2))
    return wendland_3(int(row["k"]), distance / float(row["radius"]))


def expression(text, x1, x2):
    names = {"x1": x1, "x2": x2, "pi": math.pi, "exp": np.exp, "cos": np.cos, "sin": np.sin,
             "sqrt": np.sqrt, "abs": np.abs, "log": np.log, "tanh": np.tanh}
    return eval(text.replace("^", "**"), {"__builtins__": {}}, names)


def trapezoid_weights(m, length):
    w = np.full(m, length / (m - 1))
    w[0] = w[-1] = 0.5 * length / (m - 1)
    return w


def main():
    executable, study_file, out_dir = sys.argv[1:4]
    subprocess.run([executable, "run", study_file, "--out", out_dir, "--quiet"], check=True)
    with open(study_file, "rb") as f:
        study = tomllib.load(f)
    lengths = study["domain"]["lengths"]
    if len(lengths) != 2 or study["domain"].get("periodic", True):
        raise SystemExit("the reference handles boxes in R^2 only")
    M = study["study"]["evaluation_points"]
    m = round(math.sqrt(M))
    grid_axes = [np.linspace(0.0, length, m) for length in lengths]
    points = np.array([[grid_axes[0][i % m], grid_axes[1][i // m]] for i in range(m * m)])
    weights = np.outer(trapezoid_weights(m, lengths[1]), trapezoid_weights(m, lengths[0])).ravel()
    f_points = None
    fill_brackets = {}

    compared = skipped = failures = 0

    def compare(label, metric, ours, reference, tolerance=TOLERANCE):
        nonlocal compared, failures
        compared += 1
        if abs(ours - reference) > tolerance * abs(reference):
            failures += 1
            print(f"MISMATCH {label} {metric}: {ours!r} vs reference {reference!r}")

    with open(f"{out_dir}/trials.csv", newline="") as f:
        for row in csv.DictReader(f):
            n = int(row["n"])
            label = f"{row['kernel']} k={row['k']} {row['centres']} n={n}"
            if f_points is None:
                f_points = expression(row["target_f"], points[:, 0], points[:, 1])
            centres = centres_of(row, n, lengths)
            pairwise = np.sqrt(((centres[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2))
            np.fill_diagonal(pairwise, np.inf)
            compare(label, "separation_distance", float(row["separation_distance"]),
                    0.5 * pairwise.min(), 1e-12)
            # Fill distance, bracketed by a grid of 8 points per centre spacing and axis (once
            # per centre set: every kernel sees the same centres).
            key = (row["centres"], n)
            if key not in fill_brackets:
                fine = int(8 * math.sqrt(n)) + 1
                axes = [np.linspace(0.0, length, fine) for length in lengths]
                mesh = np.stack(np.meshgrid(axes[0], axes[1]), axis=-1).reshape(-1, 2)
                low = 0.0
                for chunk in range(0, len(mesh), 4096):
                    part = mesh[chunk:chunk + 4096]
                    distances = ((part[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2)
                    low = max(low, math.sqrt(distances.min(axis=1).max()))
                fill_brackets[key] = (low, low + 0.5 * math.hypot(lengths[0] / (fine - 1),
                                                                  lengths[1] / (fine - 1)))
            low, high = fill_brackets[key]
            ours = float(row["fill_distance"])
            compared += 1
            # The tool's value is the supremum to 1e-9 relative, from below.
            if not (low * (1 - 1e-9) <= ours <= high):
                failures += 1
                print(f"MISMATCH {label} fill_distance: {ours!r} outside [{low!r}, {high!r}]")

            gram = kernel(row, centres, centres)
            eigenvalues = np.linalg.eigvalsh(gram)
            condition = eigenvalues[-1] / eigenvalues[0]
            if 0 < condition < 1e8:
                compare(label, "gram_min_eigenvalue", float(row["gram_min_eigenvalue"]),
                        eigenvalues[0])
                compare(label, "gram_condition_number", float(row["gram_condition_number"]),
                        condition)
            else:
                skipped += 2
            if n > LARGEST_SOLVED:
                skipped += 2
                continue
            cross = kernel(row, points, centres)
            f_centres = expression(row["target_f"], centres[:, 0], centres[:, 1])
            solution = np.linalg.solve(gram, np.hstack([cross.T, f_centres[:, None]]))
            coefficients = solution[:, -1]
            power = math.sqrt(max(0.0, np.max(1.0 - np.sum(cross.T * solution[:, :-1], axis=0))))
            if float(row["power_function_sup"]) > 1000 * float(row["power_function_floor"]):
                compare(label, "power_function_sup", float(row["power_function_sup"]), power)
            else:
                skipped += 1
            residual = f_points - cross @ coefficients
            l2 = math.sqrt(np.sum(weights * residual ** 2))
            if float(row["l2_error"]) > 1000 * float(row["error_floor"]):
                compare(label, "l2_error", float(row["l2_error"]), l2)
            else:
                skipped += 1
    print(f"reference check: {compared} values compared, {skipped} not resolvable in double "
          f"precision skipped, {failures} mismatches")
    sys.exit(1 if failures or compared == 0 else 0)


if __name__ == "__main__":
    main()
