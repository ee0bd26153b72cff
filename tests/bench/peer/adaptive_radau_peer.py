#!/usr/bin/env python3
"""A SciPy peer of rkhs-study's adaptive trials: the same model, integrated by solve_ivp's Radau.

What a user of SciPy would write instead of rkhs-study, kept here to compare step counts, wall
times and errors side by side (compare_adaptive.py). It reads a study file (kind = "adaptive")
and reproduces the trials of its grid from the formulas of docs/model.md, written independently
of the C++ code:

    plant      x'     = A x + B f(s),               s = (v t) mod L
    estimator  xhat'  = A xhat + B phi(s)^T alpha
    gradient   alpha' = Gamma^-1 phi(s) B^T P (x - xhat)
    rkhs       alpha' = Gamma^-1 G^-1 phi(s) B^T P (x - xhat)
    A^T P + P A = -Q,  z(0) = 0,  T = laps L / v (or final_time)

integrated by scipy.integrate.solve_ivp(method="Radau") over [0, T] in one call, with the exact
Jacobian [[A, 0, 0], [0, A, B phi^T], [psi b^T, -psi b^T, 0]] (b = P B, psi = M phi). Kernels
(docs/model.md section 3): the periodised Gaussian (image sum, checked at start-up against its
Fourier series, the formula of tests/reference/gram_and_power_reference.py) and the multiscale
B-spline kernel through its sparse feature map (Cox-de Boor splines, checked against the dense
feature matrix of the reference). Centres: "uniform" (offset allowed). Road: "sine". Plants:
"quarter_car" and "linear". G^-1 of the rkhs law: Cholesky, or when G is singular to working
precision (lambda_min <= n eps lambda_max) the pseudo-inverse dropping eigenvalues at or below
that cutoff, or the regularised inverse, as the study's [solver] says (GramSolver).

Measured per trial: accepted steps (len(sol.t) - 1), rejected step attempts (attempts counted
by wrapping Radau's collocation solve: attempts - accepted), nfev, njev, nlu, the L2 and sup
errors of fhat(T) against f and of the interpolant Pi_n f on the study's evaluation grid
(L2 as Domain::l2_norm: rectangle rule on the closed track), |x(T) - xhat(T)|, and the wall and
CPU time of the whole trial (set-up, integration, measurement) and of the integration alone.

Single-threaded: OMP_NUM_THREADS and OPENBLAS_NUM_THREADS are set to 1 before NumPy loads.
SciPy is not a dependency of the project; see README.md in this folder for how to provide it.

Usage:
    adaptive_radau_peer.py STUDY.toml [--kernel SPEC] [--law NAME] [--n N[,N...]]
                           [--rtol R] [--atol A] [--laps K] [--out FILE.csv]
SPEC is a kernel name with optional parameters, e.g. "gaussian", "bspline:degree=1" or
"gaussian:sigma=1"; --kernel, --law and --n may be repeated (a trial is run when it matches one
value of each given option).
"""
import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse
import csv
import itertools
import math
import sys
import time
import tomllib

import numpy as np

try:
    import scipy
    import scipy.linalg
    from scipy.integrate import solve_ivp
    from scipy.integrate._ivp import radau as _radau
except ImportError as error:  # pragma: no cover - depends on the machine
    sys.exit(f"adaptive_radau_peer: SciPy is needed ({error}); see tests/bench/peer/README.md")

EPS = np.finfo(float).eps

# ---------------------------------------------------------------------------------------------
# Study file: the trial grid


def as_list(value):
    return value if isinstance(value, list) else [value]


def expand_entry(entry):
    """A plugin entry with list-valued parameters as axes: one dict per combination, the first
    declared parameter varying slowest (docs/study-files.md)."""
    keys = [k for k in entry if k not in ("name", "tier")]
    combos = itertools.product(*(as_list(entry[k]) for k in keys))
    return [dict(zip(keys, values), name=entry["name"]) for values in combos]


