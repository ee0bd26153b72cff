"""The Python package rkhs_study (docs/python.md) against the rkhs-study command.

Run by ctest (python.rkhs_study, tests/CMakeLists.txt) as
    PYTHONPATH=<build>/python /usr/bin/python3 -m pytest tests/python
with RKHS_STUDY_EXECUTABLE (the command), RKHS_STUDY_SOURCE_DIR (this tree) and
RKHS_STUDY_BINARY_DIR (the build, for the installed-package test) set.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

import rkhs_study

SOURCE_DIR = Path(os.environ.get("RKHS_STUDY_SOURCE_DIR", Path(__file__).resolve().parents[2]))
EXECUTABLE = os.environ.get("RKHS_STUDY_EXECUTABLE",
                            str(SOURCE_DIR / "build" / "release" / "rkhs-study"))
STUDY = SOURCE_DIR / "studies" / "gram_and_power.toml"


def cli(*arguments, check=True):
    return subprocess.run([EXECUTABLE, *map(str, arguments)], capture_output=True, text=True,
                          check=check, cwd=SOURCE_DIR)


@pytest.fixture(scope="module")
def cli_out(tmp_path_factory):
    """What `rkhs-study run STUDY --out DIR --no-store` writes (without plots)."""
    out = tmp_path_factory.mktemp("cli")
    cli("run", STUDY, "--out", out, "--no-store", "--no-plots", "--quiet")
    return out


def assert_frames_identical(found: pd.DataFrame, expected: pd.DataFrame):
    """Same columns, dtypes and values, every double to the last bit (NaN where NaN)."""
    assert list(found.columns) == list(expected.columns)
    assert found.dtypes.to_dict() == expected.dtypes.to_dict()
    assert found.shape == expected.shape
    for column in expected.columns:
        a, b = found[column], expected[column]
        if pd.api.types.is_float_dtype(b):
            both_nan = a.isna() & b.isna()
            # equal as doubles, and with the same sign of zero: the bits agree
            assert ((a == b) | both_nan).all(), column
            assert [repr(x) for x in a] == [repr(x) for x in b], column
        else:
            assert a.tolist() == b.tolist(), column


def test_run_into_a_folder_writes_the_commands_files(cli_out, tmp_path):
    results = rkhs_study.Study.load(STUDY).run(threads=1, out=tmp_path / "py")
    assert results.out == tmp_path / "py"
    assert results.failed == 0
    for name in ("trials.csv", "rates.csv", "rates.md", "rates.tex"):
        assert (tmp_path / "py" / name).read_bytes() == (cli_out / name).read_bytes(), name
    assert (tmp_path / "py" / "summary.json").is_file()
    assert (tmp_path / "py" / "report.html").is_file()
    assert not (tmp_path / "py" / "INCOMPLETE").exists()


def test_run_returns_the_commands_tables(cli_out):
    results = rkhs_study.Study.load(STUDY).run()  # a temporary folder, all cores
    assert results.out is None
    expected_trials = rkhs_study.read_csv(cli_out / "trials.csv")
    expected_rates = rkhs_study.read_csv(cli_out / "rates.csv")
    assert len(results.trials) == 30
    assert_frames_identical(results.trials, expected_trials)
    assert_frames_identical(results.rates, expected_rates)
    # The same through pandas' own reader with round-trip parsing.
    assert results.trials.equals(pd.read_csv(cli_out / "trials.csv", float_precision="round_trip"))
    # and the verdicts the command prints
    assert [o["outcome"] for o in results.outcomes] == ["passed"] * 11


def test_from_toml_runs_the_same_study(cli_out):
    text = STUDY.read_text()
    results = rkhs_study.Study.from_toml(text, source_name=str(STUDY)).run(threads=2)
    assert_frames_identical(results.trials, rkhs_study.read_csv(cli_out / "trials.csv"))


def test_trials_is_the_grid_without_running(cli_out):
    study = rkhs_study.Study.load(STUDY)
    grid = study.trials()
    ran = rkhs_study.read_csv(cli_out / "trials.csv")
    assert list(grid.columns)[-1] == "n"
    assert_frames_identical(grid, ran[list(grid.columns)])
    assert grid["n"].tolist() == list(range(10, 101, 10)) * 3
    assert study.validate().trial_count == len(grid) == 30


def test_validate_reports_what_the_command_counts():
    validation = rkhs_study.Study.load(STUDY).validate()
    assert validation.name == "gram_and_power"
    assert validation.kind == "approximation"
    assert [(singular, count) for singular, _, count in validation.axes] == [
        ("kernel", 3), ("target", 1), ("centre placement", 1), ("value of n", 10)]
    assert validation.warnings == []
    out = cli("validate", STUDY).stdout
    assert f"= {validation.trial_count} trials" in out


BAD_STUDY = STUDY.read_text().replace('abscissa = "n"', 'abscissa = "m"', 1)


def test_validation_error_is_the_commands_message(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(BAD_STUDY)
    with pytest.raises(rkhs_study.StudyError) as error:
        rkhs_study.Study.load(bad).validate()
    message = str(error.value)
    assert re.match(re.escape(str(bad)) + r":\d+:\d+: study\.abscissa: ", message), message
    command = cli("validate", bad, check=False)
    assert command.returncode == 2
    assert command.stderr.strip() == message
    # A StudyError is a ValueError; run() and trials() raise it too.
    with pytest.raises(ValueError):
        rkhs_study.Study.load(bad).trials()


def test_validation_error_from_text_names_the_source():
    with pytest.raises(rkhs_study.StudyError, match=r"^mine\.toml:\d+:\d+: study\.abscissa: "):
        rkhs_study.Study.from_toml(BAD_STUDY, source_name="mine.toml").validate()


def test_missing_file_is_an_error(tmp_path):
    with pytest.raises(Exception, match=re.escape(str(tmp_path / "none.toml"))):
        rkhs_study.Study.load(tmp_path / "none.toml").validate()


def test_check_of_a_passing_study_passes():
    result = rkhs_study.check([STUDY], threads=2)
    assert result.passed and result
    assert result.exit_code == 0
    assert len(result.outcomes) == 11
    assert {o["outcome"] for o in result.outcomes} == {"passed"}
    assert all(o["location"].startswith(f"{STUDY}:") for o in result.outcomes)
    assert result.counts.startswith("11 passed, 0 failed, 0 inconclusive")
    command = cli("check", STUDY, "--no-store", "--quiet", check=False)
    assert command.returncode == result.exit_code


def test_check_with_a_store_reuses_the_trials(tmp_path):
    store = tmp_path / "store.sqlite"
    first = rkhs_study.check(STUDY, store=store, tier="quick")
    second = rkhs_study.check(STUDY, store=store, tier="quick")
    assert first.passed and second.passed
    assert first.studies[0]["ran"] == first.studies[0]["trials"] > 0
    assert second.studies[0]["reused"] == second.studies[0]["trials"]
    assert second.studies[0]["ran"] == 0


@pytest.mark.skipif("RKHS_STUDY_BINARY_DIR" not in os.environ,
                    reason="needs the build folder (RKHS_STUDY_BINARY_DIR)")
def test_installed_package_imports_and_runs(tmp_path, cli_out):
    prefix = tmp_path / "prefix"
    subprocess.run(["cmake", "--install", os.environ["RKHS_STUDY_BINARY_DIR"], "--prefix",
                    str(prefix)], check=True, capture_output=True)
    package = prefix / "lib" / "python3" / "dist-packages"
    assert (package / "rkhs_study" / "__init__.py").is_file()
    script = (
        "import sys, rkhs_study\n"
        "assert rkhs_study.__file__.startswith(sys.argv[1]), rkhs_study.__file__\n"
        "r = rkhs_study.Study.load(sys.argv[2]).run(threads=1)\n"
        "r.trials.to_csv(sys.argv[3], index=False)\n")
    environment = dict(os.environ, PYTHONPATH=str(package))
    subprocess.run([sys.executable, "-c", script, str(package), str(STUDY),
                    str(tmp_path / "t.csv")], check=True, env=environment, cwd=tmp_path)
    assert len(pd.read_csv(tmp_path / "t.csv")) == 30


def test_run_releases_the_gil(tmp_path):
    """Another Python thread goes on while the trials run."""
    import threading
    import time

    definition = rkhs_study.Study.load(STUDY).definition()
    ticks, stop = [], threading.Event()

    def tick():
        while not stop.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.001)

    thread = threading.Thread(target=tick)
    thread.start()
    try:
        start = time.monotonic()
        rkhs_study._core.run(definition, str(tmp_path), 1, None, False)
        end = time.monotonic()
    finally:
        stop.set()
        thread.join()
    inside = [t for t in ticks if start + 0.02 < t < end - 0.02]
    assert end - start > 0.1 and len(inside) > 10, (end - start, len(inside))


# Study.from_dict: a study as a dict of the study file's tables, written as TOML.

def study_dict():
    import tomllib
    with open(STUDY, "rb") as f:
        return tomllib.load(f)


def test_from_dict_is_the_same_study_as_the_file(cli_out):
    study = rkhs_study.Study.from_dict(study_dict())
    assert repr(study) == "Study('<dict>')"
    assert_frames_identical(study.trials(), rkhs_study.Study.load(STUDY).trials())
    results = study.run(threads=2)
    assert_frames_identical(results.trials, rkhs_study.read_csv(cli_out / "trials.csv"))
    assert_frames_identical(results.rates, rkhs_study.read_csv(cli_out / "rates.csv"))
    assert [o["outcome"] for o in results.outcomes] == ["passed"] * 11


def test_from_dict_text_reads_back_as_the_dict():
    import tomllib
    d = study_dict()
    text = rkhs_study.Study.from_dict(d).toml_text
    assert tomllib.loads(text) == d
    assert "[[kernel]]" in text and "n = { from = 10, to = 100, step = 10 }" in text
    # a file's Study has no text of its own; from_toml keeps its text
    assert rkhs_study.Study.load(STUDY).toml_text is None
    assert rkhs_study.Study.from_toml("x = 1\n").toml_text == "x = 1\n"


def test_to_toml_writes_every_value_so_that_it_reads_back():
    import datetime
    import math
    import tomllib
    import numpy as np
    d = {
        "plugins": ["a.so", "b c.so"],
        "top": 1,
        "t": {
            "quote": 'say "hi" \\ there',
            "controls": "tab\there\nline\r\b\f\x00\x1f\x7f end",
            "unicode": "Π_n ε ü",
            "floats": [0.1, 1e-300, 5e-324, 1.7976931348623157e308, -0.0, 1 / 3, 1e16, 2.5],
            "special": [math.inf, -math.inf],
            "ints": [0, -1, 2**63 - 1, -2**63],
            "bools": [True, False],
            "numpy": [np.float64(0.1), np.int64(7), np.bool_(True)],
            "mixed": [1, "two", 3.0],
            "empty": [],
            "nested": {"a": {"b": [1, 2]}, "c": "d"},
            "tables": [{"x": 1}, {"y": [2.5]}],
            "odd key": 1, "": 2, "dotted.key": 3,
            "when": datetime.date(2024, 1, 2),
        },
        "arr": [{"name": "a", "p": [1, 2], "sub": {"q": 1.5}}, {"name": "b"}],
        "empty_table": {},
    }
    text = rkhs_study.to_toml(d)
    back = tomllib.loads(text)
    expected = dict(d)
    expected["t"] = dict(d["t"], numpy=[0.1, 7, True])
    assert back == expected
    floats = back["t"]["floats"]
    assert [repr(x) for x in floats] == [repr(x) for x in d["t"]["floats"]]
    assert math.copysign(1, floats[4]) == -1
    assert math.isnan(tomllib.loads(rkhs_study.to_toml({"x": math.nan}))["x"])
    # the top level's values come before its first table
    assert text.index("top = 1") < text.index("[t]")


def test_to_toml_refuses_what_toml_cannot_hold():
    with pytest.raises(TypeError, match=r"t\.x: NoneType None has no TOML form"):
        rkhs_study.to_toml({"t": {"x": None}})
    with pytest.raises(ValueError, match=r"t\.x: 9223372036854775808 is beyond"):
        rkhs_study.to_toml({"t": {"x": 2**63}})
    with pytest.raises(TypeError, match="a study is a dict"):
        rkhs_study.to_toml([1])


def test_from_dict_error_names_the_dict_the_key_and_the_generated_text():
    d = study_dict()
    d["study"]["abscissa"] = "m"
    study = rkhs_study.Study.from_dict(d)
    with pytest.raises(rkhs_study.StudyError) as error:
        study.validate()
    message = str(error.value)
    found = re.match(r"<dict>:(\d+):(\d+): study\.abscissa: ", message)
    assert found, message
    line = study.toml_text.splitlines()[int(found.group(1)) - 1]
    assert line[int(found.group(2)) - 1:] == '"m"', line
    with pytest.raises(rkhs_study.StudyError, match=r"^mine:\d+:\d+: kernel\.sigma: "):
        d = study_dict()
        d["kernel"][0]["sigma"] = -1.0
        rkhs_study.Study.from_dict(d, source_name="mine").trials()
    # a value TOML has no form for is a StudyError too, before any text is parsed
    d = study_dict()
    d["study"]["description"] = None
    with pytest.raises(rkhs_study.StudyError, match=r"^<dict>: study\.description: NoneType"):
        rkhs_study.Study.from_dict(d)


# Results.provenance and Results.verdicts against summary.json

def test_provenance_and_verdicts_are_summary_jsons(tmp_path):
    import json
    import math
    results = rkhs_study.Study.load(STUDY).run(threads=2, out=tmp_path)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert results.study == summary["study"] == "gram_and_power"
    assert results.provenance == summary["provenance"]
    assert results.provenance["threads"] == 2
    assert {"version", "git_commit", "compiler", "build_type", "started"} <= set(
        results.provenance)
    verdicts = results.verdicts
    assert isinstance(verdicts, pd.DataFrame)
    expected = summary["expectations"]["outcomes"]
    assert len(verdicts) == len(expected) == len(results.outcomes) == 11
    assert list(verdicts.columns) == list(results.outcomes[0])
    # The columns of an empty frame are those of the outcome dicts, in their order: "study",
    # then summary.json's keys (the outcome table's, rkhs::outcome_fields, with "summary").
    assert rkhs_study._OUTCOME_FIELDS == list(results.outcomes[0])
    python_only, summary_only = {"study", "summary"}, {"expectation_name", "kind", "window"}
    assert [k for k in results.outcomes[0] if k not in python_only] == [
        k for k in expected[0] if k not in summary_only]
    for (_, row), outcome in zip(verdicts.iterrows(), expected):
        for key in ("name", "metric", "location", "group", "group_label", "outcome",
                    "expected", "found", "reason"):
            assert row[key] == outcome[key], key
        assert row["verdict"].lower() == outcome["verdict"]
        assert row["study"] == summary["study"]
        for key in ("rate", "ci_low", "ci_high", "accepted_low", "accepted_high",
                    "effectivity_min", "effectivity_max"):
            value = outcome[key]  # summary.json: null for NaN, "inf" and "-inf" as text
            if value is None:
                assert math.isnan(row[key]), key
            else:
                assert row[key] == float(value), key


def test_provenance_of_a_temporary_folder_is_kept():
    results = rkhs_study.Study.load(STUDY).run(threads=1)
    assert results.out is None
    assert results.provenance["threads"] == 1
    assert results.provenance["wall_seconds"] >= 0


def test_verdicts_of_a_study_without_expectations_is_an_empty_frame():
    text = STUDY.read_text().split("[[expect]]")[0]
    results = rkhs_study.Study.from_toml(text).run(threads=2)
    assert results.outcomes == []
    assert results.verdicts.empty
    assert {"name", "outcome", "rate"} <= set(results.verdicts.columns)


def test_check_verdicts_are_its_outcomes():
    result = rkhs_study.check(STUDY, tier="quick")
    assert result.verdicts["outcome"].tolist() == [o["outcome"] for o in result.outcomes]


# Results.plot with matplotlib (Agg) and the rich display of Jupyter (_repr_html_)

@pytest.fixture(scope="module")
def results():
    return rkhs_study.Study.load(STUDY).run(threads=2)


@pytest.fixture(scope="module")
def agg():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    yield plt
    plt.close("all")


def test_plot_draws_one_line_per_group_with_the_trials_values(results, agg, cli_out):
    import numpy as np
    trials = rkhs_study.read_csv(cli_out / "trials.csv")
    ax = results.plot("power_function_sup")
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    lines = ax.get_lines()
    kernels = [("gaussian", None), ("bspline", 1), ("bspline", 2)]
    assert len(lines) == len(kernels) == 3
    for line, (kernel, degree) in zip(lines, kernels):
        rows = trials[(trials["kernel"] == kernel)
                      & (trials["degree"].isna() if degree is None else trials["degree"] == degree)]
        assert np.array_equal(line.get_xdata(), rows["n"].to_numpy())
        assert np.array_equal(line.get_ydata(), rows["power_function_sup"].to_numpy())
    labels = [line.get_label() for line in lines]
    fits = results.rates.query("metric == 'power_function_sup' and kind == 'fit'")
    degree1 = fits[fits["degree"] == 1].iloc[0]
    assert labels[1] == (f"bspline degree=1 r=1: rate {degree1['rate']:.3g} "
                         f"[{degree1['ci_low']:.3g}, {degree1['ci_high']:.3g}]")
    assert labels[0].startswith("gaussian: exponential rate ")
    assert [t.get_text() for t in ax.get_legend().get_texts()] == labels
    agg.close(ax.figure)


def test_plot_defaults_to_the_first_error_metric_and_takes_an_axes(results, agg):
    figure, given = agg.subplots()
    ax = results.plot(ax=given)
    assert ax is given and ax.figure is figure
    assert ax.get_ylabel() == "l2_error"
    assert len(ax.get_lines()) == 3
    with pytest.raises(ValueError, match="no metric 'bogus'"):
        results.plot("bogus", ax=given)
    agg.close(figure)


def test_results_html_has_the_counts_the_rates_and_a_plot(results, agg):
    page = results._repr_html_()
    assert page.startswith(f"<h4>gram_and_power: 30 trials, 0 failed, ")
    assert "expectations: 11 passed" in page
    fits = results.rates[results.rates["kind"] == "fit"]
    table = page[page.index("<table"):page.index("</table>")]
    assert table.count("<tr") == len(fits) + 1  # a header and a row per group and metric
    assert "<td>bspline degree=2 r=2</td>" in table and "<td>power_function_sup</td>" in table
    import base64
    image = re.search(r'<img src="data:image/png;base64,([A-Za-z0-9+/=]+)"', page)
    assert image and base64.b64decode(image.group(1)).startswith(b"\x89PNG\r\n\x1a\n")
    assert results.rates_table()["group"].tolist()[:1] == ["gaussian"]


def test_check_and_validation_html():
    result = rkhs_study.check(STUDY, tier="quick")
    page = result._repr_html_()
    assert page.startswith("<h4>check passed (exit 0): 11 passed, 0 failed, 0 inconclusive")
    assert page.count("<td>passed</td>") == 11
    assert page.count("<tr") == 12
    validation = rkhs_study.Study.load(STUDY).validate()
    page = validation._repr_html_()
    assert "<tr><td>kernels</td><td>3</td></tr>" in page
    assert "<tr><td>values of n</td><td>10</td></tr>" in page
    assert "<tr><th>trials</th><th>30</th></tr>" in page


def test_the_package_imports_and_displays_without_matplotlib(tmp_path):
    """matplotlib is imported when a plot is drawn, not before; without it no image."""
    script = (
        "import sys\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] == 'matplotlib':\n"
        "            raise ImportError('no matplotlib here')\n"
        "sys.meta_path.insert(0, Block())\n"
        "import rkhs_study\n"
        "assert 'matplotlib' not in sys.modules\n"
        "r = rkhs_study.Study.load(sys.argv[1]).run(threads=2)\n"
        "page = r._repr_html_()\n"
        "assert '<table' in page and '<img' not in page, page[:200]\n"
        "try:\n"
        "    r.plot()\n"
        "except ImportError:\n"
        "    print('ok')\n")
    package = Path(rkhs_study.__file__).resolve().parents[1]
    done = subprocess.run([sys.executable, "-c", script, str(STUDY)], capture_output=True,
                          text=True, cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(package)))
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"


# A study of 243 trials (n from 200 to 600) that runs for about a minute on 2 cores, each trial
# well under a second: long enough to be interrupted, short enough that a stop is quick.
SLOW_STUDY = STUDY.read_text().replace("n = { from = 10, to = 100, step = 10 }",
                                       "n = { from = 200, to = 600, step = 5 }", 1)
assert SLOW_STUDY != STUDY.read_text()

# Runs SLOW_STUDY (argv[1]) with the store argv[2]; prints what the KeyboardInterrupt says.
INTERRUPTED_RUN = """
import signal, sys
# Python leaves SIGINT alone when it starts ignored (a background job of a shell): take it.
signal.signal(signal.SIGINT, signal.default_int_handler)
import rkhs_study
try:
    rkhs_study.Study.from_toml(sys.argv[1], "slow.toml").run(threads=2, store=sys.argv[2])
