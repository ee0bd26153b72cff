"""Kernels, targets and centre placements written in Python (python/rkhs_study/plugins.py).

Each Python plugin here is the same function as a built-in C++ plugin, computed in the same
order of operations, so a study of both must give the same metrics: the test that the engine
calls the Python code where and as it calls the C++ code.
"""

import math
import os
import re

import numpy as np
import pandas as pd
import pytest

import rkhs_study

# The paper's closed track (radius 4 m), as studies/gram_and_power.toml.
TRACK = 2 * math.pi * 4.0


class PyGaussian(rkhs_study.Kernel):
    """The built-in Gaussian exp(-d^2 / (2 sigma^2)), periodised by images on a periodic domain
    like plugins/internal/rkhs/kernels/periodic_images.hpp: the images |m| <= M summed
    smallest first, M the smallest count whose tail is below 1e-16 k(0)."""

    name = "py_gaussian"
    parameters = {"sigma": rkhs_study.Parameter(1.0, "width, metres", min=0, min_exclusive=True)}
    analytic = True

    def profile(self, r):
        return np.exp(-r * r * (1.0 / (2.0 * self.sigma * self.sigma)))

    def images(self, period):
        for count in range(1 << 20):
            first = float(self.profile((count + 0.5) * period))
            if first == 0.0:
                return count
            ratio = float(self.profile((count + 1.5) * period)) / first
            if ratio < 1.0 and 2.0 * first / (1.0 - ratio) <= 1e-16:
                return count
        return 1 << 20

    def k(self, X, Y):
        D = self.domain.differences(X, Y)
        value = np.ones(D.shape[:2])
        for axis in range(D.shape[2]):
            d = D[:, :, axis]
            if not self.domain.periodic:
                value = value * self.profile(d)
                continue
            period = self.domain.extents[axis]
            total = np.zeros_like(d)
            for m in range(self.images(period), 0, -1):
                total += self.profile(np.abs(d + m * period)) + self.profile(np.abs(d - m * period))
            value = value * (total + self.profile(np.abs(d)))
        return value


class PySine(rkhs_study.Target):
    """The built-in sine target amplitude sin(2 pi cycles s / L + phase) and its derivative."""

    name = "py_sine"
    parameters = {"amplitude": 2.0, "cycles": 1.0, "phase": 0.0}

    def f(self, X):
        wavenumber = 2.0 * math.pi * self.cycles / self.domain.length
        return self.amplitude * np.sin(wavenumber * X[:, 0] + self.phase)

    def derivative(self, X):
        wavenumber = 2.0 * math.pi * self.cycles / self.domain.length
        return self.amplitude * wavenumber * np.cos(wavenumber * X[:, 0] + self.phase)


class PyUniform(rkhs_study.CentrePlacement):
    """The built-in uniform placement on a closed track: c_i = i L / n."""

    name = "py_uniform"

    def place(self, n, domain):
        return np.arange(n) * domain.length / n


class PyJittered(rkhs_study.CentrePlacement):
    """Uniform centres moved by up to a quarter spacing, drawn from the trial's seed."""

    name = "py_jittered"

    def place(self, n, domain, seed):
        rng = np.random.default_rng(seed)
        spacing = domain.length / n
        return np.sort((np.arange(n) + 0.5 + rng.uniform(-0.25, 0.25, n)) * spacing)


rkhs_study.register_kernel(PyGaussian)
rkhs_study.register_target(PySine)
rkhs_study.register_centres(PyUniform)
rkhs_study.register_centres(PyJittered)


def study_text(kernels, targets=('name = "sine"',), centres=('name = "uniform"',),
               n="{ from = 8, to = 40, step = 8 }", name="python_plugins"):
    tables = "".join(f"\n[[kernel]]\n{k}\n" for k in kernels)
    tables += "".join(f"\n[[target]]\n{t}\n" for t in targets)
    tables += "".join(f"\n[[centres]]\n{c}\n" for c in centres)
    return f"""
[study]
name = "{name}"
kind = "approximation"
abscissa = "n"
evaluation_points = 1024

[domain]
radius = 4.0
periodic = true

[grid]
n = {n}
{tables}
[solver]
singular = "pseudo_inverse"
"""


def metric_columns(trials: pd.DataFrame):
    """The computed columns of trials.csv: every float column but the plugins' parameters."""
    return [c for c in trials.columns if pd.api.types.is_float_dtype(trials[c])
            and not c.startswith(("kernel_", "target_", "centres_"))]


# A floor is an estimate of a size (docs/metrics.md, "Floors"): two computations of it agree
# within this factor (as tests/golden/check_shipped_studies.py compares them).
FLOOR_FACTOR = 4.0


