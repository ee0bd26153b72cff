#!/usr/bin/env python3
"""Independent check of an approximation study on a box in R^2 or R^3.

The studies: studies/wendland_2d.toml (the dense path) and tests/reference/sparse_wendland_2d.toml,
sparse_wendland_3d.toml (`[linear_algebra] solver = "sparse"`, CHOLMOD's sparse Cholesky
factorisation: framework/internal/rkhs/approx/sparse_gram.hpp).

Runs `rkhs-study run STUDY --out DIR`, then recomputes every trial with NumPy from the formulas
(docs/study-files.md, "Domains in R^d"; docs/metrics.md), written independently of the C++
code, with NumPy's dense linear algebra only (np.linalg.solve, eigvalsh; SciPy is not
installable beside the project's Boost on Debian 12, so no scipy.sparse or scipy.spatial): the
grid and Halton centres (radical inverses in bases 2, 3, 5), Wendland's phi_{3,k} from its
polynomial, f from the study's expression (NumPy's own functions), and, for each metric trials.csv
holds (a study need not ask for all: the sparse path computes no Gram eigenvalues),

  separation_distance   half the smallest pairwise distance                 (1e-12 relative)
  fill_distance         bracketed: not below the largest distance from a fine grid (8 points
                        per centre spacing and axis) to the centres, and not above it by more
                        than that grid's half-diagonal (the tool's value is exact to 1e-9)
  gram_min_eigenvalue,  LAPACK's eigh, when the condition number is below 1e8
  gram_condition_number
  power_function_sup    sqrt(max(k(x,x) - k_X^T G^-1 k_X)) on the evaluation grid
  projection_norm_H_to_C  the same power function sup (interpolation: ||I - Pi||_{H -> C})
  l2_error              the tensor trapezoid rule of f - Pi f on that grid
  sup_error             max |f - Pi f| on that grid
  interpolant_native_norm  sqrt(alpha^T G alpha), G alpha = f(X)
                        (these five for n <= LARGEST_SOLVED, when above 1000 times the floor
                        trials.csv gives them: *_floor)
  power_function_floor  sqrt(n eps lambda_max max |G^-1 k_X|^2) and
  error_floor           n eps lambda_max max |G^-1 k_X| |alpha|, lambda_max exact here and a
                        Lanczos estimate in the tool                         (FLOOR_TOLERANCE)

to TOLERANCE relative (1e-8) on the sparse path; the dense study's ill-conditioned Gram matrices
(radius 2 on the unit square) to DENSE_TOLERANCE and SPECTRUM_TOLERANCE (1e-6). When the study asks for
`[linear_algebra] solver = "sparse"`, every trial's `solve` must name the sparse Cholesky
factorisation: a trial the tool measured on the dense path instead (its fallback when CHOLMOD
cannot decide) would leave the sparse path unchecked, and fails the check.

Usage: domains_in_rd_reference.py RKHS_STUDY_EXECUTABLE STUDY.toml OUT_DIR
Prints the largest relative difference per metric; exit status 0 when every compared value
agrees, 1 otherwise.
"""
import csv
import itertools
import math
import subprocess
import sys
import tomllib

import numpy as np

TOLERANCE = 1e-8
# The dense study (radius 2 on the unit square: condition numbers up to 1e8 and beyond) agrees
# to about 5e-9 on its solved metrics and 1.4e-9 on its eigenvalues; it keeps a margin.
DENSE_TOLERANCE = 1e-6
SPECTRUM_TOLERANCE = 1e-6
# The floors scale with lambda_max(G), which the tool estimates by Lanczos iterations (they agree
# to 5e-9 and better).
FLOOR_TOLERANCE = 1e-6
EPS = np.finfo(float).eps
# The power function and the L2 error need G^-1 at every evaluation point, O(n^2 M); beyond this
# n the reference leaves them out (NumPy's reference LAPACK would take minutes), and compares
# the geometry and the eigenvalues only.
LARGEST_SOLVED = 576
HALTON_BASES = (2, 3, 5)


def radical_inverse(i, base):
    value, scale = 0.0, 1.0 / base
    while i > 0:
        value += (i % base) * scale
        i //= base
        scale /= base
    return value


def tensor_grid(axes):
    """The points of the tensor grid of `axes`, the first coordinate varying fastest."""
    return np.array([point[::-1] for point in itertools.product(*reversed(axes))])


def per_axis(count, d):
    return round(count ** (1.0 / d))


