"""rkhs-study from Python (docs/python.md).

The command line's study, run and check, as thin bindings over the same C++ library
(rkhs_study._core, built from python/src/module.cpp):

    import rkhs_study
    study = rkhs_study.Study.load("studies/gram_and_power.toml")
    study.validate()                 # raises rkhs_study.StudyError "file:line:column: ..."
    grid = study.trials()            # the trial grid, nothing run: a pandas DataFrame
    results = study.run(threads=2)   # results.trials, results.rates: trials.csv, rates.csv
    results.report("results/x")      # the command's whole output folder, plots included
    rkhs_study.check(["studies/gram_and_power.toml"]).passed

and around them: Study.from_dict (a study as a dict of its tables, written as TOML by to_toml),
Results.provenance and .verdicts (summary.json's), Results.plot (matplotlib, imported when
drawing), the command's gnuplot plots (Study.run(out=..., plots=True), Results.report), its
progress display (Study.run(progress=True)) and the HTML that Jupyter shows for Results,
CheckResult and Validation.
"""

from __future__ import annotations

import base64
import datetime
import html
import io
import json
import math
import numbers
import os
import re
import sys
import tempfile
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Optional, Union

import numpy as np
import pandas as pd

from . import _core
from ._core import RunInterrupted, StudyError
from .plugins import (CentrePlacement, Domain, Kernel, Parameter, PluginVerification, Target,
                      kernel_matrix, register_centres, register_kernel, register_target,
                      unregister, verify_plugin)

