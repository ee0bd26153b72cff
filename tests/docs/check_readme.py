#!/usr/bin/env python3
"""Keeps README.md honest where that is cheap to check.

- Studies: every studies/*.toml is a row of README's studies table ("## Studies"), and every
  study the table names exists.
- Commands: every `rkhs-study <subcommand>` of README's "## Using it" block is a subcommand that
  `rkhs-study --help` lists, and every subcommand `--help` lists is mentioned in README as
  `rkhs-study <subcommand>`.
- Outputs: the outputs table ("A run writes ...") names exactly the files and directories that
  `rkhs-study run` writes, found by running a tiny approximation study and a tiny adaptive
  study; rows whose text starts with "adaptive studies only" name exactly what the adaptive
  study adds.
- Times: the studies table's `trials, time` column quotes docs/study-times.json (written by
  tests/bench/time_studies.py, which times each study), and no study file changed since it was
  timed (its SHA-256 there). `--update-times` rewrites the column from that file instead.
- Links: every relative link of README and every docs/*.md it names exists.
- Console excerpts: a fenced block that follows a line `<!-- console: rkhs-study ARGS -->` is
  what `rkhs-study ARGS` prints on standard output, run in a folder of WORK_DIR beside the
  repository's files (a fresh store): its lines appear in the output in order, a line `...`
  stands for any number of lines, and a duration (`0.17 s`) matches any duration
  (tests/docs/console_excerpts.py, which docs/writing-a-kernel.md's excerpts share).

Usage: check_readme.py RKHS_STUDY_EXECUTABLE SOURCE_DIR WORK_DIR
       check_readme.py --update-times SOURCE_DIR
Exit status 0 when README is current; otherwise 1, with one line per problem naming what is
missing or extra and where.
"""
import hashlib
import json
import pathlib
import re
import shutil
import subprocess
import sys

import console_excerpts

APPROXIMATION_STUDY = """[study]
name = "readme_approximation"
evaluation_points = 256
[domain]
radius = 4.0
[grid]
n = [8, 16, 32]
[[kernel]]
name = "bspline"
degree = 1
"""

# A scalar plant, one lap at 1 m/s: a fraction of a second. road = "projection" keeps every
# adaptive metric finite, so every plot can be drawn.
ADAPTIVE_STUDY = """[study]
name = "readme_adaptive"
kind = "adaptive"
evaluation_points = 128
[domain]
radius = 4.0
[grid]
n = [4, 6, 8]
[[kernel]]
name = "gaussian"
sigma = 1.0
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "rkhs"
gamma = 0.1
[adaptive]
speed = 1.0
laps = 1
road = "projection"
snapshot_laps = [1]
snapshot_points = 64
"""

ADAPTIVE_ONLY = "adaptive studies only"


def section(readme, heading):
    """The text of the `## heading` section, up to the next `## ` heading ('' if absent)."""
    match = re.search(r"^## " + re.escape(heading) + r"[ \t]*\n(.*?)(?=^## |\Z)", readme,
                      re.MULTILINE | re.DOTALL)
    return match.group(1) if match else ""


def table_rows(text):
    """Cells of the Markdown table rows in `text` (header and separator rows included)."""
    rows = []
    for line in text.splitlines():
        if line.startswith("|"):
            # Split on pipes that are not escaped (\|).
            cells = [cell.strip() for cell in re.split(r"(?<!\\)\|", line.strip())[1:-1]]
            rows.append(cells)
    return rows


def check_studies(readme, source, problems):
    rows = table_rows(section(readme, "Studies"))
    named = set()
    for cells in rows:
        if cells:
            named.update(re.findall(r"`(studies/[^`]+\.toml)`", cells[0]))
    if not named:
        problems.append("README.md: no studies table found in the '## Studies' section")
    present = {f"studies/{path.name}" for path in (source / "studies").glob("*.toml")}
    for study in sorted(present - named):
        problems.append(f"README.md: {study} is not in the studies table ('## Studies'); add a "
                        f"row for it")
    for study in sorted(named - present):
        problems.append(f"README.md: the studies table names {study}, which does not exist")
    return len(present)