def centres_of(row, n, lengths):
    d = len(lengths)
    if row["centres"] == "halton":
        skip = int(row.get("centres_skip") or 0)
        return np.array([[radical_inverse(skip + p + 1, HALTON_BASES[a]) * lengths[a]
                          for a in range(d)] for p in range(n)])
    if row["centres"] == "uniform":
        m = per_axis(n, d)
        if m ** d != n:
            raise SystemExit(f"uniform centres need n = m^{d}, found {n}")
        return tensor_grid([np.linspace(0.0, length, m) for length in lengths])
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
    squared = np.zeros((len(x), len(y)))
    for a in range(x.shape[1]):  # axis by axis: no (len(x), len(y), d) temporary
        squared += (x[:, a, None] - y[None, :, a]) ** 2
    return wendland_3(int(row["k"]), np.sqrt(squared) / float(row["radius"]))


def expression(text, points, lengths):
    names = {"pi": math.pi, "exp": np.exp, "cos": np.cos, "sin": np.sin,
             "sqrt": np.sqrt, "abs": np.abs, "log": np.log, "tanh": np.tanh}
    for a, length in enumerate(lengths):
        names[f"x{a + 1}"] = points[:, a]
        names[f"L{a + 1}"] = length
    return eval(text.replace("^", "**"), {"__builtins__": {}}, names)


def trapezoid_weights(m, length):
    w = np.full(m, length / (m - 1))
    w[0] = w[-1] = 0.5 * length / (m - 1)
    return w


def fill_bracket(centres, n, lengths):
    """[low, high] around sup_x min_i |x - c_i|: low the largest distance from a grid of 8
    points per centre spacing and axis, high low plus that grid's half-diagonal."""
    d = len(lengths)
    fine = int(8 * n ** (1.0 / d)) + 1
    mesh = tensor_grid([np.linspace(0.0, length, fine) for length in lengths])
    centre_norms = (centres ** 2).sum(axis=1)
    low = 0.0
    for chunk in range(0, len(mesh), 8192):
        part = mesh[chunk:chunk + 8192]
        distances = (part ** 2).sum(axis=1)[:, None] - 2.0 * part @ centres.T + centre_norms
        nearest = distances.argmin(axis=1)
        # The farthest of the nearest distances, again exactly from the differences.
        exact = ((part - centres[nearest]) ** 2).sum(axis=1)
        low = max(low, math.sqrt(exact.max()))
    return low, low + 0.5 * math.sqrt(sum((length / (fine - 1)) ** 2 for length in lengths))


def value(row, column):
    """The row's number in `column`, or None when trials.csv has no such column or leaves it
    empty (a metric the study did not ask for)."""
    text = row.get(column)
    if text is None or text == "":
        return None
    number = float(text)
    return None if math.isnan(number) else number


