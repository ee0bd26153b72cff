#!/usr/bin/env python3
"""docs/metrics.md's catalogue is `rkhs-study list metrics`.

Every study kind's metrics are one catalogue in the code (a MetricInfo row each: unit, floor
rule, whether NaN is legitimate, whether it is taken on the evaluation grid, its theory law, its
flag). `rkhs-study list metrics` prints it; docs/metrics.md holds the same rows between the
markers `<!-- catalogue: begin -->` and `<!-- catalogue: end -->`, one markdown table per kind.
This check fails when they differ: a metric added, removed, renamed or changed in the code
without the page, or the page edited by hand.

usage: check_metrics_doc.py BIN SRC            check
       check_metrics_doc.py BIN SRC --update   rewrite the page's catalogue from the listing
       check_metrics_doc.py --self-test        a removed or changed row is caught
"""
import re
import subprocess
import sys
from pathlib import Path

BEGIN = "<!-- catalogue: begin -->"
END = "<!-- catalogue: end -->"


def parse_listing(text):
    """{kind: [row, ...]} from `list metrics`; a row is a list of column texts."""
    kinds, kind, header = {}, None, None
    for line in text.splitlines():
        m = re.match(r"metrics \((\w+) trials\):$", line)
        if m:
            kind, header = m.group(1), None
            kinds[kind] = []
            continue
        if kind is None or not line.startswith("  "):
            continue
        cells = re.split(r"\s{2,}", line.strip())
        if header is None:
            header = cells
            continue
        if len(cells) != len(header):
            raise SystemExit(f"unexpected listing row: {line!r}")
        kinds[kind].append(cells)
    if not kinds:
        raise SystemExit("`list metrics` printed no catalogue")
    return kinds


def markdown(kinds):
    out = []
    for kind, rows in kinds.items():
        out.append(f"{kind.capitalize()} trials:\n")
        out.append("| metric | unit | floor | may be NaN | on the grid | theory | flag |")
        out.append("|---|---|---|---|---|---|---|")
        for name, unit, floor, nan, grid, theory, flag in rows:
            code = lambda t: "-" if t == "-" else f"`{t}`"
            out.append(f"| `{name}` | {unit} | `{floor}` | {nan} | {grid} | {code(theory)} | "
                       f"{code(flag)} |")
        out.append("")
    return "\n".join(out)


def section(page):
    if BEGIN not in page or END not in page:
        raise SystemExit(f"docs/metrics.md has no {BEGIN} ... {END} section")
    a = page.index(BEGIN) + len(BEGIN)
    return a, page.index(END)


def self_test():
    listing = ("metrics (approximation trials):\n"
               "  metric  unit  floor  NaN  grid  theory  flag\n"
               "  l2_error  [f] sqrt(m)  round_off  no  yes  error_l2_bound  l2_error_at_floor\n"
               "  fill_distance  m  exact  no  no  -  -\n")
    kinds = parse_listing(listing)
    page = f"x\n{BEGIN}\n{markdown(kinds)}{END}\n"
    a, b = section(page)
    assert page[a:b].strip() == markdown(kinds).strip()
    removed = {"approximation": kinds["approximation"][:1]}
    assert markdown(removed).strip() != page[a:b].strip(), "a removed row went unnoticed"
    changed = {"approximation": [kinds["approximation"][0],
                                 kinds["approximation"][1][:2] + ["round_off"] +
                                 kinds["approximation"][1][3:]]}
    assert markdown(changed).strip() != page[a:b].strip(), "a changed floor went unnoticed"
    print("self-test passed")


def main():
    if sys.argv[1:] == ["--self-test"]:
        return self_test()
    binary, source = sys.argv[1], Path(sys.argv[2])
    update = "--update" in sys.argv[3:]
    listing = subprocess.run([binary, "list", "metrics"], check=True, capture_output=True,
                             text=True).stdout
    expected = markdown(parse_listing(listing))
    path = source / "docs" / "metrics.md"
    page = path.read_text()
    a, b = section(page)
    if update:
        path.write_text(page[:a] + "\n" + expected + page[b:])
        print(f"{path}: catalogue rewritten")
        return 0
    if page[a:b].strip() != expected.strip():
        import difflib
        diff = difflib.unified_diff(page[a:b].strip().splitlines(), expected.strip().splitlines(),
                                    "docs/metrics.md", "rkhs-study list metrics", lineterm="")
        print("\n".join(diff))
        print("docs/metrics.md's catalogue differs from `rkhs-study list metrics`; run "
              "tests/docs/check_metrics_doc.py BIN . --update after changing a metric's row")
        return 1
    print(f"docs/metrics.md's catalogue matches `rkhs-study list metrics` "
          f"({sum(1 for l in expected.splitlines() if l.startswith('| `'))} metrics)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