def assert_same_metrics(a: pd.DataFrame, b: pd.DataFrame, relative=1e-14, floors=True):
    """Every metric of `a` equals `b`'s within `relative` or, with `floors`, within the larger of
    the two values' round-off floors (the <metric>_floor columns), the floors themselves within
    FLOOR_FACTOR. Two implementations of one kernel differ in the last bits of their entries
    (NumPy's and glibc's exp are not the same code on every processor), and an ill-conditioned
    Gram matrix magnifies that by as much as the floors say. floors=False: `relative` alone
    (relative=0.0: bit-identical)."""
    a, b = a.reset_index(drop=True), b.reset_index(drop=True)
    assert len(a) == len(b) > 0
    assert a["status"].tolist() == b["status"].tolist() == ["ok"] * len(a)
    columns = metric_columns(a)
    assert len(columns) >= 5
    for column in columns:
        x, y = a[column].to_numpy(), b[column].to_numpy()
        both_nan = np.isnan(x) & np.isnan(y)
        with np.errstate(invalid="ignore", divide="ignore"):  # inf - inf, 0 / 0: equal already
            scale = np.maximum(np.abs(x), np.abs(y))
            allowed = relative * scale
            if floors and column + "_floor" in a.columns:
                floor = np.maximum(a[column + "_floor"].to_numpy(), b[column + "_floor"].to_numpy())
                allowed = np.maximum(allowed, np.nan_to_num(floor))
            close = (x == y) | (np.abs(x - y) <= allowed)
            if floors and column.endswith("_floor"):
                close |= (x > 0) & (y > 0) & (np.maximum(x, y) <= FLOOR_FACTOR * np.minimum(x, y))
        assert (close | both_nan).all(), (column, x, y)
    for column in a.columns:
        if column.endswith("_flag") or column.startswith("flag"):
            assert a[column].fillna("").tolist() == b[column].fillna("").tolist(), column


def test_python_gaussian_gives_the_builtin_gaussians_metrics():
    text = study_text(['name = "gaussian"\nsigma = 1.5', 'name = "py_gaussian"\nsigma = 1.5'])
    trials = rkhs_study.Study.from_toml(text).run(threads=2).trials
    builtin = trials[trials["kernel"] == "gaussian"]
    python = trials[trials["kernel"] == "py_gaussian"]
    assert_same_metrics(builtin, python)


def test_python_gaussian_on_an_interval_gives_the_builtin_gaussians_metrics():
    text = study_text(['name = "gaussian"\nsigma = 1.5', 'name = "py_gaussian"\nsigma = 1.5'])
    text = text.replace("periodic = true", "periodic = false")
    trials = rkhs_study.Study.from_toml(text).run(threads=1).trials
    assert_same_metrics(trials[trials["kernel"] == "gaussian"],
                        trials[trials["kernel"] == "py_gaussian"])


def test_python_gaussian_matrix_equals_the_builtin_in_two_dimensions():
    domain = rkhs_study.Domain(length=2.0, width=1.5, dimension=2, periodic=True)
    rng = np.random.default_rng(1)
    X = rng.uniform(0, 1, (30, 2)) * [2.0, 1.5]
    Y = rng.uniform(0, 1, (20, 2)) * [2.0, 1.5]
    a = rkhs_study.kernel_matrix("py_gaussian", X, Y, domain, sigma=0.4)
    b = rkhs_study.kernel_matrix("gaussian", X, Y, domain, sigma=0.4)
    assert a.shape == (30, 20)
    np.testing.assert_allclose(a, b, rtol=1e-14, atol=0)


def test_python_gaussian_passes_the_kernel_contract():
    verification = rkhs_study.verify_plugin(PyGaussian)
    assert verification.passed, verification.report
    assert "power-function rate" in verification.report
    assert "verify-plugin: PASS" in verification.report


def test_a_kernel_that_breaks_the_contract_fails_verification():
    class NotSymmetric(rkhs_study.Kernel):
        name = "py_not_symmetric"
        analytic = True

        def k(self, X, Y):
            return np.exp(-self.domain.squared_distances(X, Y)) * (1 + 0.1 * X[:, :1])

    verification = rkhs_study.verify_plugin(NotSymmetric)
    assert not verification.passed
    assert "FAIL  symmetry" in verification.report
    rkhs_study.unregister(NotSymmetric)


def test_python_target_and_placement_give_the_builtins_metrics():
    text = study_text(['name = "gaussian"\nsigma = 1.5'],
                      targets=['name = "sine"', 'name = "py_sine"'],
                      centres=['name = "uniform"', 'name = "py_uniform"'])
    trials = rkhs_study.Study.from_toml(text).run(threads=2).trials
    reference = trials[(trials["target"] == "sine") & (trials["centres"] == "uniform")]
    for target, centres in (("py_sine", "uniform"), ("sine", "py_uniform"),
                            ("py_sine", "py_uniform")):
        found = trials[(trials["target"] == target) & (trials["centres"] == centres)]
        assert_same_metrics(reference, found)