def main():
    executable, study_file, out_dir = sys.argv[1:4]
    subprocess.run([executable, "run", study_file, "--out", out_dir, "--quiet"], check=True)
    with open(study_file, "rb") as f:
        study = tomllib.load(f)
    lengths = study["domain"]["lengths"]
    d = len(lengths)
    if d not in (2, 3) or study["domain"].get("periodic", True):
        raise SystemExit("the reference handles boxes in R^2 and R^3 only")
    sparse = study.get("linear_algebra", {}).get("solver") == "sparse"
    M = study["study"]["evaluation_points"]
    m = per_axis(M, d)
    points = tensor_grid([np.linspace(0.0, length, m) for length in lengths])
    weights = np.ones(1)
    for length in lengths:  # the first axis fastest, as the points
        weights = np.outer(trapezoid_weights(m, length), weights).ravel()
    f_points = None
    fill_brackets = {}

    compared = skipped = failures = 0
    worst = {}  # metric -> (largest relative difference, tolerance)
    widest_fill_bracket = 0.0

    solved_tolerance = TOLERANCE if sparse else DENSE_TOLERANCE

    def compare(label, metric, ours, reference, tolerance=None):
        tolerance = solved_tolerance if tolerance is None else tolerance
        nonlocal compared, failures
        compared += 1
        difference = abs(ours - reference) / abs(reference) if reference else abs(ours)
        if metric not in worst or difference > worst[metric][0]:
            worst[metric] = (difference, tolerance)
        if not difference <= tolerance:
            failures += 1
            print(f"MISMATCH {label} {metric}: {ours!r} vs reference {reference!r}")

    def compare_above_floor(label, row, metric, reference):
        """Compares `metric` when the tool asked for it and it lies 1000 times above its floor."""
        nonlocal skipped
        ours = value(row, metric)
        if ours is None:
            return
        floor = value(row, metric + "_floor")
        if floor is not None and ours <= 1000 * floor:
            skipped += 1
            return
        compare(label, metric, ours, reference)

    with open(f"{out_dir}/trials.csv", newline="") as f:
        for row in csv.DictReader(f):
            n = int(row["n"])
            label = f"{row['kernel']} k={row['k']} {row['centres']} n={n}"
            if row["status"] != "ok":
                failures += 1
                print(f"MISMATCH {label}: status {row['status']} ({row['reason']})")
                continue
            if sparse:
                compared += 1
                if not row["solve"].startswith("sparse Cholesky"):
                    failures += 1
                    print(f"MISMATCH {label}: solved by '{row['solve']}', not the sparse path")
            if f_points is None:
                f_points = expression(row["target_f"], points, lengths)
            centres = centres_of(row, n, lengths)
            pairwise = np.sqrt(((centres[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2))
            np.fill_diagonal(pairwise, np.inf)
            if value(row, "separation_distance") is not None:
                compare(label, "separation_distance", value(row, "separation_distance"),
                        0.5 * pairwise.min(), 1e-12)
            # Fill distance, once per centre set: every kernel sees the same centres.
            ours = value(row, "fill_distance")
            if ours is not None:
                key = (row["centres"], row.get("centres_skip"), n)
                if key not in fill_brackets:
                    fill_brackets[key] = fill_bracket(centres, n, lengths)
                low, high = fill_brackets[key]
                widest_fill_bracket = max(widest_fill_bracket, (high - low) / low)
                compared += 1
                # The tool's value is the supremum to 1e-9 relative, from below.
                if not (low * (1 - 1e-9) <= ours <= high):
                    failures += 1
                    print(f"MISMATCH {label} fill_distance: {ours!r} outside [{low!r}, {high!r}]")

            gram = kernel(row, centres, centres)
            eigenvalues = np.linalg.eigvalsh(gram)
            condition = eigenvalues[-1] / eigenvalues[0]
            for metric, reference in (("gram_min_eigenvalue", eigenvalues[0]),
                                      ("gram_condition_number", condition)):
                if value(row, metric) is None:
                    continue
                if 0 < condition < 1e8:
                    compare(label, metric, value(row, metric), reference, SPECTRUM_TOLERANCE)
                else:
                    skipped += 1
            if n > LARGEST_SOLVED:
                skipped += 1
                continue
            cross = kernel(row, points, centres)
            f_centres = expression(row["target_f"], centres, lengths)
            solution = np.linalg.solve(gram, np.hstack([cross.T, f_centres[:, None]]))
            coefficients = solution[:, -1]
            cardinal = solution[:, :-1]  # G^-1 k_X(s_m), one column per evaluation point
            power = math.sqrt(max(0.0, np.max(1.0 - np.sum(cross.T * cardinal, axis=0))))
            compare_above_floor(label, row, "power_function_sup", power)
            compare_above_floor(label, row, "projection_norm_H_to_C", power)
            residual = f_points - cross @ coefficients
            compare_above_floor(label, row, "l2_error", math.sqrt(np.sum(weights * residual ** 2)))
            compare_above_floor(label, row, "sup_error", np.abs(residual).max())
            compare_above_floor(label, row, "interpolant_native_norm",
                                math.sqrt(coefficients @ gram @ coefficients))
            round_off = n * EPS * eigenvalues[-1]
            largest_cardinal = math.sqrt((cardinal ** 2).sum(axis=0).max())
            for metric, reference in (
                    ("power_function_floor", math.sqrt(round_off) * largest_cardinal),
                    ("error_floor", round_off * largest_cardinal * np.linalg.norm(coefficients))):
                if value(row, metric) is not None:
                    compare(label, metric, value(row, metric), reference, FLOOR_TOLERANCE)
    if fill_brackets:
        print(f"  {'fill_distance':<24} within the brackets, the widest {widest_fill_bracket:.2e} "
              f"relative")
    for metric, (difference, tolerance) in worst.items():
        print(f"  {metric:<24} largest relative difference {difference:.2e} "
              f"(tolerance {tolerance:.0e})")
    print(f"reference check ({'sparse' if sparse else 'dense'} path, d = {d}): {compared} values "
          f"compared, {skipped} not resolvable in double precision skipped, "
          f"{failures} mismatches")
    sys.exit(1 if failures or compared == 0 else 0)


if __name__ == "__main__":
    main()