def help_subcommands(executable):
    result = subprocess.run([executable, "--help"], capture_output=True, text=True, timeout=60)
    if result.returncode != 0:
        raise RuntimeError(f"`rkhs-study --help` exited {result.returncode}:\n{result.stderr}")
    subcommands, inside = [], False
    for line in result.stdout.splitlines():
        if line.strip() == "Subcommands:":
            inside = True
        elif inside and not line.strip():
            break
        elif inside:
            match = re.match(r"^\s+([a-z][a-z0-9-]*)\s", line)
            if match:
                subcommands.append(match.group(1))
    if not subcommands:
        raise RuntimeError("`rkhs-study --help` lists no subcommands:\n" + result.stdout)
    return subcommands


def check_commands(readme, executable, problems):
    listed = help_subcommands(executable)
    using = section(readme, "Using it")
    block = re.search(r"```sh\n(.*?)```", using, re.DOTALL)
    if not block:
        problems.append("README.md: no ```sh block in the '## Using it' section")
        used = []
    else:
        used = re.findall(r"rkhs-study\s+([a-z][a-z0-9-]*)", block.group(1))
    for command in sorted(set(used) - set(listed)):
        problems.append(f"README.md: the 'Using it' block runs `rkhs-study {command}`, which "
                        f"`rkhs-study --help` does not list (it lists: {', '.join(listed)})")
    for command in listed:
        if not re.search(r"rkhs-study\s+" + re.escape(command) + r"\b", readme):
            problems.append(f"README.md: `rkhs-study {command}` (listed by `rkhs-study --help`) "
                            f"is not mentioned")
    return len(listed)


def run_study(executable, work, name, text, problems):
    """Runs a study file with `text` in `work`; returns the entries of its output directory."""
    study = work / f"{name}.toml"
    study.write_text(text)
    out = work / name
    command = [executable, "run", str(study), "--out", str(out), "--store",
               str(work / "store.sqlite"), "--threads", "2", "--quiet"]
    result = subprocess.run(command, cwd=work, capture_output=True, text=True, timeout=120)
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} exited {result.returncode}:\n"
                           f"{result.stdout}{result.stderr}")
    if "warning" in result.stderr:
        # Not a README problem, but the outputs may then be incomplete: say so.
        print(f"note: {name}: {result.stderr.strip()}")
    return {entry.name + ("/" if entry.is_dir() else "") for entry in out.iterdir()}


def check_outputs(readme, executable, work, problems):
    marker = readme.find("A run writes")
    if marker < 0:
        problems.append("README.md: no outputs table (the paragraph 'A run writes ...')")
        return 0
    after = readme[marker:]
    table = re.search(r"((?:^\|.*\n)+)", after, re.MULTILINE)
    rows = table_rows(table.group(1)) if table else []
    everywhere, adaptive_only = set(), set()
    for cells in rows[2:]:  # after the header and separator rows
        if len(cells) < 2:
            continue
        names = set(re.findall(r"`([^`]+)`", cells[0]))
        (adaptive_only if cells[1].startswith(ADAPTIVE_ONLY) else everywhere).update(names)
    if not everywhere:
        problems.append("README.md: the outputs table ('A run writes ...') has no rows")
    approximation = run_study(executable, work, "readme_approximation", APPROXIMATION_STUDY,
                              problems)
    adaptive = run_study(executable, work, "readme_adaptive", ADAPTIVE_STUDY, problems)
    written = approximation | adaptive
    named = everywhere | adaptive_only
    for entry in sorted(written - named):
        kind = "every study" if entry in approximation else "an adaptive study"
        problems.append(f"README.md: the outputs table does not name `{entry}`, which "
                        f"`rkhs-study run` writes for {kind}")
    for entry in sorted(named - written):
        problems.append(f"README.md: the outputs table names `{entry}`, which `rkhs-study run` "
                        f"did not write (approximation study: {', '.join(sorted(approximation))};"
                        f" adaptive study adds: {', '.join(sorted(adaptive - approximation))})")
    for entry in sorted(adaptive_only & approximation):
        problems.append(f"README.md: the outputs table marks `{entry}` '{ADAPTIVE_ONLY}', but an "
                        f"approximation study writes it too")
    for entry in sorted((adaptive - approximation) & everywhere):
        problems.append(f"README.md: `{entry}` is written only for adaptive studies; its row in "
                        f"the outputs table should start with '{ADAPTIVE_ONLY}'")
    return len(written)


STUDY_TIMES = "docs/study-times.json"


