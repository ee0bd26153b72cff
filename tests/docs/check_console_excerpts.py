#!/usr/bin/env python3
"""Checks the console excerpts of a Markdown page against real runs (console_excerpts.py).

Usage: check_console_excerpts.py RKHS_STUDY PAGE BASE_DIR WORK_DIR [--variant WORD]
                                 [--replace OLD=NEW ...]

Every excerpt of PAGE marked `<!-- console: rkhs-study ARGS -->` (or, with --variant WORD,
`<!-- console WORD: rkhs-study ARGS -->`) is run as `RKHS_STUDY ARGS` in a fresh folder of
WORK_DIR linking BASE_DIR's entries, and compared with what it prints. tests/plugin/
install_and_build_plugin.sh runs it on docs/writing-a-kernel.md with BASE_DIR its copy of
examples/kernel-plugin/ and the plugin built there, so the page's output is the output of the
installed package and the plugin it describes.

Exit status 0 when every excerpt matches (at least one must be checked), 1 otherwise with one
paragraph per excerpt that does not, 2 for bad arguments. Standard library only.
"""
import argparse
import pathlib
import sys

import console_excerpts


def main():
    parser = argparse.ArgumentParser(usage=__doc__.split("\n\n")[1])
    parser.add_argument("executable")
    parser.add_argument("page", type=pathlib.Path)
    parser.add_argument("base", type=pathlib.Path)
    parser.add_argument("work", type=pathlib.Path)
    parser.add_argument("--variant")
    parser.add_argument("--replace", action="append", default=[], metavar="OLD=NEW")
    arguments = parser.parse_args()
    replacements = []
    for pair in arguments.replace:
        if "=" not in pair:
            parser.error(f"--replace {pair}: expected OLD=NEW")
        replacements.append(tuple(pair.split("=", 1)))
    console_excerpts.self_test()
    page = arguments.page.read_text(encoding="utf-8")
    problems = []
    count = console_excerpts.check(arguments.page.name, page, str(pathlib.Path(
        arguments.executable).resolve()), arguments.base, arguments.work, problems,
                                   arguments.variant, replacements)
    what = f"console excerpt{'s' if count != 1 else ''}" + (
        f" ({arguments.variant})" if arguments.variant else "")
    if count == 0:
        print(f"{arguments.page}: no {what} to check")
        return 1
    if problems:
        print("\n".join(problems))
        print(f"{len(problems)} of {count} {what} of {arguments.page} do not match the output")
        return 1
    print(f"{arguments.page}: {count} {what} {'match' if count != 1 else 'matches'} the output")
    return 0


if __name__ == "__main__":
    sys.exit(main())
