"""rkhs-study from Python (docs/python.md).

The command line's study, run and check, as thin bindings over the same C++ library
(rkhs_study._core, built from python/src/module.cpp):

    import rkhs_study
    study = rkhs_study.Study.load("studies/gram_and_power.toml")
    study.validate()                 # raises rkhs_study.StudyError "file:line:column: ..."
    grid = study.trials()            # the trial grid, nothing run: a pandas DataFrame
    results = study.run(threads=2)   # results.trials, results.rates: trials.csv, rates.csv
    rkhs_study.check(["studies/gram_and_power.toml"]).passed
"""

from __future__ import annotations

import io
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Optional, Union

import pandas as pd

from . import _core
from ._core import RunInterrupted, StudyError

__all__ = ["Study", "Validation", "Results", "CheckResult", "StudyError", "RunInterrupted",
           "check", "read_csv"]

PathLike = Union[str, "os.PathLike[str]"]


def read_csv(source) -> pd.DataFrame:
    """A CSV file rkhs-study wrote (trials.csv, rates.csv) as a DataFrame.

    Numbers are parsed to the nearest double (round trip: the files print the shortest text
    that reads back exactly), "inf" and "-inf" are infinities, and only an empty field is
    missing (NaN): a name such as "NA" stays text.
    """
    return pd.read_csv(source, float_precision="round_trip", keep_default_na=False,
                       na_values=[""])


@dataclass
class Validation:
    """What `rkhs-study validate` reports for a valid study."""

    source: str
    name: str
    kind: str
    axes: list            # (singular, plural, count) of each grid axis, n last
    trial_count: int
    warnings: list        # "file:line:column: key: why", valid but doubtful settings
    computed_metrics: list
    expectations: int
    tiers: list


@dataclass
class Results:
    """A finished run: the tables `rkhs-study run` writes, read back from `out`."""

    out: Optional[Path]   # the output folder; None when it was a temporary one, now removed
    trials: pd.DataFrame  # trials.csv
    rates: pd.DataFrame   # rates.csv
    failed: int           # trials whose status is failed
    seconds: float        # wall time of the run
    outcomes: list = field(default_factory=list)  # the expectations' verdicts (dicts)
    verification: str = ""  # the verdicts as `rkhs-study check` prints them
    warnings: list = field(default_factory=list)  # the study file's (validate's) warnings


@dataclass
class CheckResult:
    """What `rkhs-study check` decides: `passed` is its exit status 0."""

    exit_code: int        # 0 all pass, 1 a failure, 3 inconclusive, 5 nothing judged
    outcomes: list        # one dict per test case (expectation and group), every study
    studies: list         # per study: its name, trial counts, seconds and outcomes
    report: str           # the verdicts as the command prints them
    counts: str           # "11 passed, 0 failed, 0 inconclusive"

    @property
    def passed(self) -> bool:
        return self.exit_code == 0

    def __bool__(self) -> bool:
        return self.passed