def n_values(grid):
    n = grid.get("n", [10])
    if isinstance(n, list):
        return [int(v) for v in n]
    if isinstance(n, int):
        return [n]
    if "step" in n:
        return list(range(int(n["from"]), int(n["to"]) + 1, int(n["step"])))
    if "factor" in n:
        out, v = [], int(n["from"])
        while v <= int(n["to"]):
            out.append(v)
            v *= int(n["factor"])
        return out
    raise SystemExit(f"unsupported [grid] n = {n!r}")


def domain_of(study):
    domain = study.get("domain", {})
    if not domain.get("periodic", True):
        raise SystemExit("the peer handles closed tracks (periodic domains) only")
    return float(domain["length"]) if "length" in domain else 2 * math.pi * float(domain.get("radius", 4.0))


def parse_matrix(text, size):
    """docs/study-files.md matrix syntax: "identity", "diag(a, b, ...)" or rows split by ';'."""
    body = str(text).strip()
    if body in ("identity", "I"):
        return np.eye(size)
    if body.startswith("diag(") and body.endswith(")"):
        return np.diag([float(v) for v in body[5:-1].replace(",", " ").split()])
    rows = [[float(v) for v in row.replace(",", " ").split()] for row in body.split(";")]
    return np.array(rows, dtype=float)


def plant_matrices(entry):
    name = entry["name"]
    if name == "quarter_car":
        m1, m2 = float(entry.get("m1", 0.5)), float(entry.get("m2", 0.5))
        k1, k2 = float(entry.get("k1", 5e4)), float(entry.get("k2", 3e4))
        c2 = float(entry.get("c2", 200.0))
        a20 = (-1.0 if entry.get("paper_sign", False) else 1.0) * c2 / m2
        A = np.array([[-c2 / m1, -(k1 + k2) / m1, c2 / m1, k2 / m1],
                      [1.0, 0.0, 0.0, 0.0],
                      [a20, k2 / m2, -c2 / m2, -k2 / m2],
                      [0.0, 0.0, 1.0, 0.0]])
        B = np.array([k1 / m1, 0.0, 0.0, 0.0])
        return A, B
    if name == "linear":
        A = parse_matrix(entry.get("A", "-1"), 0)
        B = parse_matrix(entry.get("B", "1"), 0).reshape(-1)
        return A, B
    raise SystemExit(f"the peer has no plant '{name}'")


def kernel_label(entry):
    params = ",".join(f"{k}={entry[k]}" for k in entry if k != "name")
    return f"{entry['name']}:{params}" if params else entry["name"]


def parse_kernel_selector(text):
    name, _, rest = text.partition(":")
    params = {}
    for item in filter(None, rest.split(",")):
        key, _, value = item.partition("=")
        params[key.strip()] = value.strip()
    return name.strip(), params


def value_matches(actual, wanted):
    try:
        return float(actual) == float(wanted)
    except (TypeError, ValueError):
        return str(actual).lower() == str(wanted).lower()


def kernel_matches(entry, selectors):
    if not selectors:
        return True
    for name, params in selectors:
        if entry["name"] == name and all(
                key in entry and value_matches(entry[key], value) for key, value in params.items()):
            return True
    return False


# ---------------------------------------------------------------------------------------------
# Kernels (docs/model.md section 3)


def cardinal_bspline(p, x):
    """N_p(x) with knots 0..p+1 by the Cox-de Boor recursion (vectorised)."""
    x = np.asarray(x, dtype=float)
    if p == 0:
        return ((x >= 0) & (x < 1)).astype(float)
    return (x * cardinal_bspline(p - 1, x) + (p + 1 - x) * cardinal_bspline(p - 1, x - 1)) / p


def gaussian_fourier(d, L, sigma, convention):
    """Periodised Gaussian by its Fourier series (Poisson summation): the reference formula."""
    s = sigma if convention == "2sigma2" else sigma / math.sqrt(2)
    K = 1
    while math.exp(-2 * math.pi ** 2 * s ** 2 * K ** 2 / L ** 2) > 1e-18:
        K += 1
    k = np.arange(1, K + 1)
    weights = np.exp(-2 * math.pi ** 2 * s ** 2 * k ** 2 / L ** 2)
    d = np.asarray(d)
    return s * math.sqrt(2 * math.pi) / L * (
        1 + 2 * np.tensordot(np.cos(2 * math.pi * d[..., None] * k / L), weights, axes=1))