__all__ = ["Study", "Validation", "Results", "CheckResult", "StudyError", "RunInterrupted",
           "check", "read_csv", "to_toml", "Parameter", "Domain", "Kernel", "Target",
           "CentrePlacement", "register_kernel", "register_target", "register_centres",
           "unregister", "verify_plugin", "PluginVerification", "kernel_matrix"]

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

    def _repr_html_(self) -> str:
        """Jupyter's view: the grid's axes and their product, the warnings."""
        rows = [(plural, count) for _, plural, count in self.axes]
        grid = "".join(f"<tr><td>{_e(plural)}</td><td>{count}</td></tr>" for plural, count in rows)
        grid += f"<tr><th>trials</th><th>{self.trial_count}</th></tr>"
        parts = [f"<h4>{_e(self.name)}: valid {_e(self.kind)} study</h4>",
                 f"<p>{_e(self.source)}; {self.expectations} expectation"
                 f"{'' if self.expectations == 1 else 's'}"
                 + (f", tiers {_e(', '.join(self.tiers))}" if self.tiers else "") + "</p>",
                 '<table class="rkhs-grid"><thead><tr><th>axis</th><th>values</th></tr></thead>'
                 f"<tbody>{grid}</tbody></table>",
                 f"<p>metrics computed: {_e(', '.join(self.computed_metrics))}</p>"]
        if self.warnings:
            parts.append("<ul>" + "".join(f"<li>{_e(w)}</li>" for w in self.warnings) + "</ul>")
        return "\n".join(parts)


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
    ran: int = 0          # trials computed by this run
    reused: int = 0       # trials read back from the result store
    study: str = ""       # the study's name
    provenance: dict = field(default_factory=dict)  # summary.json's: version, commit, threads...
    plots: list = field(default_factory=list)  # the plots rendered into out/plots (file stems)
    # The run itself (_core.FinishedRun), kept for report(): the record the run wrote from.
    _finished: object = field(default=None, repr=False, compare=False)

    def report(self, out: PathLike, plots: bool = True) -> Path:
        """Writes the run's whole output folder into `out`, as `rkhs-study run --out OUT` does.

        trials.csv, rates.csv, summary.json, rates.md, rates.tex, report.html (and the adaptive
        files), and with `plots` the gnuplot plots in out/plots (SVG, PNG, PDF and their
        scripts), written by the command's own writers from the record of this run (kept in
        memory), so the tables are byte for byte those the run wrote; nothing is run again.
        Works for a run into a temporary folder (out=None) as well. Returns `out` as a Path.
        A plot gnuplot could not render is a RuntimeWarning naming it, as the command warns.
        """
        if self._finished is None:
            raise ValueError("report() needs the Results of Study.run: this one holds no run")
        folder = Path(out)
        written = _core.report(self._finished, os.fspath(folder), bool(plots))
        _warn_plot_failures(written)
        return folder

    @property
    def verdicts(self) -> pd.DataFrame:
        """The expectations' verdicts, one row per outcome (the dicts of `outcomes`)."""
        return _verdict_frame(self.outcomes)

    def plot(self, metric: Optional[str] = None, ax=None):
        """The convergence plot of `metric` with matplotlib: the metric against n, log-log.

        One line per group of trials (every axis column but n, as rates.csv groups them),
        labelled with the axis values that tell the groups apart and the fitted rate of
        `rates` with its 95% confidence interval. metric None: the first error metric (the
        order of the command's plots). ax: the matplotlib Axes to draw into (None: a new
        figure of matplotlib.pyplot). Returns the Axes (its figure: `.figure`).
        """
        if ax is None:
            import matplotlib.pyplot as plt
            _, ax = plt.subplots(figsize=(6.4, 4.4))
        metric = metric or self._default_metric()
        if metric not in self.trials.columns:
            raise ValueError(f"no metric {metric!r} in trials (metrics: "
                             f"{', '.join(_metrics(self.rates))})")
        groups = _group_columns(self.rates)
        labels = _group_labels(self.trials, groups)
        fits = self.rates[(self.rates["metric"] == metric) & (self.rates["kind"] == "fit")]
        for key, rows in _by_group(self.trials, groups):
            fit = _matching(fits, groups, key)
            label = labels[key]
            rate = _rate_text(fit.iloc[0]) if len(fit) else "no rate"
            ax.plot(rows["n"].to_numpy(), rows[metric].to_numpy(), marker="o", markersize=3,
                    label=f"{label}: {rate}" if label else rate)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("n")
        ax.set_ylabel(metric)
        ax.set_title(f"{self.study}: {metric}" if self.study else metric)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize="small")
        return ax

    def _default_metric(self) -> str:
        metrics = _metrics(self.rates)
        if not metrics:
            raise ValueError("no metric to plot: rates is empty")
        rank = lambda m: (0 if "error" in m else
                          2 if m in ("fill_distance", "separation_distance") else 1)
        return sorted(metrics, key=rank)[0]  # stable: convergence_plot_order (plots.cpp)

    def rates_table(self) -> pd.DataFrame:
        """The fitted rates, one row per group and metric (rates' rows of kind "fit")."""
        groups = _group_columns(self.rates)
        fits = self.rates[self.rates["kind"] == "fit"]
        labels = _group_labels(fits, groups)
        table = pd.DataFrame({
            "group": [labels[k] for k in _keys(fits, groups)],
            **{c: fits[c] for c in ("metric", "model", "n_from", "n_to", "rate", "ci_low",
                                     "ci_high", "value") if c in fits.columns}})
        return table.reset_index(drop=True)

    def _repr_html_(self) -> str:
        """Jupyter's view: the run's counts, its verdicts, the fitted rates, a plot."""
        parts = [f"<h4>{_e(self.study or 'study')}: {len(self.trials)} trials, "
                 f"{self.failed} failed, {self.seconds:.3g} s</h4>"]
        if self.outcomes:
            parts.append(f"<p>expectations: {_e(_count_outcomes(self.outcomes))}</p>")
        if self.out is not None:
            parts.append(f"<p>output: {_e(os.fspath(self.out))}</p>")
        if len(self.rates):
            parts.append(self.rates_table().to_html(index=False, na_rep="",
                                                    float_format=_number,
                                                    classes="rkhs-rates"))
            image = self._png()
            if image:
                parts.append(f'<img src="data:image/png;base64,{image}" '
                             'alt="convergence plot"/>')
        return "\n".join(parts)

    def _png(self) -> str:
        """The convergence plot of the first error metric as base64 PNG ("" without matplotlib)."""
        try:
            from matplotlib.figure import Figure
        except ImportError:
            return ""
        figure = Figure(figsize=(6.4, 4.4), dpi=100)
        self.plot(ax=figure.add_subplot())
        figure.tight_layout()
        buffer = io.BytesIO()
        figure.savefig(buffer, format="png")
        return base64.b64encode(buffer.getvalue()).decode("ascii")


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

    def _repr_html_(self) -> str:
        """Jupyter's view: passed or not, the verdict counts, a row per outcome."""
        head = (f"<h4>check {'passed' if self.passed else 'did not pass'} "
                f"(exit {self.exit_code}): {_e(self.counts)}</h4>")
        columns = ["study", "name", "outcome", "summary", "location"]
        frame = self.verdicts
        table = frame[[c for c in columns if c in frame.columns]].to_html(
            index=False, na_rep="", classes="rkhs-verdicts")
        return head + "\n" + table


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
            store: Optional[PathLike] = None, fresh: bool = False,
            plots: Optional[bool] = None, progress: bool = False) -> Results:
        """Runs every trial, as `rkhs-study run --out OUT` does.

        threads: worker threads (None: all cores). out: the output folder that receives
        trials.csv, rates.csv, summary.json, rates.md, rates.tex, report.html and the plots
        (None: a temporary folder, removed once the tables are read). store: the result store
        (SQLite) to reuse and commit trials to (None: no store, as --no-store); fresh: run every
        trial again even when the store holds it.

        plots: render the command's gnuplot plots into out/plots (SVG, PNG, PDF), embedded in
        report.html. None (the default): as the command, plots whenever there is an `out` (the
        command always has one); False is --no-plots. plots=True without `out` is an error
        (they would be removed with the temporary folder): use results.report(folder) instead.
        A plot gnuplot could not render is a RuntimeWarning, as the command warns.

        progress: show the command's progress display on sys.stderr while the trials run:
        trials done of those to run, failures, elapsed time, ETA and the trials in flight. On a
        terminal or in Jupyter one line redrawn in place ("\\r"), elsewhere a line every few
        seconds; each failed trial on a line of its own. Nothing when the store holds every
        trial.

        Ctrl-C stops the run as it stops the command (trials in flight are cancelled, finished
        ones are in the store) and raises RunInterrupted, a KeyboardInterrupt whose finished,
        stored, stopped and not_started count the trials; the same call again reuses them.
        """
        d = self.definition()
        if threads is not None and threads < 1:
            raise ValueError(f"threads must be at least 1, found {threads}")
        if plots is None:
            plots = out is not None
        elif plots and out is None:
            raise ValueError("plots=True needs an output folder (out=...): without one the plots "
                             "would be removed with the temporary folder; "
                             "results.report(folder) writes them later")
        store_file = None if store is None else os.fspath(store)
        progress_mode = (2 if _progress_redraws() else 1) if progress else 0

        def run_into(folder: str) -> Results:
            summary = _core.run(d, folder, threads or 0, store_file, fresh, bool(plots),
                                progress_mode)
            _warn_plot_failures(summary["plots"])
            return Results(out=None if out is None else Path(folder),
                           trials=read_csv(os.path.join(folder, "trials.csv")),
                           rates=read_csv(os.path.join(folder, "rates.csv")),
                           failed=summary["failed"], seconds=summary["seconds"],
                           outcomes=summary["outcomes"],
                           verification=summary["verification"],
                           warnings=summary["warnings"], ran=summary["ran"],
                           reused=summary["reused"], study=summary["study"],
                           provenance=_read_provenance(folder),
                           plots=list(summary["plots"]["rendered"]),
                           _finished=summary["finished"])

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


