#!/usr/bin/env python3
"""scikit-learn peer for rkhs-study approximation trials on a box in R^d (d = 1, 2, 3).

Reads an rkhs-study study file (kind = "approximation", [domain] lengths = [...], periodic = false,
[[kernel]] matern, [[target]] expression, [[centres]] uniform) and reproduces each trial with

    GaussianProcessRegressor(Matern(length_scale, nu), optimizer=None, alpha=ALPHA,
                             normalize_y=False).fit(X, f(X)).predict(Xs, return_std=True)

and measures what rkhs-study's trials.csv reports (docs/metrics.md):

    power_function_sup = max_m std(s_m)         (std^2 = k(x,x) - k_X^T G^-1 k_X, clamped at 0)
    sup_error          = max_m |f(s_m) - mean(s_m)|
    l2_error           = sqrt(sum_m w_m (f(s_m) - mean(s_m))^2), w = tensor trapezoid weights

Points, as rkhs-study places them on a box (docs/model.md sections 4-5, docs/metrics.md "Domains
in R^d", docs/study-files.md):
    centres `uniform`: m = round(n^(1/d)) points per axis, c = i L_a / (m - 1) (end points
        included); n must be m^d;
    evaluation points: p = round(M^(1/d)) per axis, s = j L_a / (p - 1), M = evaluation_points;
        L2 weights: the trapezoid rule per axis, tensor product.
Kernel: rkhs-study's matern is scikit-learn's Matern (plugins/internal/rkhs/kernels/matern.hpp):
    nu = 2.5: (1 + a + a^2/3) exp(-a), a = sqrt(5) |x - y| / length_scale; unit amplitude.
Target `expression`: the muparser expression f of x1..xd, L1..Ld, pi, evaluated here with NumPy
(`^` -> `**`; the functions of muparser that NumPy has under the same name).

alpha (the nugget added to the diagonal) defaults to 0: rkhs-study factorises the exact G by
Cholesky when it is not singular to working precision, so alpha = 0 is the like-for-like setting;
scikit-learn's default 1e-10 is --alpha 1e-10.

Threads: --threads N sets OPENBLAS_NUM_THREADS / OMP_NUM_THREADS / MKL_NUM_THREADS before NumPy is
imported and limits the pools with threadpoolctl as well. The BLAS that NumPy and SciPy use
(threadpoolctl.threadpool_info()) is printed and written to the CSV.

Environment (Debian 12; SciPy and scikit-learn unpacked beside the system, not installed):
    PYTHONPATH=/opt/pyref/root/usr/lib/python3/dist-packages
    LD_LIBRARY_PATH=/opt/pyref/root/usr/lib/x86_64-linux-gnu
    /usr/bin/python3 approx_gp_peer.py STUDY.toml [--n 1024,4096] [--threads 1] [--out peer.csv]
        [--rkhs-trials trials.csv]   (prints relative differences against rkhs-study's metrics)
"""
import argparse
import csv
import math
import os
import re
import sys
import time
import tomllib


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("study", help="rkhs-study study file (approximation, box, matern, expression)")
    p.add_argument("--n", help="comma-separated n values instead of the study's [grid] n")
    p.add_argument("--alpha", type=float, default=0.0, help="nugget on the diagonal (default 0)")
    p.add_argument("--threads", type=int, default=1, help="BLAS/OpenMP threads (default 1)")
    p.add_argument("--repeat", type=int, default=1, help="time each trial this many times")
    p.add_argument("--out", help="CSV file for the results")
    p.add_argument("--rkhs-trials", help="rkhs-study trials.csv to compare with (rows by n)")
    p.add_argument("--quiet", action="store_true")
    return p.parse_args()


ARGS = parse_args()
for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[var] = str(ARGS.threads)

import numpy as np  # noqa: E402  (after the thread variables)
import scipy  # noqa: E402
import sklearn  # noqa: E402
import threadpoolctl  # noqa: E402
from sklearn.gaussian_process import GaussianProcessRegressor  # noqa: E402
from sklearn.gaussian_process.kernels import Matern  # noqa: E402