def test_a_seeded_python_placement_is_the_same_on_any_thread_count():
    text = study_text(['name = "gaussian"\nsigma = 1.5'], centres=['name = "py_jittered"'],
                      n="[8, 16, 24, 32, 40, 48]")
    one = rkhs_study.Study.from_toml(text).run(threads=1).trials
    two = rkhs_study.Study.from_toml(text).run(threads=2).trials
    assert_same_metrics(one, two, relative=0.0, floors=False)
    uniform = rkhs_study.Study.from_toml(text.replace("py_jittered", "uniform")).run().trials
    assert not np.array_equal(one["l2_error"].to_numpy(), uniform["l2_error"].to_numpy())


def test_an_exception_in_a_python_kernel_fails_its_trials_only():
    class Raising(rkhs_study.Kernel):
        name = "py_raising"

        def k(self, X, Y):
            if len(X) > 20:
                raise ValueError("too many points for this kernel")
            return np.exp(-self.domain.squared_distances(X, Y))

    rkhs_study.register_kernel(Raising)
    try:
        text = study_text(['name = "gaussian"\nsigma = 1.5', 'name = "py_raising"'])
        trials = rkhs_study.Study.from_toml(text).run(threads=2).trials
    finally:
        rkhs_study.unregister(Raising)
    assert (trials[trials["kernel"] == "gaussian"]["status"] == "ok").all()
    raising = trials[trials["kernel"] == "py_raising"]
    failed = raising[raising["status"] == "failed"]
    assert len(failed) > 0
    reason_column = [c for c in trials.columns if "reason" in c or "error_message" in c][0]
    for reason in failed[reason_column]:
        assert re.search(r"kernel 'py_raising': k\(X, Y\) raised ValueError: too many points "
                         r"for this kernel \(at .*test_plugins\.py:\d+ in k\)", reason), reason


def test_a_wrong_shape_names_the_method_and_both_shapes():
    class WrongShape(rkhs_study.Kernel):
        name = "py_wrong_shape"

        def k(self, X, Y):
            return np.zeros((len(X), len(Y) + 1))

    rkhs_study.register_kernel(WrongShape)
    try:
        with pytest.raises(Exception, match=r"k\(X, Y\) returned an array of shape \(3, 3\), "
                                            r"expected \(3, 2\)"):
            rkhs_study.kernel_matrix("py_wrong_shape", np.zeros((3, 1)), np.zeros((2, 1)),
                                     rkhs_study.Domain(length=1.0))
    finally:
        rkhs_study.unregister(WrongShape)


def test_a_registered_name_is_usable_in_validation_and_listed_parameters_are_checked():
    text = study_text(['name = "py_gaussian"\nsigma = -1.0'])
    with pytest.raises(rkhs_study.StudyError, match="sigma"):
        rkhs_study.Study.from_toml(text, "bad.toml").validate()
    text = study_text(['name = "py_gaussian"\nwidth = 1.0'])
    with pytest.raises(rkhs_study.StudyError, match="width"):
        rkhs_study.Study.from_toml(text, "bad.toml").validate()


class StoredGaussianA(rkhs_study.Kernel):
    name = "py_stored"
    analytic = True

    def k(self, X, Y):
        return np.exp(-self.domain.squared_distances(X, Y) / 2.0)


class StoredGaussianB(rkhs_study.Kernel):
    name = "py_stored"
    analytic = True

    def k(self, X, Y):
        return np.exp(-self.domain.squared_distances(X, Y) / 3.0)


def test_a_store_reuses_a_python_kernels_trials_until_its_source_changes(tmp_path):
    store = tmp_path / "store.sqlite"
    text = study_text(['name = "py_stored"'], n="[8, 16]")
    rkhs_study.register_kernel(StoredGaussianA)
    first = rkhs_study.Study.from_toml(text).run(store=store)
    again = rkhs_study.Study.from_toml(text).run(store=store)
    assert (first.ran, first.reused) == (2, 0)
    assert (again.ran, again.reused) == (0, 2)
    rkhs_study.register_kernel(StoredGaussianB)  # the same name, another source
    changed = rkhs_study.Study.from_toml(text).run(store=store)
    assert (changed.ran, changed.reused) == (2, 0)
    assert not np.array_equal(first.trials["l2_error"], changed.trials["l2_error"])
    rkhs_study.unregister(StoredGaussianB)


