"""Kernels, targets and centre placements written in Python (docs/python.md, "Plugins").

A plugin is a class; registering it makes its `name` usable in any study, exactly like a C++
plugin's, for the rest of the process:

    import numpy as np, rkhs_study

    class MyGaussian(rkhs_study.Kernel):
        name = "my_gaussian"
        doc = "exp(-|x - y|^2 / (2 sigma^2))"
        parameters = {"sigma": rkhs_study.Parameter(1.0, "width, metres", min=0,
                                                    min_exclusive=True)}
        analytic = True

        def k(self, X, Y):
            return np.exp(-self.domain.squared_distances(X, Y) / (2 * self.sigma**2))

    rkhs_study.register_kernel(MyGaussian)
    rkhs_study.verify_plugin(MyGaussian).passed

The engine calls the methods with whole blocks of points (X and Y are (m, d) float64 arrays, d
the domain's dimension): a Gram matrix is one call of k, a cross matrix one call per chunk of a
million entries, an adaptive right-hand side one call per evaluation. Each call holds the GIL;
the trials' other work runs without it, and trials of C++ plugins only run on every thread.
An exception in a method fails the trial that called it, with the exception's text as reason.

A trial's result is keyed by the hash of its plugin classes' source (inspect.getsource), so a
result store re-runs trials whose Python kernel changed.
"""

from __future__ import annotations

import hashlib
import inspect
import itertools
import math
import re
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from . import _core

__all__ = ["Parameter", "Domain", "Kernel", "Target", "CentrePlacement", "register_kernel",
           "register_target", "register_centres", "unregister", "verify_plugin",
           "PluginVerification", "kernel_matrix"]


@dataclass
class Parameter:
    """A plugin parameter as a study file sets it (`sigma = 2` in the plugin's table).

    The type follows the default: float (real), int (integer), bool (boolean), str (text, or
    choice when `choices` is given). A list in the study file makes the parameter an axis of the
    grid. min/max bound a number (open at an end whose *_exclusive flag is set).
    """

    default: Any
    doc: str = ""
    min: Optional[float] = None
    max: Optional[float] = None
    min_exclusive: bool = False
    max_exclusive: bool = False
    choices: Optional[list] = None

    def spec(self, name: str) -> dict:
        value = self.default
        if self.choices is not None:
            kind = "choice"
        elif isinstance(value, bool):
            kind = "boolean"
        elif isinstance(value, int):
            kind = "integer"
        elif isinstance(value, float):
            kind = "real"
        elif isinstance(value, str):
            kind = "text"
        else:
            raise TypeError(f"parameter '{name}': default {value!r} is not a float, int, bool "
                            "or str")
        return {"name": name, "type": kind, "default": value, "doc": self.doc,
                "min": self.min, "max": self.max, "min_exclusive": self.min_exclusive,
                "max_exclusive": self.max_exclusive,
                "choices": [str(c) for c in (self.choices or [])]}


