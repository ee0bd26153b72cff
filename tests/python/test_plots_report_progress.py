"""Study.run's plots and progress display and Results.report (docs/python.md) against the
rkhs-study command: the same plot files in plots/, the same tables, the same progress line.

Run by ctest (python.rkhs_study) with test_rkhs_study.py; see there for the environment.
"""

import os
import re
import subprocess
from pathlib import Path

import pytest

import rkhs_study

SOURCE_DIR = Path(os.environ.get("RKHS_STUDY_SOURCE_DIR", Path(__file__).resolve().parents[2]))
EXECUTABLE = os.environ.get("RKHS_STUDY_EXECUTABLE",
                            str(SOURCE_DIR / "build" / "release" / "rkhs-study"))
STUDY = SOURCE_DIR / "studies" / "gram_and_power.toml"
TABLES = ("trials.csv", "rates.csv", "rates.md", "rates.tex")
FOLDER = ("trials.csv", "rates.csv", "summary.json", "rates.md", "rates.tex", "report.html")


@pytest.fixture(scope="module")
def cli_out(tmp_path_factory):
    """What `rkhs-study run STUDY --out DIR --no-store` writes, plots included."""
    out = tmp_path_factory.mktemp("cli-plots")
    subprocess.run([EXECUTABLE, "run", str(STUDY), "--out", str(out), "--no-store", "--quiet"],
                   capture_output=True, text=True, check=True, cwd=SOURCE_DIR)
    return out


@pytest.fixture(scope="module")
def py_run(tmp_path_factory):
    """Study.run(out=...) with its default plots (True with an output folder)."""
    out = tmp_path_factory.mktemp("py-plots")
    return rkhs_study.Study.load(STUDY).run(threads=2, out=out)


def plot_files(folder: Path) -> list:
    return sorted(os.listdir(folder / "plots"))


def test_run_with_out_renders_the_commands_plots(cli_out, py_run):
    expected = plot_files(cli_out)
    assert any(name.endswith(".svg") for name in expected)
    assert plot_files(py_run.out) == expected
    for stem in py_run.plots:
        for extension in (".svg", ".png"):
            file = py_run.out / "plots" / (stem + extension)
            assert file.is_file() and file.stat().st_size > 0, file
    assert sorted(stem + ".svg" for stem in py_run.plots) == \
        [name for name in expected if name.endswith(".svg")]
    # and report.html embeds them, as the command's does
    embedded = lambda folder: (folder / "report.html").read_text().count('<img class="plot"')
    assert embedded(py_run.out) == embedded(cli_out) == len(py_run.plots)
    assert not (py_run.out / "INCOMPLETE").exists()


def test_plots_false_is_no_plots_and_without_out_there_are_none(tmp_path):
    study = rkhs_study.Study.load(STUDY)
    results = study.run(threads=2, out=tmp_path / "none", plots=False)
    assert results.plots == []
    assert not (tmp_path / "none" / "plots").exists()
    assert study.run(threads=2).plots == []
    with pytest.raises(ValueError, match="plots=True needs an output folder"):
        study.run(plots=True)


def test_report_writes_the_runs_folder_byte_for_byte(py_run, tmp_path):
    written = py_run.report(tmp_path / "again")
    assert written == tmp_path / "again"
    for name in FOLDER:
        assert (written / name).is_file(), name
    for name in TABLES + ("summary.json", "report.html"):
        assert (written / name).read_bytes() == (py_run.out / name).read_bytes(), name
    assert plot_files(written) == plot_files(py_run.out)
    for name in plot_files(written):  # the PDFs carry the time gnuplot made them
        if not name.endswith(".pdf"):
            assert (written / "plots" / name).read_bytes() == \
                (py_run.out / "plots" / name).read_bytes(), name
    assert not (written / "INCOMPLETE").exists()


def test_report_of_a_run_into_a_temporary_folder_is_the_commands_folder(cli_out, tmp_path):
    results = rkhs_study.Study.load(STUDY).run(threads=1)
    assert results.out is None
    written = results.report(tmp_path / "kept")
    for name in TABLES:
        assert (written / name).read_bytes() == (cli_out / name).read_bytes(), name
    assert plot_files(written) == plot_files(cli_out)
    results.report(tmp_path / "tables", plots=False)
    assert not (tmp_path / "tables" / "plots").exists()
    assert (tmp_path / "tables" / "rates.md").read_bytes() == (cli_out / "rates.md").read_bytes()


def test_report_needs_a_run():
    results = rkhs_study.Results(out=None, trials=None, rates=None, failed=0, seconds=0)
    with pytest.raises(ValueError, match="needs the Results of Study.run"):
        results.report("anywhere")


# The command's progress line: "30/30 trials, 0 failed, 1.2 s, ETA 0.0 s".
FINAL = re.compile(r"30/30 trials, 0 failed, [0-9.]+ (s|min)")


def test_progress_writes_the_commands_lines_to_stderr(capsys):
    rkhs_study.Study.load(STUDY).run(threads=2, progress=True)
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert lines, "no progress written"
    assert FINAL.match(lines[-1].strip()), captured.err
    assert captured.err.endswith("\n")


def test_progress_in_a_notebook_redraws_one_line(capsys, monkeypatch):
    monkeypatch.setattr(rkhs_study, "_progress_redraws", lambda: True)
    rkhs_study.Study.load(STUDY).run(threads=2, progress=True)
    err = capsys.readouterr().err
    assert err.startswith("\r[") and err.endswith("\n"), repr(err)
    assert "\n" not in err[:-1], repr(err)  # one line, redrawn with "\r"
    last = err.rstrip("\n").split("\r")[-1]
    assert last.startswith("[" + "#" * 30 + "] "), repr(last)
    assert FINAL.match(last[33:]), repr(last)


def test_no_progress_writes_nothing(capfd, tmp_path):
    study = rkhs_study.Study.load(STUDY)
    study.run(threads=2, store=tmp_path / "store.sqlite")
    assert capfd.readouterr().err == ""
    # a store holding every trial: nothing to run, no progress (as the command)
    study.run(threads=2, store=tmp_path / "store.sqlite", progress=True)
    assert capfd.readouterr().err == ""
