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

import datetime
import io
import json
import math
import numbers
import os
import re
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Optional, Union

import numpy as np
import pandas as pd

from . import _core
from ._core import StudyError

__all__ = ["Study", "Validation", "Results", "CheckResult", "StudyError", "check", "read_csv",
           "to_toml"]

PathLike = Union[str, "os.PathLike[str]"]


def read_csv(source) -> pd.DataFrame:
    """A CSV file rkhs-study wrote (trials.csv, rates.csv) as a DataFrame.

    Numbers are parsed to the nearest double (round trip: the files print the shortest text
    that reads back exactly), "inf" and "-inf" are infinities, and only an empty field is
    missing (NaN): a name such as "NA" stays text.
    """
    return pd.read_csv(source, float_precision="round_trip", keep_default_na=False,
                       na_values=[""])


# ---------------------------------------------------------------------------------------------
# A study given as a Python dict, written as TOML text (Study.from_dict)

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+\Z")
_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f",
            "\r": "\\r"}


def _toml_string(text: str) -> str:
    """A TOML basic string: quotes, backslashes and control characters escaped."""
    out = []
    for c in text:
        if c in _ESCAPES:
            out.append(_ESCAPES[c])
        elif ord(c) < 0x20 or ord(c) == 0x7F:
            out.append(f"\\u{ord(c):04X}")
        else:
            out.append(c)
    return '"' + "".join(out) + '"'


def _toml_key(key, where: str) -> str:
    if not isinstance(key, str):
        raise TypeError(f"{where}: a key must be a string, found {key!r}")
    return key if _BARE_KEY.match(key) else _toml_string(key)


def _is_table(value) -> bool:
    return isinstance(value, Mapping)


def _is_array_of_tables(value) -> bool:
    return (isinstance(value, (list, tuple)) and len(value) > 0
            and all(_is_table(v) for v in value))


def _toml_value(value, where: str) -> str:
    """One value as TOML text on one line (tables and arrays inline)."""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        value = int(value)
        if not -2**63 <= value < 2**63:
            raise ValueError(f"{where}: {value} is beyond TOML's 64-bit integers")
        return str(value)
    if isinstance(value, numbers.Real):
        value = float(value)
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)  # the shortest text that reads back as the same double
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, (datetime.datetime, datetime.date, datetime.time)):
        return value.isoformat()
    if _is_table(value):
        items = [f"{_toml_key(k, where)} = {_toml_value(v, f'{where}.{k}')}"
                 for k, v in value.items()]
        return "{ " + ", ".join(items) + " }" if items else "{}"
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(v, f"{where}[{i}]")
                               for i, v in enumerate(value)) + "]"
    raise TypeError(f"{where}: {type(value).__name__} {value!r} has no TOML form "
                    "(strings, numbers, booleans, dates, lists and dicts do)")


def _table_lines(table: Mapping, where: str) -> list:
    return [f"{_toml_key(k, where)} = {_toml_value(v, f'{where}.{k}' if where else str(k))}"
            for k, v in table.items()]


def to_toml(study: Mapping) -> str:
    """A study dict (the tables of a study file) as TOML text that reads back as the same dict.

    The top level's dicts are tables ([study]), its lists of dicts arrays of tables ([[kernel]]);
    everything inside them is written inline (n = { from = 10, to = 100 }, degree = [1, 2]).
    Keys of the top level that are values come first, as TOML requires. Floats are written with
    repr (read back to the same double), strings as basic strings with TOML's escapes.
    """
    if not _is_table(study):
        raise TypeError(f"a study is a dict of tables, found {type(study).__name__}")
    values = {k: v for k, v in study.items() if not (_is_table(v) or _is_array_of_tables(v))}
    lines = _table_lines(values, "")
    for key, value in study.items():
        if key in values:
            continue
        header = _toml_key(key, str(key))
        if _is_table(value):
            if lines:
                lines.append("")
            lines.append(f"[{header}]")
            lines += _table_lines(value, str(key))
        else:
            for i, entry in enumerate(value):
                if lines:
                    lines.append("")
                lines.append(f"[[{header}]]")
                lines += _table_lines(entry, f"{key}[{i}]")
    return "\n".join(lines) + "\n"


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
    study: str = ""       # the study's name
    provenance: dict = field(default_factory=dict)  # summary.json's: version, commit, threads...

    @property
    def verdicts(self) -> pd.DataFrame:
        """The expectations' verdicts, one row per outcome (the dicts of `outcomes`)."""
        return _verdict_frame(self.outcomes)


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

    @property
    def verdicts(self) -> pd.DataFrame:
        """The verdicts of every study, one row per outcome (the dicts of `outcomes`)."""
        return _verdict_frame(self.outcomes)


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

    @classmethod
    def from_dict(cls, study: Mapping, source_name: str = "<dict>") -> "Study":
        """The study given as a dict of the study file's tables, written as TOML (to_toml).

        Nested dicts are tables and lists of dicts arrays of tables: the dict tomllib reads from
        a study file gives the same study. Errors are the StudyError messages of from_toml,
        naming `source_name` and a line and column of the generated text, `toml_text`.
        """
        try:
            text = to_toml(study)
        except (TypeError, ValueError) as error:
            raise StudyError(f"{source_name}: {error}") from None
        return cls(text=text, source_name=source_name)

    @property
    def toml_text(self) -> Optional[str]:
        """The TOML text of from_toml and from_dict (None for a file): what messages point at."""
        return self._text

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
                           warnings=summary["warnings"], study=summary["study"],
                           provenance=_read_provenance(folder))

        if out is not None:
            return run_into(os.fspath(out))
        with tempfile.TemporaryDirectory(prefix="rkhs-study-") as folder:
            return run_into(folder)

    def __repr__(self) -> str:
        where = self._path if self._path is not None else self._source_name
        return f"Study({where!r})"


def check(paths: Union[PathLike, Iterable[PathLike]], *, threads: Optional[int] = None,
          store: Optional[PathLike] = None, fresh: bool = False, tier: Optional[str] = None,
          strict: bool = False, allow_inconclusive: bool = False) -> CheckResult:
    """Runs each study and judges its [[expect]] tables, as `rkhs-study check` does.

    `passed` is the command's exit status 0: every verdict a pass (with strict, inconclusive
    verdicts and XPASS fail; with allow_inconclusive, inconclusive ones do not).
    """
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    files = [os.fspath(p) for p in paths]
    result = _core.check(files, threads or 0, None if store is None else os.fspath(store),
                         fresh, tier or "", strict, allow_inconclusive)
    outcomes = [o for s in result["studies"] for o in s["outcomes"]]
    return CheckResult(exit_code=result["exit_code"], outcomes=outcomes,
                       studies=result["studies"], report=result["report"],
                       counts=result["counts"])


# ---------------------------------------------------------------------------------------------
# Helpers of Results, CheckResult and Validation

def _read_provenance(folder: str) -> dict:
    """summary.json's provenance (version, git_commit, compiler, threads, started, ...)."""
    with open(os.path.join(folder, "summary.json"), encoding="utf-8") as f:
        return json.load(f).get("provenance", {})


_OUTCOME_FIELDS = ["study", "name", "outcome", "verdict", "metric", "location", "group",
                   "group_label", "expected", "found", "reason", "advice", "xfail", "summary",
                   "rate", "ci_low", "ci_high", "accepted_low", "accepted_high",
                   "effectivity_min", "effectivity_max", "seconds"]


def _verdict_frame(outcomes: list) -> pd.DataFrame:
    if not outcomes:
        return pd.DataFrame(columns=_OUTCOME_FIELDS)
    return pd.DataFrame.from_records(outcomes)