class GaussianBasis:
    """phi_i(s) = sum_{|m| <= M} exp(-(d_i + m L)^2 / (c sigma^2)), d_i = s - c_i reduced to
    [-L/2, L/2]; M the smallest count whose omitted images are below 1e-16 k0(0)."""

    def __init__(self, entry, L, centres):
        unknown = set(entry) - {"name", "sigma", "convention"}
        if unknown:
            raise SystemExit(f"gaussian: the peer does not know parameters {sorted(unknown)}")
        self.sigma = float(entry.get("sigma", 1.0))
        self.convention = entry.get("convention", "2sigma2")
        self.inverse_scale = 1.0 / ((2.0 if self.convention == "2sigma2" else 1.0) * self.sigma ** 2)
        self.L, self.centres = L, np.asarray(centres, dtype=float)
        profile = lambda r: math.exp(-r * r * self.inverse_scale)
        self.images = 0
        while True:  # omitted images |m| > M lie beyond (M + 1/2) L; bounded by a geometric tail
            first, second = profile((self.images + 0.5) * L), profile((self.images + 1.5) * L)
            if first == 0.0 or (second / first < 1 and 2 * first / (1 - second / first) <= 1e-16):
                break
            self.images += 1
        self.shifts = L * np.arange(-self.images, self.images + 1)

    def kernel(self, points, centres):
        d = np.asarray(points)[:, None] - np.asarray(centres)[None, :]
        d -= self.L * np.round(d / self.L)
        if self.images == 0:
            return np.exp(-d * d * self.inverse_scale)
        e = d[..., None] + self.shifts
        return np.exp(-e * e * self.inverse_scale).sum(axis=-1)

    def gram(self):
        G = self.kernel(self.centres, self.centres)
        check = gaussian_fourier(self.centres[:, None] - self.centres[None, :], self.L,
                                 self.sigma, self.convention)
        if np.max(np.abs(G - check)) > 1e-12:
            raise SystemExit(f"gaussian: image sum and Fourier series differ by "
                             f"{np.max(np.abs(G - check)):.3e}")
        return G

    def cross(self, points):
        return self.kernel(points, self.centres)

    def phi(self, s):
        d = s - self.centres
        d -= self.L * np.round(d / self.L)
        if self.images == 0:
            return np.exp(-d * d * self.inverse_scale)
        e = d[:, None] + self.shifts
        return np.exp(-e * e * self.inverse_scale).sum(axis=1)

    def kinks(self):
        return []