@dataclass(frozen=True)
class Domain:
    """The domain Omega of a study (its [domain] table): a closed track or an interval in d = 1,
    a box or a torus in d = 2, 3. Extents in metres; `periodic` identifies every axis with its
    own period."""

    length: float
    periodic: bool = True
    dimension: int = 1
    width: float = 0.0
    height: float = 0.0

    @property
    def extents(self) -> np.ndarray:
        """(d,) the extent of each axis: length, width, height."""
        return np.array([self.length, self.width, self.height][: self.dimension])

    def differences(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """(m, n, d) the differences x_i - y_j per axis; on a periodic domain the representative
        in [-P/2, P/2] of each axis' period P (the same rounding as the C++ kernels)."""
        D = np.asarray(X, float)[:, None, :] - np.asarray(Y, float)[None, :, :]
        if self.periodic:
            P = self.extents
            D = D - P * np.rint(D / P)
        return D

    def squared_distances(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """(m, n) the squared distances |x_i - y_j|^2 (on a torus, the torus distance)."""
        D = self.differences(X, Y)
        if D.shape[2] == 1:
            return D[:, :, 0] * D[:, :, 0]
        return np.einsum("mnd,mnd->mn", D, D)

    def distances(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """(m, n) the distances |x_i - y_j|."""
        return np.sqrt(self.squared_distances(X, Y))

    def radial(self, profile, X: np.ndarray, Y: np.ndarray, tolerance: float = 1e-16,
               max_images: int = 1000) -> np.ndarray:
        """(m, n) k(x_i, y_j) of the radial kernel k(x, y) = profile(|x - y|).

        On a box, profile of the distance. On a periodic domain the kernel periodised by
        images, sum over the lattice vectors m P of profile(|x - y + m P|), which is positive
        definite whenever profile is on R^d (profile of the torus distance in general is not).
        The images |m_a| <= M_a are summed, M_a per axis the smallest count whose tail is below
        `tolerance` profile(0), as the built-in kernels choose it
        (plugins/internal/rkhs/kernels/periodic_images.hpp): `profile` must be vectorised,
        positive at 0, non-increasing and log-concave (the Gaussian, Matern profiles of
        half-integer nu, Wendland's functions); a profile with a heavier tail (the inverse
        multiquadric's 1/r) has no convergent image sum. In d = 1 the terms are added in the
        built-in kernels' order, smallest first. In d > 1, ValueError when the lattice holds
        more than `max_images` images (each costs a pass over the (m, n) block).
        """
        if not self.periodic:
            return profile(self.distances(X, Y))
        D = self.differences(X, Y)
        periods = self.extents
        counts = [_image_count(profile, float(P), tolerance) for P in periods]
        if self.dimension == 1:
            d, L = D[:, :, 0], float(periods[0])
            total = np.zeros_like(d)
            for m in range(counts[0], 0, -1):
                total += profile(np.abs(d + m * L)) + profile(np.abs(d - m * L))
            return total + profile(np.abs(d))
        lattice = math.prod(2 * M + 1 for M in counts)
        if lattice > max_images:
            shape = " x ".join(str(2 * M + 1) for M in counts)
            raise ValueError(f"the image sum needs {lattice} lattice images ({shape}, more "
                             f"than max_images = {max_images}): the profile decays too "
                             "slowly for these periods; use a box (periodic = false)")
        offsets = sorted(itertools.product(*[range(-M, M + 1) for M in counts]),
                         key=lambda m: -sum(abs(x) for x in m))
        total = np.zeros(D.shape[:2])
        for m in offsets:
            shifted = D + np.asarray(m, float) * periods
            total += profile(np.sqrt(np.einsum("mnd,mnd->mn", shifted, shifted)))
        return total


def _image_count(profile, period: float, tolerance: float, most: int = 1 << 20) -> int:
    """The smallest M whose images |m| > M add less than tolerance profile(0) (see Domain.radial
    and image_count in periodic_images.hpp)."""
    target = tolerance * float(profile(np.float64(0.0)))
    for count in range(most):
        first = float(profile(np.float64((count + 0.5) * period)))
        if first == 0.0:
            return count
        ratio = float(profile(np.float64((count + 1.5) * period))) / first
        if ratio < 1.0 and 2.0 * first / (1.0 - ratio) <= target:
            return count
    return most


class _Plugin:
    """What every plugin class declares: name, doc and parameters (a dict of Parameter or of
    plain defaults). An instance has its domain (for kernels and targets) and each parameter as
    an attribute (self.sigma)."""

    name: str = ""
    doc: str = ""
    parameters: dict = {}

    def __init__(self, domain: Optional[Domain] = None, **parameters):
        self.domain = domain
        for key, value in parameters.items():
            setattr(self, key, value)


class Kernel(_Plugin):
    """A kernel k(x, y): subclass it and define k(X, Y) -> (m, n) array, vectorised.

    Class attributes state what approximation theory needs (the fields of the C++
    KernelProperties): positive_definite, sobolev_order (tau of a native space equal to
    H^tau, None otherwise), analytic, support_radius (0: global support), stationary, periodic
    (periodised on a periodic domain: True means k is a function of the torus difference).
    properties() may compute them from the parameters instead.
    """

    positive_definite: bool = True
    #: The dimensions d of the boxes it is defined on, and of the periodic domains (a closed
    #: track is d = 1, a torus d > 1): elsewhere constructing it raises ValueError, which
    #: verify_plugin reports as a domain the kernel is not defined on (a profile that decays
    #: too slowly for a lattice of images leaves the tori of d > 1 out, as the built-in
    #: matern does).
    dimensions: tuple = (1, 2, 3)
    periodic_dimensions: tuple = (1, 2, 3)
    sobolev_order: Optional[float] = None
    analytic: bool = False
    support_radius: float = 0.0
    stationary: bool = True
    periodic: Optional[bool] = None  # None: periodic exactly when the domain is

    def __init__(self, domain: Optional[Domain] = None, **parameters):
        if domain is not None:
            allowed = self.periodic_dimensions if domain.periodic else self.dimensions
            if domain.dimension not in allowed:
                where = ("a closed track" if domain.dimension == 1 else "a torus") \
                    if domain.periodic else ("an interval" if domain.dimension == 1 else "a box")
                raise ValueError(f"kernel '{self.name}' is not defined on {where} of d = "
                                 f"{domain.dimension} (it declares d in {tuple(allowed)})")
        super().__init__(domain, **parameters)

    def k(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        raise NotImplementedError(f"{type(self).__name__}.k(X, Y)")

    def diagonal(self, X: np.ndarray) -> np.ndarray:
        """(m,) k(x_i, x_i). Default: k(x, x) of the first point for a stationary kernel,
        otherwise one k call per point; override it for speed."""
        X = np.asarray(X, float)
        if len(X) == 0:
            return np.zeros(0)
        if self.stationary:
            return np.full(len(X), float(np.asarray(self.k(X[:1], X[:1]))[0, 0]))
        return np.array([float(np.asarray(self.k(x[None, :], x[None, :]))[0, 0]) for x in X])

    def properties(self) -> dict:
        periodic = self.domain.periodic if self.periodic is None else bool(self.periodic)
        return {"positive_definite": bool(self.positive_definite),
                "sobolev_order": None if self.sobolev_order is None else float(self.sobolev_order),
                "analytic": bool(self.analytic), "support_radius": float(self.support_radius),
                "stationary": bool(self.stationary), "periodic": periodic,
                "dimension": int(self.domain.dimension)}


class Target(_Plugin):
    """A target function f: subclass it and define f(X) -> (m,) array, vectorised. Define
    derivative(X) -> (m,) too when f has one in closed form (d = 1: df/ds); otherwise the
    engine takes central differences."""

    def f(self, X: np.ndarray) -> np.ndarray:
        raise NotImplementedError(f"{type(self).__name__}.f(X)")

    @property
    def has_derivative(self) -> bool:
        return type(self).derivative is not Target.derivative

    def derivative(self, X: np.ndarray) -> np.ndarray:
        raise NotImplementedError(f"{type(self).__name__}.derivative(X)")


class CentrePlacement(_Plugin):
    """Where the n centres of a trial sit: subclass it and define place(n, domain, seed) ->
    (n, d) array of points inside the domain (in d = 1 an (n,) array will do; it is sorted). `seed` is the
    trial's seed, derived from its key: a random placement draws from
    np.random.default_rng(seed), so results are the same on every run and thread count.
    A placement of two arguments, place(n, domain), is called without the seed."""

    def place(self, n: int, domain: Domain, seed: int) -> np.ndarray:
        raise NotImplementedError(f"{type(self).__name__}.place(n, domain, seed)")


def _parameter_specs(cls) -> list:
    specs = []
    for key, value in dict(getattr(cls, "parameters", {}) or {}).items():
        parameter = value if isinstance(value, Parameter) else Parameter(value)
        specs.append(parameter.spec(key))
    return specs


def _info(cls, base) -> dict:
    if not (isinstance(cls, type) and issubclass(cls, base)):
        raise TypeError(f"{cls!r} is not a subclass of rkhs_study.{base.__name__}")
    name = getattr(cls, "name", "")
    if not isinstance(name, str) or not name:
        raise ValueError(f"{cls.__qualname__}: set the class attribute `name` (the name study "
                         "files use)")
    if not re.fullmatch(r"[a-z][a-z0-9_]*", name):
        raise ValueError(f"{cls.__qualname__}: name {name!r} is not a plugin name (a lower-case "
                         "letter, then lower-case letters, digits and _), as study files, "
                         "trials.csv and plots write it")
    doc = cls.doc or (inspect.getdoc(cls) or "").split("\n")[0]
    return {"name": name, "doc": doc, "parameters": _parameter_specs(cls)}


def _origin(cls) -> str:
    return f"python:{cls.__module__}.{cls.__qualname__}"


def _source_hash(cls) -> str:
    """SHA-256 of the source of cls and of its bases up to the package's, so a change to the
    class re-runs the trials a store holds for it. A class without retrievable source (typed
    at an interactive prompt) is keyed by its name and a per-process token: its results are
    reused only within the process."""
    digest = hashlib.sha256()
    for klass in cls.__mro__:
        if klass in (Kernel, Target, CentrePlacement, _Plugin, object):
            continue
        try:
            digest.update(inspect.getsource(klass).encode())
        except (OSError, TypeError):
            digest.update(f"{klass.__module__}.{klass.__qualname__}@{id(klass)}".encode())
    return digest.hexdigest()


_registered: dict = {}  # name -> class


def _register(register, cls, info: dict, make):
    """Registers `cls` through `register` (a _core function), first removing another class
    registered under the same name from Python (an edited class in a notebook replaces the
    old one)."""
    earlier = _registered.get(info["name"])
    if earlier is not None and earlier is not cls:
        _core.unregister(_origin(earlier))
    register(info, make, _origin(cls), _source_hash(cls))
    _registered[info["name"]] = cls
    return cls


def _domain(d: dict) -> Domain:
    return Domain(length=d["length"], periodic=d["periodic"], dimension=d["dimension"],
                  width=d["width"], height=d["height"])


def register_kernel(cls):
    """Registers the Kernel subclass `cls` under cls.name for this process (again after an
    edit: the new class replaces the old). Returns cls, so it also works as a decorator."""
    info = _info(cls, Kernel)

    def make(domain: dict, parameters: dict):
        return cls(_domain(domain), **parameters)

    return _register(_core.register_kernel, cls, info, make)


def register_target(cls):
    """Registers the Target subclass `cls` under cls.name for this process. Returns cls."""
    info = _info(cls, Target)

    def make(domain: dict, parameters: dict):
        return cls(_domain(domain), **parameters)

    return _register(_core.register_target, cls, info, make)


class _Placing:
    """The object the engine calls: place(n, domain dict, seed) on the user's placement."""

    def __init__(self, placement: CentrePlacement):
        self.placement = placement
        self.takes_seed = len(inspect.signature(placement.place).parameters) >= 3

    def place(self, n: int, domain: dict, seed: int):
        omega = _domain(domain)
        args = (n, omega, seed) if self.takes_seed else (n, omega)
        points = np.asarray(self.placement.place(*args), dtype=float)
        if points.ndim == 1 and omega.dimension == 1:
            points = points[:, None]
        if omega.dimension == 1 and points.ndim == 2 and points.shape[1] == 1:
            points = np.sort(points, axis=0)  # the engine's contract: increasing in d = 1
        return points


def register_centres(cls):
    """Registers the CentrePlacement subclass `cls` under cls.name for this process. Returns
    cls."""
    info = _info(cls, CentrePlacement)

    def make(parameters: dict):
        return _Placing(cls(None, **parameters))

    return _register(_core.register_centres, cls, info, make)


def unregister(cls) -> bool:
    """Removes what `cls` registered; False when it registered nothing."""
    removed = _core.unregister(_origin(cls))
    if removed:
        _registered.pop(getattr(cls, "name", None), None)
    return removed


@dataclass
class PluginVerification:
    """What `rkhs-study verify-plugin` checks of a kernel: the kernel contract on the track,
    the interval (and boxes and tori where the kernel is defined there), strict positive
    definiteness and the declared smoothness against the measured power-function decay."""

    passed: bool
    report: str

    def __bool__(self) -> bool:
        return self.passed

    def __str__(self) -> str:
        return self.report


def verify_plugin(kernel) -> PluginVerification:
    """Checks a kernel (a Kernel subclass, registered first if it is not, or the name of any
    registered kernel) with its default parameters, as `rkhs-study verify-plugin` does."""
    if isinstance(kernel, type):
        if _registered.get(getattr(kernel, "name", None)) is not kernel:
            register_kernel(kernel)
        name = kernel.name
    else:
        name = str(kernel)
    passed, report = _core.verify_kernel(name)
    return PluginVerification(passed=passed, report=report)


def kernel_matrix(name: str, X, Y, domain: Domain, **parameters) -> np.ndarray:
    """(m, n) k(x_i, y_j) of the registered kernel `name` (C++ or Python) with `parameters`
    (defaults for the others) on `domain`, computed as a trial computes a cross matrix."""
    X = np.ascontiguousarray(np.asarray(X, float).reshape(len(X), -1))
    Y = np.ascontiguousarray(np.asarray(Y, float).reshape(len(Y), -1))
    d = {"length": float(domain.length), "width": float(domain.width),
         "height": float(domain.height), "periodic": bool(domain.periodic),
         "dimension": int(domain.dimension)}
    return _core.kernel_matrix(name, parameters, d, X, Y)