# ---------------------------------------------------------------------------------------------
# Helpers of Results, CheckResult and Validation

def _progress_redraws() -> bool:
    """Whether the progress line is redrawn in place ("\\r"): on a terminal and in Jupyter
    (whose output area honours a carriage return); elsewhere (a log, a pipe) lines are written."""
    if "ipykernel" in sys.modules:
        return True
    try:
        return sys.stderr is not None and sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def _warn_plot_failures(plots: dict) -> None:
    """The command's "warning: plot not rendered: ..." as RuntimeWarnings."""
    for failure in plots["failures"]:
        warnings.warn(f"plot not rendered: {failure}", RuntimeWarning, stacklevel=3)


def _read_provenance(folder: str) -> dict:
    """summary.json's provenance (version, git_commit, compiler, threads, started, ...)."""
    with open(os.path.join(folder, "summary.json"), encoding="utf-8") as f:
        return json.load(f).get("provenance", {})


# The keys of the module's outcome dicts, in their order (rkhs::outcome_fields, summary.json's
# order): the columns of an empty verdict frame.
_OUTCOME_FIELDS = ["study", "name", "metric", "location", "group", "group_label", "verdict",
                   "outcome", "xfail", "summary", "rate", "ci_low", "ci_high", "accepted_low",
                   "accepted_high", "effectivity_min", "effectivity_max", "expected", "found",
                   "reason", "advice", "seconds"]