def test_python_gaussian_in_an_adaptive_study_gives_the_builtin_gaussians_metrics():
    """The adaptive engine evaluates the kernel sections along the path (KernelBasis: one k call
    per right-hand side). An explicit integrator needs no Jacobian, so no derivative of the
    sections: the Python kernel's difference quotients would differ from the built-in
    Gaussian's closed form in the last digits."""
    text = f"""
[study]
name = "python_adaptive"
kind = "adaptive"
evaluation_points = 512
metrics = ["l2_error", "sup_error", "gap_to_projection", "final_state_error",
           "max_state_error", "steps", "rhs_evaluations"]

[domain]
radius = 4.0

[grid]
n = [8, 16]

[[kernel]]
name = "gaussian"
sigma = 1.5

[[kernel]]
name = "py_gaussian"
sigma = 1.5

[[target]]
name = "sine"

[[plant]]
name = "quarter_car"

[[law]]
name = "gradient"
gamma = 2e4

[[integrator]]
name = "dopri5"
rtol = 1e-6
atol = 1e-8

[adaptive]
speed = 1.0
laps = 1
"""
    trials = rkhs_study.Study.from_toml(text).run(threads=2).trials
    builtin = trials[trials["kernel"] == "gaussian"]
    python = trials[trials["kernel"] == "py_gaussian"]
    assert_same_metrics(builtin, python)


class PyMatern32(rkhs_study.Kernel):
    """Matern nu = 3/2, (1 + sqrt(3) r / l) exp(-sqrt(3) r / l), periodised by Domain.radial."""

    name = "py_matern32"
    parameters = {"length_scale": rkhs_study.Parameter(1.0, "l, metres", min=0,
                                                       min_exclusive=True)}

    @property
    def sobolev_order(self):
        return 1.5 + self.domain.dimension / 2

    def k(self, X, Y):
        a = math.sqrt(3.0) / self.length_scale
        return self.domain.radial(lambda r: (1.0 + a * r) * np.exp(-a * r), X, Y)


class PyRadialGaussian(rkhs_study.Kernel):
    """The Gaussian through Domain.radial: on a torus the lattice image sum."""

    name = "py_radial_gaussian"
    parameters = {"sigma": 1.0}
    analytic = True

    def k(self, X, Y):
        scale = 1.0 / (2.0 * self.sigma * self.sigma)
        return self.domain.radial(lambda r: np.exp(-r * r * scale), X, Y)


# The built-in Matern is periodised on the track only (it refuses a torus of d > 1); the
# built-in Gaussian on a torus is the product of per-axis image sums, the same lattice sum.
@pytest.mark.parametrize("domain,python,builtin,parameters", [
    (rkhs_study.Domain(length=TRACK, periodic=True), "py_matern32", "matern", {}),
    (rkhs_study.Domain(length=TRACK, periodic=False), "py_matern32", "matern", {}),
    (rkhs_study.Domain(length=2.0, width=1.5, dimension=2, periodic=False), "py_matern32",
     "matern", {}),
    (rkhs_study.Domain(length=2.0, width=1.5, dimension=2, periodic=True),
     "py_radial_gaussian", "gaussian", {"sigma": 0.6}),
    (rkhs_study.Domain(length=2.0, width=1.5, height=1.0, dimension=3, periodic=True),
     "py_radial_gaussian", "gaussian", {"sigma": 0.6}),
], ids=["track", "interval", "box2", "torus2", "torus3"])
def test_domain_radial_periodises_by_images_like_the_builtin_kernels(domain, python, builtin,
                                                                     parameters):
    rkhs_study.register_kernel(PyMatern32)
    rkhs_study.register_kernel(PyRadialGaussian)
    matern = {"length_scale": 0.7} if builtin == "matern" else {}
    rng = np.random.default_rng(7)
    X = rng.uniform(0, 1, (25, domain.dimension)) * domain.extents
    Y = rng.uniform(0, 1, (15, domain.dimension)) * domain.extents
    found = rkhs_study.kernel_matrix(python, X, Y, domain, **parameters, **matern)
    extra = {"nu": 1.5} if builtin == "matern" else {}
    expected = rkhs_study.kernel_matrix(builtin, X, Y, domain, **parameters, **matern, **extra)
    np.testing.assert_allclose(found, expected, rtol=2e-14, atol=0)


@pytest.mark.parametrize("name", ["", "My Kernel", "k\x1b[31m", 'a"; rm', "9lives"])
def test_a_plugin_name_that_study_files_cannot_write_is_refused(name):
    class Badly(rkhs_study.Kernel):
        def k(self, X, Y):
            return np.ones((len(X), len(Y)))

    Badly.name = name
    with pytest.raises(ValueError, match="name"):
        rkhs_study.register_kernel(Badly)