def as_list(value):
    return value if isinstance(value, list) else [value]


def expand_grid(grid):
    n = grid["n"]
    if isinstance(n, dict):
        if "step" in n:
            return list(range(n["from"], n["to"] + 1, n["step"]))
        values, v = [], n["from"]
        while v <= n["to"]:
            values.append(v)
            v *= n["factor"]
        return values
    return as_list(n)


MUPARSER_FUNCTIONS = {name: getattr(np, name) for name in (
    "sin", "cos", "tan", "arcsin", "arccos", "arctan", "sinh", "cosh", "tanh", "exp", "log",
    "log2", "log10", "sqrt", "abs", "sign", "floor", "ceil")}
MUPARSER_FUNCTIONS.update({"asin": np.arcsin, "acos": np.arccos, "atan": np.arctan,
                           "ln": np.log, "rint": np.rint, "atan2": np.arctan2,
                           "min": np.minimum, "max": np.maximum})


def expression_target(entry, lengths):
    text = entry["f"]
    python = text.replace("^", "**")
    if re.search(r"[;=]|__|\blambda\b|\bimport\b", python):
        raise SystemExit(f"refusing expression {text!r}")
    constants = {k: float(v) for k, v in entry.items() if k not in ("name", "f")}
    code = compile(python, "<target f>", "eval")

    def f(points):
        names = dict(MUPARSER_FUNCTIONS, pi=math.pi, **constants)
        for a, L in enumerate(lengths):
            names[f"x{a + 1}"] = points[:, a]
            names[f"L{a + 1}"] = L
        value = eval(code, {"__builtins__": {}}, names)  # noqa: S307 (a study file's own f)
        return np.broadcast_to(np.asarray(value, dtype=float), (points.shape[0],)).copy()

    return f, text


def axis_points(count, length):
    # rkhs-study's interval placement, end points included: i L / (count - 1).
    return np.array([i * length / (count - 1) for i in range(count)])


def tensor_grid(axes):
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([m.ravel() for m in mesh])


def trapezoid_weights(count, length):
    h = length / (count - 1)
    w = np.full(count, h)
    w[0] = w[-1] = h / 2
    return w


def integer_root(value, d):
    m = int(round(value ** (1.0 / d)))
    return m if m ** d == value else None


def blas_description():
    info = threadpoolctl.threadpool_info()
    parts = []
    for lib in info:
        if lib.get("user_api") == "blas":
            parts.append(f"{lib.get('internal_api')} {lib.get('version')} "
                         f"{lib.get('architecture', '?')} threads={lib.get('num_threads')} "
                         f"{lib.get('filepath')}")
    return "; ".join(parts) or "no BLAS found by threadpoolctl", info


def run_trial(n, d, lengths, M, kernel_entry, target, alpha, repeat):
    m = integer_root(n, d)
    if m is None:
        raise SystemExit(f"n = {n} is not a {d}-th power: uniform centres need n = m^{d}")
    p = integer_root(M, d)
    if p is None:
        p = int(round(M ** (1.0 / d)))
    X = tensor_grid([axis_points(m, L) for L in lengths])
    Xs = tensor_grid([axis_points(p, L) for L in lengths])
    W = np.ones(1)
    for L in lengths:
        W = np.multiply.outer(W, trapezoid_weights(p, L))
    W = W.ravel()
    y = target(X)
    fs = target(Xs)
    kernel = Matern(length_scale=float(kernel_entry["length_scale"]), nu=float(kernel_entry["nu"]))
    fit_times, predict_times = [], []
    for _ in range(repeat):
        gpr = GaussianProcessRegressor(kernel=kernel, optimizer=None, alpha=alpha,
                                       normalize_y=False, copy_X_train=False)
        t0 = time.perf_counter()
        gpr.fit(X, y)
        t1 = time.perf_counter()
        mean, std = gpr.predict(Xs, return_std=True)
        t2 = time.perf_counter()
        fit_times.append(t1 - t0)
        predict_times.append(t2 - t1)
        del gpr
    e = fs - mean
    return {
        "n": n, "m_per_axis": m, "evaluation_points": Xs.shape[0], "alpha": alpha,
        "fit_seconds_min": min(fit_times), "fit_seconds_median": float(np.median(fit_times)),
        "predict_seconds_min": min(predict_times),
        "predict_seconds_median": float(np.median(predict_times)),
        "total_seconds_min": min(f + q for f, q in zip(fit_times, predict_times)),
        "power_function_sup": float(std.max()),
        "sup_error": float(np.abs(e).max()),
        "l2_error": float(math.sqrt(np.sum(W * e * e))),
        "repeat": repeat,
    }


