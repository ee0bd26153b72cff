#!/usr/bin/env python3
"""docs/paper.md is what tools/paper_report.py makes of the paper studies (studies/paper/).

Runs the studies and the script into WORK and compares its page with docs/paper.md line by line,
numbers within one unit of their last printed digit (a value printed to its digits may round the
other way on another processor; tests/golden/check_shipped_studies.py, same_text). Fails naming
the first line that differs: a study, a printed number or the script changed without the page,
or the page edited by hand. `--self-test` first checks that a changed number and a changed
verdict are caught.

usage: check_paper_doc.py BIN SRC WORK
"""
import pathlib
import subprocess
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent / "golden"))
from check_shipped_studies import same_text  # noqa: E402


def first_difference(want, got):
    """The first (line number, want, got) where the two pages differ, or None."""
    a, b = want.splitlines(), got.splitlines()
    for k in range(max(len(a), len(b))):
        x = a[k] if k < len(a) else "(no line)"
        y = b[k] if k < len(b) else "(no line)"
        if not same_text(x, y, 0.0):
            return k + 1, x, y
    return None


def self_test():
    page = "| 10 | 664.6 | 114.7 | 0.173 |\n| verdict | **not reproducible** |\n"
    assert first_difference(page, page.replace("0.173", "0.174")) is None  # its last digit
    assert first_difference(page, page.replace("0.173", "0.175")) == (
        1, "| 10 | 664.6 | 114.7 | 0.173 |", "| 10 | 664.6 | 114.7 | 0.175 |")
    assert first_difference(page, page.replace("not reproducible", "reproduced"))[0] == 2
    assert first_difference(page, page + "extra\n")[0] == 3


def main(argv):
    self_test()
    exe, src, work = (pathlib.Path(a) for a in argv)
    page = subprocess.run([sys.executable, str(src / "tools" / "paper_report.py"), "--exe",
                           str(exe), "--work", str(work)], capture_output=True, text=True,
                          check=True).stdout
    (work / "paper.md").write_text(page)
    found = first_difference((src / "docs" / "paper.md").read_text(), page)
    if found:
        line, want, got = found
        sys.exit(f"docs/paper.md:{line} differs from what tools/paper_report.py makes of the "
                 f"paper studies ({work / 'paper.md'}):\n  page:   {want}\n  script: {got}\n"
                 "Regenerate it: python3 tools/paper_report.py --exe BIN --work DIR > "
                 "docs/paper.md")
    print(f"docs/paper.md is current ({len(page.splitlines())} lines)")


if __name__ == "__main__":
    main(sys.argv[1:])