class BSplineBasis:
    """Multiscale B-spline kernel on the closed track through its feature map:
    phi_{j,k}(u) = 2^{j (1 - 2r) / 2} N_p(2^j u / h0 - k), k mod n_j, h0 = L / n0, j = 0..J;
    phi_i(s) = sum_{j,k} phi_{j,k}(c_i) phi_{j,k}(s) (only (p + 1)(J + 1) features are nonzero)."""

    def __init__(self, entry, L, centres):
        unknown = set(entry) - {"name", "degree", "r", "n0", "J"}
        if unknown:
            raise SystemExit(f"bspline: the peer does not know parameters {sorted(unknown)}")
        self.p = int(entry.get("degree", 1))
        if "r" not in entry and self.p == 0:
            raise SystemExit("bspline: degree 0 needs r")
        self.r = float(entry.get("r", self.p))
        self.n0, self.J = int(entry.get("n0", 4)), int(entry.get("J", 6))
        self.L, self.centres = L, np.asarray(centres, dtype=float)
        self.h0 = L / self.n0
        levels = np.arange(self.J + 1)
        self.scale = 2.0 ** levels / self.h0
        self.cells = self.n0 * 2 ** levels
        self.offsets = self.n0 * (2 ** levels - 1)
        self.weights = 2.0 ** (levels * (1 - 2 * self.r) / 2)
        self.features = int(self.n0 * (2 ** (self.J + 1) - 1))
        self.shift = np.arange(self.p + 1)
        self.coefficients = self.dense_features(self.centres)  # n x F: phi_{j,k}(c_i)
        for i, c in enumerate(self.centres):  # the sparse evaluation agrees with the dense one
            index, value = self.sparse_features(c)
            dense = np.zeros(self.features)
            np.add.at(dense, index, value)
            if np.max(np.abs(dense - self.coefficients[i])) > 1e-14:
                raise SystemExit("bspline: sparse and dense feature maps differ")
        self.mapped = None

    def dense_features(self, s):
        """Every (level j, index k) of the periodic multiscale kernel, weight included (the
        reference's formula)."""
        blocks = []
        for j in range(self.J + 1):
            nj = self.n0 * 2 ** j
            x = (2 ** j) * np.asarray(s)[:, None] / self.h0
            k = np.arange(nj)[None, :]
            blocks.append(2 ** (j * (1 - 2 * self.r) / 2) * cardinal_bspline(self.p, np.mod(x - k, nj)))
        return np.hstack(blocks)

    def sparse_features(self, s):
        x = s * self.scale
        cell = np.floor(x)
        t = x - cell
        # Spline k = cell - i covers x at x - k = t + i, i = 0..p.
        value = self.weights[:, None] * cardinal_bspline(self.p, t[:, None] + self.shift[None, :])
        k = np.mod(cell[:, None].astype(np.int64) - self.shift[None, :], self.cells[:, None])
        return (self.offsets[:, None] + k).ravel(), value.ravel()

    def gram(self):
        return self.coefficients @ self.coefficients.T

    def cross(self, points):
        return self.dense_features(points) @ self.coefficients.T

    def set_learning_map(self, M):
        self.mapped = M @ self.coefficients  # psi(s) = M Phi_c phi_features(s)

    def phi(self, s):
        index, value = self.sparse_features(s)
        return self.coefficients[:, index] @ value

    def phi_psi(self, s):
        index, value = self.sparse_features(s)
        return self.coefficients[:, index] @ value, self.mapped[:, index] @ value

    def kinks(self):
        cells = self.n0 * 2 ** self.J
        return self.L * np.arange(cells) / cells


def make_basis(entry, L, centres):
    if entry["name"] == "gaussian":
        return GaussianBasis(entry, L, centres)
    if entry["name"] == "bspline":
        return BSplineBasis(entry, L, centres)
    raise SystemExit(f"the peer has no kernel '{entry['name']}'")


class GramSolve:
    """Solves with G as GramSolver does: Cholesky, or for a G singular to working precision
    (lambda_min <= n eps lambda_max) the pseudo-inverse dropping the eigenvalues at or below
    that cutoff, applied as V (V^T b / lambda) (never as an explicit G^+ times b: with
    eigenvalues near 1e-13 lambda_max that product loses ten digits), or the regularised
    Cholesky factorisation of G + mu lambda_max I."""

    def __init__(self, G, solver):
        n = G.shape[0]
        values, vectors = np.linalg.eigh(G)
        cutoff = n * EPS * values[-1]
        self.cholesky = None
        if values[0] > cutoff:
            try:
                self.cholesky = scipy.linalg.cho_factor(G, lower=True)
                self.method = "cholesky"
                return
            except np.linalg.LinAlgError:
                pass
        policy = solver.get("singular", "pseudo_inverse")
        if policy == "fail":
            raise RuntimeError("Gram matrix singular to working precision")
        if policy == "regularised":
            mu = float(solver.get("regularisation", 0.0)) or n * EPS
            self.cholesky = scipy.linalg.cho_factor(G + mu * values[-1] * np.eye(n), lower=True)
            self.method = f"regularised (mu = {mu:.3e} lambda_max)"
            return
        keep = values > cutoff
        self.vectors, self.values = vectors[:, keep], values[keep]
        self.method = f"pseudo-inverse (rank {int(keep.sum())} of {n})"

    def solve(self, b):
        if self.cholesky is not None:
            return scipy.linalg.cho_solve(self.cholesky, b)
        projected = self.vectors.T @ b
        return self.vectors @ (projected / (self.values if b.ndim == 1 else self.values[:, None]))


