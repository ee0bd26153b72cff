#!/usr/bin/env python3
"""Behaviour of every shipped study, pinned: trials.csv, rates.csv and the verdicts of
`rkhs-study check` for each studies/*.toml are compared with the golden files in
tests/golden/studies/<study>/.

Adaptive studies run on a short horizon (one lap, one snapshot; a laps axis becomes one lap and
the limit) so the whole check takes a few minutes on two cores; approximation studies run as
shipped. Numbers must agree to 1e-9 relative: the last digits of a double depend on the
processor (glibc picks its exp, log and sin by CPU features at run time, and Eigen its kernels
at build time), so a refactoring that changes no formula stays well inside that, while a change
of method does not. Text must match exactly. Columns may be added, never removed, renamed or
changed; rows must match in number and order. Verdicts must match line for line, except the
first line's wall time.

Usage:
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR                 compare every study
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR --study NAME    compare studies/NAME.toml
                                                                          (ctest: golden.NAME)
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR --stale         only: no golden files
                                                                          for a study not shipped
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR --record        write the golden files

Record only when a change of behaviour is intended, and say why in the commit.
Standard library only.
"""
import csv
import pathlib
import re
import shutil
import subprocess
import sys

# The first line of `check` output: "<study>: 8 trials, 8 ok, 0 failed in 0.24 s".
WALL_TIME = re.compile(r" in [0-9.e+-]+ s$")


def shortened(text):
    """The study with adaptive horizons cut to one lap (a laps list to [1], or to [1, "limit"]
    when it has the limit; laps = "limit" alone kept; approximation studies unchanged)."""
    if not re.search(r'^kind = "adaptive"', text, re.M):
        return text
    def one_lap(match):
        if match.group(1) == '"limit"':
            return 'laps = "limit"'  # the lap map's fixed point: no horizon to shorten
        if match.group(1)[0] != "[":
            return "laps = 1"
        return 'laps = [1, "limit"]' if '"limit"' in match.group(1) else "laps = [1]"
    # The [adaptive] table's laps, not an [[expect]] selector (`laps = "limit"`) after it.
    head, separator, expectations = text.partition("\n[[expect]]")
    head, laps = re.subn(r'^laps = (\d+|\[.*\]|"limit")', one_lap, head, flags=re.M)
    text = head + separator + expectations
    text, snapshots = re.subn(r"^snapshot_laps = \[.*\]", "snapshot_laps = [1]", text, flags=re.M)
    if laps != 1 or snapshots > 1:
        raise SystemExit(f"cannot shorten the horizon: {laps} 'laps =' lines, {snapshots} "
                         "'snapshot_laps =' lines (expected one each)")
    return text


def run_study(exe, source, work, study):
    """Runs `check` on the (shortened) study; returns the output folder and the verdict lines."""
    name = study.stem
    work.mkdir(parents=True, exist_ok=True)
    definition = work / f"{name}.toml"
    definition.write_text(shortened(study.read_text()))
    out = work / name
    shutil.rmtree(out, ignore_errors=True)
    result = subprocess.run(
        [exe, "check", "--no-store", "--no-plots", "--quiet", "--threads", "2", "--out", name,
         "--data-dir", str(source / "studies" / "data"), definition.name],
        cwd=work, capture_output=True, text=True, check=False)
    # 0 all pass, 1 a failure, 3 inconclusive: short horizons fail some expectations, and that
    # is pinned too. 2 (bad input) or a crash is an error of this check.
    if result.returncode not in (0, 1, 3):
        raise SystemExit(f"{name}: rkhs-study check exited {result.returncode}\n{result.stderr}")
    lines = result.stdout.splitlines()
    if lines:
        lines[0] = WALL_TIME.sub("", lines[0])
    return out, lines


def read_csv(path):
    with open(path, newline="", encoding="utf-8") as handle:
        rows = list(csv.reader(handle))
    if not rows:
        raise SystemExit(f"{path}: empty")
    return rows[0], rows[1:]


RELATIVE_TOLERANCE = 1e-9


# The fit statistics of rates.csv are dimensionless numbers of order one (slopes, their standard
# errors and intervals, R^2, AIC differences): a slope of 6.2e-5 against 6.2025e-5 is the same
# flat series on two processors, so they also match within an absolute 1e-6.
FIT_COLUMNS = {"rate", "std_error", "ci_low", "ci_high", "r_squared", "delta_aic"}
FIT_ABSOLUTE_TOLERANCE = 1e-6