def _verdict_frame(outcomes: list) -> pd.DataFrame:
    if not outcomes:
        return pd.DataFrame(columns=_OUTCOME_FIELDS)
    return pd.DataFrame.from_records(outcomes)


def _count_outcomes(outcomes: list) -> str:
    counts = {}
    for o in outcomes:
        counts[o["outcome"]] = counts.get(o["outcome"], 0) + 1
    return ", ".join(f"{n} {outcome}" for outcome, n in counts.items())


def _e(text) -> str:
    return html.escape(str(text))


def _number(x: float) -> str:
    return f"{x:.4g}"


def _metrics(rates: pd.DataFrame) -> list:
    return list(dict.fromkeys(rates["metric"])) if "metric" in rates.columns else []


def _group_columns(rates: pd.DataFrame) -> list:
    """The axis columns of rates.csv: every column before "metric"."""
    columns = list(rates.columns)
    return columns[:columns.index("metric")] if "metric" in columns else []


def _key_value(value):
    return None if isinstance(value, float) and math.isnan(value) else value


def _keys(frame: pd.DataFrame, columns: list) -> list:
    return [tuple(_key_value(v) for v in row)
            for row in frame[columns].itertuples(index=False, name=None)]


def _by_group(trials: pd.DataFrame, columns: list):
    """(key, rows) per group of trials, in the order of their first trial (NaN as a value)."""
    keys = _keys(trials, columns)
    order = list(dict.fromkeys(keys))
    positions = {}
    for i, key in enumerate(keys):
        positions.setdefault(key, []).append(i)
    for key in order:
        yield key, trials.iloc[positions[key]]


def _matching(frame: pd.DataFrame, columns: list, key: tuple) -> pd.DataFrame:
    keys = _keys(frame, columns)
    return frame.iloc[[i for i, k in enumerate(keys) if k == key]]


_PLUGIN_AXES = ("kernel", "target", "centres", "projection", "plant", "law", "integrator")


def _text(value) -> str:
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return str(value)


def _group_labels(frame: pd.DataFrame, columns: list) -> dict:
    """A short label per group: the axis values that tell the groups apart.

    A plugin's name (kernel, target, ...) when it varies; a parameter (its column after its
    plugin's, the plugin's prefix dropped: target_amplitude is amplitude) as name=value when it
    varies among the groups of the same plugin name.
    """
    keys = list(dict.fromkeys(_keys(frame, columns)))
    owner = []  # the plugin-name column each column belongs to (-1: its own)
    current = -1
    for i, c in enumerate(columns):
        if c in _PLUGIN_AXES:
            current = i
            owner.append(i)
        else:
            owner.append(current if c != "laps" else i)
    shown = []
    for i, c in enumerate(columns):
        if owner[i] == i:
            shown.append(len({k[i] for k in keys}) > 1)
        else:
            values = {}
            for k in keys:
                values.setdefault(k[owner[i]], set()).add(k[i])
            shown.append(any(len(v) > 1 for v in values.values()))
    labels = {}
    for key in keys:
        parts = []
        for i, c in enumerate(columns):
            if not shown[i] or key[i] is None:
                continue
            if c in _PLUGIN_AXES:
                parts.append(_text(key[i]))
            else:
                name = c
                if owner[i] >= 0 and c.startswith(columns[owner[i]] + "_"):
                    name = c[len(columns[owner[i]]) + 1:]
                parts.append(f"{name}={_text(key[i])}")
        labels[key] = " ".join(parts)
    return labels


def _rate_text(fit) -> str:
    """The fitted rate of a rates.csv row: "rate -2.01 [-2.05, -1.97]" (the 95% CI)."""
    model = fit.get("model", "power_law")
    if model == "constant":
        return f"constant {_number(fit['value'])}"
    if not math.isfinite(fit["rate"]):
        return "no rate"
    name = "exponential rate" if model == "exponential" else "rate"
    if fit.get("abscissa", "n") == "h":
        name += " (against h)"
    interval = ""
    if math.isfinite(fit["ci_low"]) and math.isfinite(fit["ci_high"]):
        interval = f" [{fit['ci_low']:.3g}, {fit['ci_high']:.3g}]"
    return f"{name} {fit['rate']:.3g}{interval}"