def main():
    with open(ARGS.study, "rb") as fh:
        study = tomllib.load(fh)
    kind = study.get("study", {}).get("kind", "approximation")
    if kind != "approximation":
        raise SystemExit(f"{ARGS.study}: kind = {kind!r}; only approximation studies")
    domain = study["domain"]
    if "lengths" not in domain or domain.get("periodic", True):
        raise SystemExit("only a box: [domain] lengths = [...] with periodic = false")
    lengths = [float(L) for L in domain["lengths"]]
    d = len(lengths)
    M = int(study["study"].get("evaluation_points", 4096))
    ns = [int(v) for v in ARGS.n.split(",")] if ARGS.n else expand_grid(study["grid"])
    kernels = [k for k in study["kernel"] if k["name"] == "matern"]
    if not kernels:
        raise SystemExit("no [[kernel]] name = \"matern\"")
    targets = [t for t in study.get("target", []) if t["name"] == "expression"]
    if not targets:
        raise SystemExit("no [[target]] name = \"expression\"")
    for c in study.get("centres", [{"name": "uniform"}]):
        if c["name"] != "uniform":
            raise SystemExit(f"centres {c['name']!r}: only uniform")
    blas, _ = blas_description()
    versions = f"numpy {np.__version__}, scipy {scipy.__version__}, sklearn {sklearn.__version__}"
    if not ARGS.quiet:
        print(f"# {versions}; BLAS: {blas}", flush=True)
    rkhs_rows = {}
    if ARGS.rkhs_trials:
        with open(ARGS.rkhs_trials, newline="") as fh:
            for row in csv.DictReader(fh):
                rkhs_rows[int(float(row["n"]))] = row
    rows = []
    with threadpoolctl.threadpool_limits(limits=ARGS.threads):
        for kernel_entry in kernels:
            for nu in as_list(kernel_entry.get("nu", 1.5)):
                for ls in as_list(kernel_entry.get("length_scale", 1.0)):
                    for target_entry in targets:
                        target, text = expression_target(target_entry, lengths)
                        for n in ns:
                            r = run_trial(n, d, lengths, M, {"nu": nu, "length_scale": ls},
                                          target, ARGS.alpha, ARGS.repeat)
                            r.update({"kernel": f"matern:nu={nu},length_scale={ls}",
                                      "target": text, "threads": ARGS.threads,
                                      "blas": blas, "versions": versions})
                            rows.append(r)
                            if not ARGS.quiet:
                                print(f"n={n:5d} fit {r['fit_seconds_min']:.3f} s  predict "
                                      f"{r['predict_seconds_min']:.3f} s  power_function_sup "
                                      f"{r['power_function_sup']:.12e}  sup_error "
                                      f"{r['sup_error']:.12e}  l2_error {r['l2_error']:.12e}",
                                      flush=True)
                            if n in rkhs_rows:
                                row = rkhs_rows[n]
                                for key in ("power_function_sup", "sup_error", "l2_error"):
                                    a, b = r[key], float(row[key])
                                    rel = abs(a - b) / max(abs(a), abs(b), 1e-300)
                                    print(f"    {key}: rkhs-study {b:.12e}  sklearn {a:.12e}  "
                                          f"rel. diff {rel:.2e}", flush=True)
    if ARGS.out:
        with open(ARGS.out, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    sys.exit(main())