def same_value(golden, found, column=""):
    """Equal text, or numbers within RELATIVE_TOLERANCE of each other (fit statistics also
    within FIT_ABSOLUTE_TOLERANCE)."""
    if golden == found:
        return True
    try:
        a, b = float(golden), float(found)
    except ValueError:
        return False
    if column in FIT_COLUMNS and abs(a - b) <= FIT_ABSOLUTE_TOLERANCE:
        return True
    return abs(a - b) <= RELATIVE_TOLERANCE * max(abs(a), abs(b))


def compare_csv(golden_path, actual_path):
    """Differences between two CSV files, golden columns only (added columns are allowed)."""
    golden_header, golden_rows = read_csv(golden_path)
    actual_header, actual_rows = read_csv(actual_path)
    problems = []
    missing = [c for c in golden_header if c not in actual_header]
    if missing:
        problems.append(f"{actual_path}: columns removed or renamed: {', '.join(missing)}")
        return problems
    if len(golden_rows) != len(actual_rows):
        problems.append(f"{actual_path}: {len(actual_rows)} rows, golden has {len(golden_rows)}")
        return problems
    where = {c: actual_header.index(c) for c in golden_header}
    for number, (golden, actual) in enumerate(zip(golden_rows, actual_rows), start=2):
        for column, value in zip(golden_header, golden):
            found = actual[where[column]]
            if not same_value(value, found, column if actual_path.name == "rates.csv" else ""):
                problems.append(f"{actual_path}:{number}: column {column}: found '{found}', "
                                f"golden '{value}'")
                if len(problems) >= 20:
                    return problems + ["(more differences not shown)"]
    return problems


def main(argv):
    options = argv[4:]
    if len(argv) < 4 or options not in ([], ["--record"], ["--stale"]) and not (
            len(options) == 2 and options[0] == "--study"):
        raise SystemExit(__doc__)
    exe = str(pathlib.Path(argv[1]).resolve())
    source, work = pathlib.Path(argv[2]).resolve(), pathlib.Path(argv[3]).resolve()
    record = options == ["--record"]
    golden_root = source / "tests" / "golden" / "studies"
    shipped = sorted((source / "studies").glob("*.toml"))
    if not shipped:
        raise SystemExit(f"no studies in {source / 'studies'}")
    studies = shipped
    if options[:1] == ["--study"]:
        studies = [s for s in shipped if s.stem == options[1]]
        if not studies:
            raise SystemExit(f"no study {options[1]!r} in {source / 'studies'}")
    elif options == ["--stale"]:
        studies = []
    failures = []
    for study in studies:
        out, verdicts = run_study(exe, source, work, study)
        golden = golden_root / study.stem
        if record:
            golden.mkdir(parents=True, exist_ok=True)
            for name in ("trials.csv", "rates.csv"):
                shutil.copyfile(out / name, golden / name)
            (golden / "verdicts.txt").write_text("\n".join(verdicts) + "\n")
            print(f"recorded {golden}")
            continue
        if not golden.is_dir():
            failures.append(f"{study.stem}: no golden files in {golden} (record them with --record)")
            continue
        problems = []
        for name in ("trials.csv", "rates.csv"):
            problems += compare_csv(golden / name, out / name)
        expected = (golden / "verdicts.txt").read_text().splitlines()
        if verdicts != expected:
            for number, (want, got) in enumerate(zip(expected, verdicts), start=1):
                if want != got:
                    problems.append(f"verdicts line {number}: found '{got}', golden '{want}'")
                    break
            if len(verdicts) != len(expected):
                problems.append(f"verdicts: {len(verdicts)} lines, golden has {len(expected)}")
        status = "ok" if not problems else "DIFFERS"
        print(f"{study.stem}: {status}")
        failures += [f"{study.stem}: {p}" for p in problems]
    check_stale = not record and options[:1] != ["--study"]
    for stale in sorted(p.name for p in golden_root.iterdir() if p.is_dir()) if check_stale else []:
        if stale not in {s.stem for s in shipped}:
            failures.append(f"{stale}: golden files for a study that is no longer shipped")
    if failures:
        print("\n".join(failures), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