except KeyboardInterrupt as e:
    print(type(e).__name__, isinstance(e, rkhs_study.RunInterrupted), e.finished, e.stored,
          e.reused, e.stopped, e.not_started, flush=True)
    print(e, file=sys.stderr)
    sys.exit(130)
print("completed", flush=True)
"""


def stored_trials(store: Path) -> int:
    import sqlite3
    if not store.exists():
        return 0
    try:
        with sqlite3.connect(f"file:{store}?mode=ro", uri=True, timeout=1) as db:
            return db.execute("SELECT count(*) FROM trials").fetchone()[0]
    except sqlite3.Error:  # not created yet, or busy
        return 0


def interrupt_once_stored(store: Path, at_least: int):
    """Starts INTERRUPTED_RUN, sends SIGINT once the store holds `at_least` trials and returns
    (its output fields, seconds from the signal to its end, stderr)."""
    import signal
    import time

    environment = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    process = subprocess.Popen([sys.executable, "-c", INTERRUPTED_RUN, SLOW_STUDY, str(store)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env=environment)
    try:
        deadline = time.monotonic() + 120  # generous: a loaded machine
        while stored_trials(store) < at_least:
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline, "no trial stored in 120 s"
            time.sleep(0.05)
        signalled = time.monotonic()
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=30)
        ended = time.monotonic() - signalled
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert process.returncode == 130, (process.returncode, out, err)
    return out.split(), ended, err


def test_ctrl_c_stops_a_run_and_keeps_the_finished_trials(tmp_path):
    store = tmp_path / "store.sqlite"
    fields, seconds, err = interrupt_once_stored(store, 2)
    assert seconds < 2, (seconds, fields, err)
    name, is_run_interrupted, finished, stored, reused, stopped, not_started = fields
    assert name == "RunInterrupted" and is_run_interrupted == "True"
    finished, stored, reused = int(finished), int(stored), int(reused)
    assert finished >= 2 and stored == finished and reused == 0
    assert finished + int(stopped) + int(not_started) == 243
    assert stored_trials(store) == stored
    assert "interrupted" in err and "reuses the stored trials" in err
    # The same run again reuses every stored trial (and is interrupted in turn).
    fields, seconds, err = interrupt_once_stored(store, stored + 1)
    assert seconds < 2, (seconds, fields, err)
    assert int(fields[4]) == stored, fields


def test_an_error_of_the_run_is_raised_with_its_message(tmp_path):
    """The run goes on a thread of its own; what it throws is raised in the caller."""
    (tmp_path / "file").write_text("")
    with pytest.raises(RuntimeError, match=re.escape(f"cannot write the output folder "
                                                     f"{tmp_path / 'file' / 'out'}")):
        rkhs_study.Study.load(STUDY).run(out=tmp_path / "file" / "out")


def test_check_k_selects_test_cases_as_the_command(tmp_path):
    result = rkhs_study.check(STUDY, k="sup_error and not gaussian")
    assert result.passed
    assert [o["name"] for o in result.outcomes] == [
        "sup_error [kernel=bspline degree=1 r=1]", "sup_error [kernel=bspline degree=2 r=2]"]
    assert result.studies[0]["deselected"] == 9
    assert result.counts.startswith("2 passed, 0 failed, 0 inconclusive, 9 deselected")
    # -k that selects nothing: the study is not run, exit code 5 as the command's
    none = rkhs_study.check(STUDY, k="no_such_case")
    assert none.exit_code == 5 and not none.passed and none.outcomes == []
    assert none.studies[0]["ran"] == 0
    assert cli("check", STUDY, "-k", "no_such_case", "--no-store", "-q",
               check=False).returncode == 5
    with pytest.raises(ValueError, match="-k 'power and'"):
        rkhs_study.check(STUDY, k="power and")


def test_check_junit_writes_the_commands_report(tmp_path):
    import xml.etree.ElementTree as ElementTree

    result = rkhs_study.check(STUDY, k="power_function_sup", junit=tmp_path / "py.xml")
    root = ElementTree.parse(tmp_path / "py.xml").getroot()
    cases = root.findall("./testsuite/testcase")
    assert len(cases) == len(result.outcomes) == 3
    assert {c.get("name") for c in cases} == {o["name"] for o in result.outcomes}
    assert root.find("./testsuite").get("name") == "gram_and_power"
    cli("check", STUDY, "-k", "power_function_sup", "--no-store", "-q", "--junit",
        tmp_path / "cli.xml")

    def without_times(file):
        return re.sub(r' (time|timestamp)="[^"]*"', "", file.read_text())

    assert without_times(tmp_path / "py.xml") == without_times(tmp_path / "cli.xml")


def test_check_of_a_failing_study_fails_as_the_command(tmp_path):
    """A declared rate the study cannot meet (the degree-1 B-spline's power function falls like
    n^-1/2, not n^-3): check() does not pass, with the command's exit code 1."""
    text = STUDY.read_text() + '''
[[expect]]
metric = "power_function_sup"
kernel = "bspline"
degree = 1
rate = -3.0
'''
    study_file = tmp_path / "failing.toml"
    study_file.write_text(text)
    result = rkhs_study.check([study_file], threads=2, tier=None)
    assert not result.passed and not result
    assert result.exit_code == 1
    failed = [o for o in result.outcomes if o["outcome"] == "failed"]
    assert len(failed) == 1 and failed[0]["metric"] == "power_function_sup"
    assert failed[0]["location"].startswith(f"{study_file}:")
    assert "1 failed" in result.counts
    command = subprocess.run([EXECUTABLE, "check", str(study_file), "--no-store", "--quiet"],
                             capture_output=True, text=True, cwd=tmp_path)
    assert command.returncode == result.exit_code == 1