# ---------------------------------------------------------------------------------------------
# One trial


class AttemptCounter:
    """Counts Radau's step attempts (one collocation solve each), so rejected steps are
    attempts - accepted. Wraps the module-level function Radau's step calls."""

    def __init__(self):
        self.count = 0
        self.original = _radau.solve_collocation_system

        def counted(*args, **kwargs):
            self.count += 1
            return self.original(*args, **kwargs)

        _radau.solve_collocation_system = counted


def run_trial(trial, settings, counter, restart_at_kinks=False):
    started_wall, started_cpu = time.perf_counter(), time.process_time()
    L, n = settings["length"], trial["n"]
    offset = float(trial["centres"].get("offset", 0.0))
    centres = (np.arange(n) + offset) * L / n
    basis = make_basis(trial["kernel"], L, centres)
    target = trial["target"]
    amplitude = float(target.get("amplitude", 2.0))
    wavenumber = 2 * math.pi * float(target.get("cycles", 1.0)) / L
    phase = float(target.get("phase", 0.0))
    road = lambda s: amplitude * np.sin(wavenumber * s + phase)

    A, B = plant_matrices(trial["plant"])
    d = A.shape[0]
    Q = parse_matrix(settings["q"], d)
    P = scipy.linalg.solve_continuous_lyapunov(A.T, -Q)  # A^T P + P A = -Q
    b = P @ B
    G = basis.gram()
    gram_solve = GramSolve(G, settings["solver"])
    solve = gram_solve.method
    gamma = float(trial["law"].get("gamma", 1e-3))
    law = trial["law"]["name"]
    if law == "rkhs":
        M = gram_solve.solve(np.eye(n)) / gamma
    elif law == "gradient":
        M = np.eye(n) / gamma
    else:
        raise SystemExit(f"the peer has no law '{law}'")

    # The static part: Pi_n f on the evaluation grid.
    grid = L * np.arange(settings["evaluation_points"]) / settings["evaluation_points"]
    cross = basis.cross(grid)
    f_grid = road(grid)
    alpha_star = gram_solve.solve(road(centres))
    l2 = lambda v: math.sqrt(float(np.sum(v * v)) * L / len(v))

    v = settings["speed"]
    T = settings["final_time"] if settings["final_time"] > 0 else settings["laps"] * L / v
    N = 2 * d + n
    if isinstance(basis, BSplineBasis):
        basis.set_learning_map(M)
        phi_psi = basis.phi_psi
    elif law == "gradient":
        def phi_psi(s):
            phi = basis.phi(s)
            return phi, phi / gamma
    else:
        def phi_psi(s):
            phi = basis.phi(s)
            return phi, M @ phi

    def rhs(t, z):
        s = math.fmod(v * t, L)
        if s < 0:
            s += L
        phi, psi = phi_psi(s)
        x, xhat, alpha = z[:d], z[d:2 * d], z[2 * d:]
        dz = np.empty(N)
        dz[:d] = A @ x + B * road(s)
        dz[d:2 * d] = A @ xhat + B * (phi @ alpha)
        dz[2 * d:] = psi * (b @ (x - xhat))
        return dz

    template = np.zeros((N, N))
    template[:d, :d] = A
    template[d:2 * d, d:2 * d] = A

    def jacobian(t, z):
        s = math.fmod(v * t, L)
        if s < 0:
            s += L
        phi, psi = phi_psi(s)
        J = template.copy()
        J[d:2 * d, 2 * d:] = np.outer(B, phi)
        coupling = np.outer(psi, b)
        J[2 * d:, :d] = coupling
        J[2 * d:, d:2 * d] = -coupling
        return J

    # Integration over [0, T] in one call (or segment by segment between kinks of phi(s(t))).
    bounds = [0.0, T]
    if restart_at_kinks:
        kinks = [(lap * L + k) / v for lap in range(int(math.ceil(T * v / L)) + 1)
                 for k in basis.kinks()]
        bounds = [0.0] + sorted(t for t in kinks if 1e-12 * T < t < T * (1 - 1e-12)) + [T]
    z = np.zeros(N)
    counter.count = 0
    steps = nfev = njev = nlu = 0
    integration_wall = time.perf_counter()
    step = None  # a restart carries the last full step over (SciPy's own first step otherwise)
    for t0, t1 in zip(bounds[:-1], bounds[1:]):
        first = min(step, t1 - t0) if step and settings["carry_step"] else None
        sol = solve_ivp(rhs, (t0, t1), z, method="Radau", rtol=settings["rtol"],
                        atol=settings["atol"], jac=jacobian, dense_output=False, first_step=first)
        if sol.status != 0:
            raise RuntimeError(f"solve_ivp failed: {sol.message}")
        steps += len(sol.t) - 1
        if len(sol.t) > 2:
            step = max(sol.t[-2] - sol.t[-3], sol.t[-1] - sol.t[-2])
        elif len(sol.t) == 2:
            step = max(step or 0.0, sol.t[-1] - sol.t[-2])
        nfev, njev, nlu = nfev + sol.nfev, njev + sol.njev, nlu + sol.nlu
        z = sol.y[:, -1].copy()
    integration_seconds = time.perf_counter() - integration_wall
    attempts = counter.count

    alpha = z[2 * d:]
    estimate = cross @ alpha
    projection = cross @ alpha_star
    out = {
        "steps": steps,
        "rejected_steps": attempts - steps,
        "segments": len(bounds) - 1,
        "nfev": nfev, "njev": njev, "nlu": nlu,
        "l2_error": l2(f_grid - estimate),
        "sup_error": float(np.max(np.abs(f_grid - estimate))),
        "interpolant_l2_error": l2(f_grid - projection),
        "gap_to_projection": l2(estimate - projection),
        "final_state_error": float(np.linalg.norm(z[:d] - z[d:2 * d])),
        "solve": solve,
        "final_time": T,
        "integration_seconds": integration_seconds,
        "seconds": time.perf_counter() - started_wall,
        "cpu_seconds": time.process_time() - started_cpu,
    }
    return out