class Study:
    """A study definition (a TOML file, docs/study-files.md), read when first needed.

    Study.load(path) and Study.from_toml(text) only keep the source; validate(), trials() and
    run() read it, and raise StudyError with the command line's message when it is not valid.
    """

    def __init__(self, *, path: Optional[PathLike] = None, text: Optional[str] = None,
                 source_name: str = "<string>"):
        if (path is None) == (text is None):
            raise ValueError("Study takes a path or a text, one of them")
        self._path = None if path is None else os.fspath(path)
        self._text = text
        self._source_name = source_name
        self._definition = None

    @classmethod
    def load(cls, path: PathLike) -> "Study":
        """The study in the file `path` (as `rkhs-study run PATH` reads it)."""
        return cls(path=path)

    @classmethod
    def from_toml(cls, text: str, source_name: str = "<string>") -> "Study":
        """The study in `text`; messages name `source_name` as they would a file."""
        return cls(text=text, source_name=source_name)

    def definition(self) -> "_core.StudyDefinition":
        """The parsed study (raises StudyError when it is not valid)."""
        if self._definition is None:
            if self._path is not None:
                self._definition = _core.load_study(self._path)
            else:
                self._definition = _core.parse_study(self._text, self._source_name)
        return self._definition

    @property
    def name(self) -> str:
        return self.definition().name

    def validate(self) -> Validation:
        """Checks the study as `rkhs-study validate` does; raises StudyError otherwise."""
        d = self.definition()
        axes = d.grid_axes()
        count = 1
        for _, _, n in axes:
            count *= n
        return Validation(source=d.source, name=d.name, kind=d.kind, axes=axes,
                          trial_count=count, warnings=list(d.warnings),
                          computed_metrics=list(d.computed_metrics),
                          expectations=d.expectation_count, tiers=list(d.tiers))

    def trials(self) -> pd.DataFrame:
        """The trial grid without running it: the axis columns of trials.csv and n."""
        return read_csv(io.StringIO(self.definition().grid_csv()))

    def run(self, threads: Optional[int] = None, out: Optional[PathLike] = None,
            store: Optional[PathLike] = None, fresh: bool = False) -> Results:
        """Runs every trial, as `rkhs-study run --out OUT --no-plots` does.

        threads: worker threads (None: all cores). out: the output folder that receives
        trials.csv, rates.csv, summary.json, rates.md, rates.tex and report.html (None: a
        temporary folder, removed once the tables are read). store: the result store (SQLite)
        to reuse and commit trials to (None: no store, as --no-store); fresh: run every trial
        again even when the store holds it.

        Ctrl-C stops the run as it stops the command (trials in flight are cancelled, finished
        ones are in the store) and raises RunInterrupted, a KeyboardInterrupt whose finished,
        stored, stopped and not_started count the trials; the same call again reuses them.
        """
        d = self.definition()
        if threads is not None and threads < 1:
            raise ValueError(f"threads must be at least 1, found {threads}")
        store_file = None if store is None else os.fspath(store)

        def run_into(folder: str) -> Results:
            summary = _core.run(d, folder, threads or 0, store_file, fresh)
            return Results(out=None if out is None else Path(folder),
                           trials=read_csv(os.path.join(folder, "trials.csv")),
                           rates=read_csv(os.path.join(folder, "rates.csv")),
                           failed=summary["failed"], seconds=summary["seconds"],
                           outcomes=summary["outcomes"],
                           verification=summary["verification"],
                           warnings=summary["warnings"])

        if out is not None:
            return run_into(os.fspath(out))
        with tempfile.TemporaryDirectory(prefix="rkhs-study-") as folder:
            return run_into(folder)

    def __repr__(self) -> str:
        where = self._path if self._path is not None else self._source_name
        return f"Study({where!r})"


def check(paths: Union[PathLike, Iterable[PathLike]], *, threads: Optional[int] = None,
          store: Optional[PathLike] = None, fresh: bool = False, tier: Optional[str] = None,
          strict: bool = False, allow_inconclusive: bool = False, k: Optional[str] = None,
          junit: Optional[PathLike] = None) -> CheckResult:
    """Runs each study and judges its [[expect]] tables, as `rkhs-study check` does.

    `passed` is the command's exit status 0: every verdict a pass (with strict, inconclusive
    verdicts and XPASS fail; with allow_inconclusive, inconclusive ones do not). k: judge only
    the test cases whose names match the expression, as `check -k` (a study with none selected
    is not run; none selected at all: exit_code 5). junit: write the JUnit XML report there, as
    `check --junit`. Ctrl-C raises RunInterrupted, as Study.run does.
    """
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    files = [os.fspath(p) for p in paths]
    result = _core.check(files, threads or 0, None if store is None else os.fspath(store),
                         fresh, tier or "", strict, allow_inconclusive, k or "",
                         "" if junit is None else os.fspath(junit))
    outcomes = [o for s in result["studies"] for o in s["outcomes"]]
    return CheckResult(exit_code=result["exit_code"], outcomes=outcomes,
                       studies=result["studies"], report=result["report"],
                       counts=result["counts"])
