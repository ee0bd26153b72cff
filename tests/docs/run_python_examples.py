#!/usr/bin/env python3
"""Runs every ```python block of docs/python.md, so the page's examples are code that works.

Each block runs on its own, in a fresh interpreter (the one running this script), in an empty
folder that holds a link `studies` to the repository's studies/ (the examples name
"studies/gram_and_power.toml" as a reader in the repository's root would), with matplotlib's
Agg backend. The package comes from PYTHONPATH (the build's python/ folder, as ctest sets it).
A block that raises fails the check: the examples assert what they claim.

Usage: run_python_examples.py PAGE REPOSITORY WORK_FOLDER
Exit status 0 when every block ran without an error.
"""
import os
import pathlib
import re
import shutil
import subprocess
import sys

BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def main() -> int:
    page, repository, work = (pathlib.Path(a) for a in sys.argv[1:4])
    text = page.read_text()
    blocks = [(text.count("\n", 0, m.start()) + 1, m.group(1)) for m in BLOCK.finditer(text)]
    if not blocks:
        print(f"{page}: no ```python block")
        return 1
    failed = 0
    for line, code in blocks:
        folder = work / f"block-{line}"
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
        (folder / "studies").symlink_to(repository / "studies")
        (folder / "results").mkdir()
        env = dict(os.environ, MPLBACKEND="Agg")
        run = subprocess.run([sys.executable, "-c", code], cwd=folder, env=env,
                             capture_output=True, text=True)
        if run.returncode != 0:
            failed += 1
            print(f"{page}:{line}: the block failed (exit {run.returncode})\n{run.stderr}")
        else:
            print(f"{page}:{line}: ran")
    print(f"{len(blocks) - failed} of {len(blocks)} blocks ran")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
