#!/usr/bin/env python3
"""Validates the JUnit XML of `rkhs-study check` with Python's own XML parser.

Writes a small study with one passing, one failing and one inconclusive expectation, runs
`rkhs-study check --junit` on it (plain and --strict), parses the XML with xml.etree and checks
what CI systems read: the suite's counts agree with its test cases, every test case names the
expectation (classname, name, file, line), a failure or skip carries the verdict with the fitted
rate, CI and window in its message, and every test case has the full report in <system-out>.

Usage: validate_junit.py RKHS_STUDY_EXECUTABLE WORK_DIR
Exit status 0 when every check holds.
"""
import pathlib
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

STUDY = """[study]
name = "junit_check"
evaluation_points = 512
metrics = ["fill_distance", "separation_distance", "gram_condition_number", "power_function_sup"]
[domain]
radius = 4.0
[grid]
n = { from = 10, to = 60, step = 10 }
[[kernel]]
name = "bspline"
degree = [1, 2]
J = 8

[[expect]]
name = "theory <pass> & \\"quotes\\""
metric = "power_function_sup"
kernel = "bspline"
degree = 1
theory = true

[[expect]]
metric = "power_function_sup"
degree = 2
rate = -3.0

[[expect]]
metric = "gram_condition_number"
degree = 2
theory = true
tolerance = 0.01
"""


def check(condition, message):
    if not condition:
        print(f"FAILED: {message}")
        sys.exit(1)


def run(executable, study, report, *extra):
    result = subprocess.run([executable, "check", str(study), "--quiet", "--junit", str(report), *extra],
                            capture_output=True, text=True)
    return result.returncode, result.stdout + result.stderr


def validate(report, strict):
    root = ElementTree.parse(report).getroot()  # raises on malformed XML
    check(root.tag == "testsuites", f"root element is {root.tag}")
    suites = root.findall("testsuite")
    check(len(suites) == 1, "one testsuite")
    suite = suites[0]
    cases = suite.findall("testcase")
    check(len(cases) == 3, f"{len(cases)} test cases, expected 3")
    failures = [c for c in cases if c.find("failure") is not None]
    skipped = [c for c in cases if c.find("skipped") is not None]
    for element in (root, suite):
        check(int(element.get("tests")) == len(cases), "tests count")
        check(int(element.get("failures")) == len(failures), "failures count")
        check(int(element.get("skipped")) == len(skipped), "skipped count")
        check(int(element.get("errors")) == 0, "errors count")
        float(element.get("time"))
    check(len(failures) == (2 if strict else 1), f"{len(failures)} failures")
    check(len(skipped) == (0 if strict else 1), f"{len(skipped)} skipped")
    for case in cases:
        for attribute in ("classname", "name", "file", "line", "time"):
            check(case.get(attribute), f"test case without {attribute}")
        check(case.get("classname").startswith("junit_check."), case.get("classname"))
        check(int(case.get("line")) > 0, "line number")
        out = case.find("system-out")
        check(out is not None and "expected:" in out.text and "found:" in out.text
              and "verdict:" in out.text, "system-out report")
        check("CI [" in out.text and "window n = 10..60" in out.text, "fitted rate, CI and window")
    names = [c.get("name") for c in cases]
    check(names[0] == 'theory <pass> & "quotes" [kernel=bspline degree=1 r=1]',
          f"escaped name read back: {names[0]}")
    failure = failures[0].find("failure")
    check(failure.get("type") == "fail", "failure type")
    message = failure.get("message")
    check(message.startswith("FAIL: the 95% CI lies entirely above -2.90"), message)
    check("CI [" in message and "window n = 10..60" in message, "failure message has CI and window")
    if strict:
        check(failures[1].find("failure").get("type") == "inconclusive", "strict: inconclusive failure")
    else:
        check(skipped[0].find("skipped").get("message").startswith("INCONCLUSIVE: "), "skip message")


def main():
    executable, work = sys.argv[1], pathlib.Path(sys.argv[2])
    work.mkdir(parents=True, exist_ok=True)
    study = work / "junit_check.toml"
    study.write_text(STUDY)
    for strict in (False, True):
        report = work / f"report{'_strict' if strict else ''}.xml"
        code, output = run(executable, study, report, *(["--strict"] if strict else []))
        check(code == 1, f"exit code {code}, expected 1:\n{output}")
        validate(report, strict)
    print("JUnit XML valid: counts, test cases, messages, escaping")


if __name__ == "__main__":
    main()
