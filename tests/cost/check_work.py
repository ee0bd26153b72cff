#!/usr/bin/env python3
"""The cost gate: a study's quick tier must not do more work than its committed budget.

Runs `rkhs-study check STUDY --tier quick ... --out DIR --no-plots` once (the same run that
judges the study's expectations: its verdicts and exit code are passed through unchanged), then
compares the study's work counters in DIR/summary.json ("work", docs/results.md) with the budget
in tests/cost/budgets/<study>.json:

  - a counter more than its margin above its budget fails the test: 10 % for the counts, 25 % for
    peak_bytes (the peak of a trial whose parts run on several threads depends on how they
    interleave; every other counter is a sum and does not);
  - a counter more than 25 % below its budget passes with a note to lower the budget;
  - a counter the build does not measure (allocations under the sanitizers) is skipped.

With --record (or the environment variable RKHS_RECORD_WORK_BUDGETS=1) the measured counters are
written as the new budget instead. Regenerate every budget with one command:

  RKHS_RECORD_WORK_BUDGETS=1 ctest --test-dir build/release -R '^quick\\.' -j 2

Standard library only.
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys

# Counter -> allowed excess over its budget (a fraction of the budget).
MARGINS = {
    "kernel_evaluations": 0.10,
    "kernel_derivative_evaluations": 0.10,
    "factorisations": 0.10,
    "sparse_nonzeros": 0.10,
    "factor_nonzeros": 0.10,
    "sparse_solve_columns": 0.10,
    "allocations": 0.10,
    "allocated_bytes": 0.10,
    "peak_bytes": 0.25,
    "steps": 0.10,
    "rhs_evaluations": 0.10,
}
# A counter this far below its budget gets a note suggesting a lower budget.
FAR_BELOW = 0.25


def measured_work(summary):
    """The study's counters from summary.json: {counter: value or None}."""
    work = summary.get("work")
    if not isinstance(work, dict):
        raise SystemExit("check_work: summary.json has no study-wide \"work\" object")
    if work.get("trials_without_counters"):
        raise SystemExit(
            f"check_work: {work['trials_without_counters']} trials have no work counters "
            "(reused from a result store?): run with --no-store")
    return {name: work.get(name) for name in MARGINS if name in work}


def compare(study, trials, measured, budget_file):
    """Prints the comparison; returns True when no counter is over its budget."""
    if not budget_file.exists():
        print(f"cost gate: {study}: no budget {budget_file}; record it with\n"
              f"  RKHS_RECORD_WORK_BUDGETS=1 ctest --test-dir BUILD -R '^quick\\.{study}$'")
        return False
    budget = json.loads(budget_file.read_text())
    budgeted = budget.get("work", {})
    ok = True
    lines = []
    if budget.get("trials") != trials:
        lines.append(f"  the quick tier runs {trials} trials, the budget was recorded for "
                     f"{budget.get('trials')}: record the budgets again")
        ok = False
    for name, value in measured.items():
        limit = budgeted.get(name)
        if value is None:
            lines.append(f"  {name:31} not measured by this build (skipped)")
            continue
        if limit is None:
            lines.append(f"  {name:31} {value:>16,}   not budgeted: record the budgets again")
            continue
        margin = MARGINS[name]
        change = (value - limit) / limit if limit else (0.0 if value == 0 else float("inf"))
        if value > limit * (1 + margin):
            verdict = f"OVER BUDGET (allowed +{margin:.0%})"
            ok = False
        elif limit and value < limit * (1 - FAR_BELOW):
            verdict = "far below budget: lower it (record the budgets again)"
        else:
            verdict = "ok"
        lines.append(f"  {name:31} {value:>16,}   budget {limit:>16,}   {change:+8.1%}   {verdict}")
    print(f"cost gate: {study}: work of the quick tier against {budget_file.name} "
          f"({'within budget' if ok else 'OVER BUDGET'})")
    print("\n".join(lines))
    if not ok:
        print("A counter above its budget means this change makes the study do more work. Find "
              "out why (summary.json has the counters of every trial, \"work\"); raise the "
              "budget only when the extra work is wanted (docs/results.md, \"The cost gate\").")
    return ok


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     epilog="-- ARGS...: further arguments of `rkhs-study check`")
    parser.add_argument("rkhs_study", help="the rkhs-study executable")
    parser.add_argument("study_file")
    parser.add_argument("--budgets", required=True, type=pathlib.Path,
                        help="the folder of budgets, one <study>.json each")
    parser.add_argument("--out", required=True, type=pathlib.Path,
                        help="where check writes its outputs (summary.json)")
    parser.add_argument("--record", action="store_true",
                        help="write the measured counters as the budget")
    # Everything after "--" is passed to `rkhs-study check`.
    argv = sys.argv[1:]
    split = argv.index("--") if "--" in argv else len(argv)
    args = parser.parse_args(argv[:split])
    extra = argv[split + 1:]
    record = args.record or os.environ.get("RKHS_RECORD_WORK_BUDGETS") == "1"

    command = [args.rkhs_study, "check", args.study_file, "--out", str(args.out), "--no-plots",
               *extra]
    sys.stdout.flush()
    code = subprocess.call(command)
    if code != 0:
        return code  # the check's own verdict, unchanged
    summary = json.loads((args.out / "summary.json").read_text())
    study = summary["study"]
    measured = measured_work(summary)
    budget_file = args.budgets / f"{study}.json"
    if record:
        budget = {
            "study": study,
            "tier": summary.get("tier"),
            "trials": summary["counts"]["trials"],
            "regenerate": "RKHS_RECORD_WORK_BUDGETS=1 ctest --test-dir build/release -R '^quick\\.' -j 2",
            "work": {name: value for name, value in measured.items() if value is not None},
        }
        budget_file.parent.mkdir(parents=True, exist_ok=True)
        budget_file.write_text(json.dumps(budget, indent=2) + "\n")
        print(f"cost gate: {study}: recorded the budget {budget_file}")
        return 0
    return 0 if compare(study, summary["counts"]["trials"], measured, budget_file) else 1


if __name__ == "__main__":
    sys.exit(main())