# ---------------------------------------------------------------------------------------------


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("study", help="study file (TOML, kind = \"adaptive\")")
    parser.add_argument("--kernel", action="append", default=[],
                        help='kernel selector, e.g. "gaussian" or "bspline:degree=1" (repeatable)')
    parser.add_argument("--law", action="append", default=[], help="learning law (repeatable)")
    parser.add_argument("--n", action="append", default=[], help="n, or a comma-separated list")
    parser.add_argument("--rtol", type=float, help="override the study's rtol")
    parser.add_argument("--atol", type=float, help="override the study's atol")
    parser.add_argument("--laps", type=float, help="override the study's laps")
    parser.add_argument("--restart-at-kinks", action="store_true",
                        help="integrate segment by segment between the kinks of phi(s(t)), as "
                             "rkhs-study does (default: one solve_ivp call over [0, T])")
    parser.add_argument("--carry-step", action="store_true",
                        help="with --restart-at-kinks: start each segment with the last step "
                             "size of the one before (default: SciPy's first-step selection)")
    parser.add_argument("--out", help="CSV file of the results (default: standard output)")
    parser.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    args = parser.parse_args(argv)

    with open(args.study, "rb") as f:
        study = tomllib.load(f)
    header = study.get("study", {})
    if header.get("kind", "approximation") != "adaptive":
        raise SystemExit("the study is not adaptive (kind = \"adaptive\")")
    adaptive = study.get("adaptive", {})
    integrators = study.get("integrator", [{"name": "rosenbrock4"}])
    if len(integrators) > 1 and (args.rtol is None or args.atol is None):
        print("adaptive_radau_peer: several [[integrator]] entries; the first one's tolerances "
              "are used", file=sys.stderr)
    integrator = integrators[0]
    if isinstance(integrator.get("rtol", 0.0), list) or isinstance(integrator.get("atol", 0.0), list):
        raise SystemExit("tolerance axes are not supported: select with --rtol/--atol")
    settings = {
        "length": domain_of(study),
        "evaluation_points": int(header.get("evaluation_points", 4096)),
        "speed": float(adaptive.get("speed", 1.0)),
        "laps": float(args.laps if args.laps is not None else adaptive.get("laps", 10)),
        "final_time": 0.0 if args.laps is not None else float(adaptive.get("final_time", 0.0)),
        "q": adaptive.get("q", "identity"),
        "solver": study.get("solver", {}),
        "rtol": args.rtol if args.rtol is not None else float(integrator.get("rtol", 1e-6)),
        "atol": args.atol if args.atol is not None else float(integrator.get("atol", 1e-8)),
        "carry_step": args.carry_step,
    }
    if adaptive.get("road", "target") != "target":
        raise SystemExit("the peer drives the plant with the target itself only (road = \"target\")")

    kernel_selectors = [parse_kernel_selector(k) for k in args.kernel]
    wanted_n = {int(v) for item in args.n for v in item.split(",") if v}
    kernels = [e for entry in study.get("kernel", []) for e in expand_entry(entry)]
    laws = [e for entry in study.get("law", [{"name": "rkhs"}]) for e in expand_entry(entry)]
    targets = [e for entry in study.get("target", [{"name": "sine"}]) for e in expand_entry(entry)]
    plants = [e for entry in study.get("plant", [{"name": "quarter_car"}]) for e in expand_entry(entry)]
    centres = [e for entry in study.get("centres", [{"name": "uniform"}]) for e in expand_entry(entry)]
    for entry in targets:
        if entry["name"] != "sine":
            raise SystemExit(f"the peer has no target '{entry['name']}'")
    for entry in centres:
        if entry["name"] != "uniform":
            raise SystemExit(f"the peer has no centre placement '{entry['name']}'")

    counter = AttemptCounter()
    columns = ["kernel", "law", "gamma", "target", "plant", "n", "rtol", "atol", "laps", "steps",
               "rejected_steps", "segments", "nfev", "njev", "nlu", "l2_error", "sup_error",
               "interpolant_l2_error", "gap_to_projection", "final_state_error", "solve",
               "seconds", "integration_seconds", "cpu_seconds", "scipy", "numpy"]
    stream = open(args.out, "w", newline="") if args.out else sys.stdout
    writer = csv.DictWriter(stream, fieldnames=columns)
    writer.writeheader()
    for kernel, target, centre, plant, law, n in itertools.product(
            kernels, targets, centres, plants, laws, n_values(study.get("grid", {}))):
        if not kernel_matches(kernel, kernel_selectors):
            continue
        if args.law and law["name"] not in args.law:
            continue
        if wanted_n and n not in wanted_n:
            continue
        trial = {"kernel": kernel, "target": target, "centres": centre, "plant": plant,
                 "law": law, "n": n}
        result = run_trial(trial, settings, counter, args.restart_at_kinks)
        row = {"kernel": kernel_label(kernel), "law": law["name"],
               "gamma": law.get("gamma", 1e-3), "target": kernel_label(target),
               "plant": kernel_label(plant), "n": n, "rtol": settings["rtol"],
               "atol": settings["atol"], "laps": settings["laps"],
               "scipy": scipy.__version__, "numpy": np.__version__}
        row.update({k: result[k] for k in columns if k in result})
        for key in ("l2_error", "sup_error", "interpolant_l2_error", "gap_to_projection",
                    "final_state_error"):
            row[key] = repr(float(row[key]))
        for key in ("seconds", "integration_seconds", "cpu_seconds"):
            row[key] = f"{row[key]:.4f}"
        writer.writerow(row)
        stream.flush()
        if not args.quiet:
            print(f"{kernel_label(kernel)} {law['name']} n={n}: {result['steps']} steps "
                  f"({result['rejected_steps']} rejected), l2_error {result['l2_error']:.6e}, "
                  f"{result['seconds']:.2f} s", file=sys.stderr)
    if args.out:
        stream.close()


if __name__ == "__main__":
    main()