def duration_text(seconds):
    """Two significant digits below 10 s, whole seconds below 2 min, then minutes."""
    if seconds < 10:
        return f"{seconds:.2g} s"
    if seconds < 120:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.1f} min"


def time_cell(entry):
    return f"{entry['trials']} trials, {duration_text(entry['wall_seconds'])}"


def study_times(source):
    path = source / STUDY_TIMES
    if not path.exists():
        raise RuntimeError(f"no {STUDY_TIMES}: run tests/bench/time_studies.py RKHS_STUDY {source}")
    return json.loads(path.read_text())["studies"]


def check_times(readme, source, problems):
    """The studies table's time column against docs/study-times.json (module docstring)."""
    times = study_times(source)
    checked = 0
    for cells in table_rows(section(readme, "Studies"))[2:]:
        named = re.findall(r"`studies/([^`]+)\.toml`", cells[0]) if cells else []
        if not named:
            continue
        name = named[0]
        entry = times.get(name)
        if entry is None:
            problems.append(f"README.md: {STUDY_TIMES} has no time of studies/{name}.toml; run "
                            f"tests/bench/time_studies.py RKHS_STUDY . --study {name}")
            continue
        sha = hashlib.sha256((source / "studies" / f"{name}.toml").read_bytes()).hexdigest()
        if sha != entry["study_sha256"]:
            problems.append(f"README.md: studies/{name}.toml changed since {STUDY_TIMES} timed it; "
                            f"run tests/bench/time_studies.py RKHS_STUDY . --study {name} and "
                            f"check_readme.py --update-times .")
        if len(cells) < 3 or cells[2] != time_cell(entry):
            found = cells[2] if len(cells) >= 3 else "no such column"
            problems.append(f"README.md: the studies table gives studies/{name}.toml "
                            f"'{found}', {STUDY_TIMES} '{time_cell(entry)}' (run check_readme.py "
                            f"--update-times .)")
        checked += 1
    return checked


def update_times(source):
    """Rewrites the last cell of each row of the studies table from docs/study-times.json."""
    path = source / "README.md"
    times = study_times(source)
    lines = path.read_text(encoding="utf-8").split("\n")
    for i, line in enumerate(lines):
        named = re.match(r"^\| `studies/([^`]+)\.toml`", line)
        if named and named.group(1) in times:
            body = re.sub(r"(?<!\\)\|[^|]*\|\s*$", "|", line.rstrip())
            lines[i] = f"{body} {time_cell(times[named.group(1)])} |"
    path.write_text("\n".join(lines), encoding="utf-8")


def check_links(readme, source, problems):
    targets = set()
    for target in re.findall(r"\]\(([^)\s]+)\)", readme):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
            continue  # a URL or an anchor of this page
        targets.add(target.split("#", 1)[0])
    targets.update(re.findall(r"(?<![\w/.-])(docs/[\w.-]+\.md)", readme))
    for target in sorted(targets):
        if not (source / target).exists():
            problems.append(f"README.md: links to {target}, which does not exist")
    return len(targets)


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--update-times":
        update_times(pathlib.Path(sys.argv[2]))
        return 0
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    executable = str(pathlib.Path(sys.argv[1]).resolve())  # the studies run in WORK_DIR
    source, work = pathlib.Path(sys.argv[2]), pathlib.Path(sys.argv[3])
    readme = (source / "README.md").read_text(encoding="utf-8")
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    problems = []
    studies = check_studies(readme, source, problems)
    commands = check_commands(readme, executable, problems)
    outputs = check_outputs(readme, executable, work, problems)
    times = check_times(readme, source, problems)
    links = check_links(readme, source, problems)
    console_excerpts.self_test()
    excerpts = console_excerpts.check("README.md", readme, executable, source, work, problems)
    if problems:
        print("\n".join(problems))
        print(f"{len(problems)} problem{'s' if len(problems) > 1 else ''}: README.md does not "
              f"match the repository or `rkhs-study`")
        return 1
    print(f"README.md is current: {studies} studies, {commands} subcommands, {outputs} outputs, "
          f"{times} study times, {links} links and {excerpts} console excerpt{'s' if excerpts != 1 else ''} checked")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except (RuntimeError, subprocess.TimeoutExpired) as error:
        print(f"check_readme.py: {error}")
        sys.exit(1)
