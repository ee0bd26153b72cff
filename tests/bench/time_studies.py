#!/usr/bin/env python3
"""Times every shipped study and writes the figures README.md's studies table quotes.

Usage: time_studies.py RKHS_STUDY SOURCE_DIR [--study NAME ...] [--threads N]

Runs `rkhs-study run studies/NAME.toml --threads N --fresh --no-plots --quiet` (N = 2 unless
given) for every study of SOURCE_DIR/studies (or the ones named), one after the other, each with
a store and output folder of its own in a temporary folder, and records in
SOURCE_DIR/docs/study-times.json, beside the figures of the studies not run:

  trials        the trials the study ran (its summary line)
  wall_seconds  the wall time of the whole command (start-up, every trial, fits and outputs)
  cpu_seconds   the processor time of the command, summed over its threads
  study_sha256  the study file's SHA-256 when it was timed
  rkhs_study    `rkhs-study --version` of the binary timed
  date          the day it was timed

and, for the file as a whole, the command, the processor and the core count (a study timed on
another processor has its own `processor`).
tests/docs/check_readme.py checks that README's "time" column quotes these figures and that no
study file changed since it was timed (its SHA-256), so a timing cannot drift from the study it
describes: after changing a study, run this script with --study NAME.

Time it on an otherwise idle machine: the figures are of one run, not a benchmark's median,
and say so in the README. Standard library only.
"""
import argparse
import datetime
import hashlib
import json
import os
import pathlib
import platform
import re
import resource
import subprocess
import sys
import tempfile
import time

OUTPUT = "docs/study-times.json"
SUMMARY = re.compile(r"^(\S+): (\d+) trials, (\d+) ok, (\d+) failed in ", re.MULTILINE)


def processor():
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def time_study(executable, version, study, threads, work):
    folder = work / study.stem
    folder.mkdir()
    command = [executable, "run", str(study), "--threads", str(threads), "--fresh", "--no-plots",
               "--quiet", "--out", str(folder / "out"), "--store", str(folder / "store.sqlite")]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.monotonic()
    result = subprocess.run(command, capture_output=True, text=True)
    wall = time.monotonic() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    summary = SUMMARY.search(result.stdout)
    if not summary or result.returncode not in (0, 1):
        raise RuntimeError(f"{' '.join(command)} exited {result.returncode}:\n"
                           f"{result.stdout}{result.stderr}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"trials": int(summary.group(2)), "wall_seconds": round(wall, 3),
            "cpu_seconds": round(cpu, 3),
            "study_sha256": hashlib.sha256(study.read_bytes()).hexdigest(),
            "rkhs_study": version, "date": datetime.date.today().isoformat()}


def main():
    parser = argparse.ArgumentParser(usage=__doc__.split("\n\n")[1])
    parser.add_argument("executable")
    parser.add_argument("source", type=pathlib.Path)
    parser.add_argument("--study", action="append", default=[])
    parser.add_argument("--threads", type=int, default=2)
    arguments = parser.parse_args()
    executable = str(pathlib.Path(arguments.executable).resolve())
    studies = sorted((arguments.source / "studies").glob("*.toml"))
    if arguments.study:
        unknown = set(arguments.study) - {study.stem for study in studies}
        if unknown:
            parser.error(f"no study {', '.join(sorted(unknown))} in {arguments.source}/studies")
        studies = [study for study in studies if study.stem in arguments.study]
    output = arguments.source / OUTPUT
    figures = json.loads(output.read_text()) if output.exists() else {}
    version = subprocess.run([executable, "--version"], capture_output=True, text=True)
    # The processor of the file is that of the studies without their own "processor": a study
    # timed on another machine says which (the README's times are of the same size, not ratios).
    figures.setdefault("processor", processor())
    figures.update({
        "command": f"rkhs-study run STUDY --threads {arguments.threads} --fresh --no-plots --quiet",
        "cores": os.cpu_count(),
    })
    times = figures.setdefault("studies", {})
    with tempfile.TemporaryDirectory(prefix="rkhs_time_studies.") as work:
        for study in studies:
            entry = time_study(executable, version.stdout.strip(), study, arguments.threads,
                               pathlib.Path(work))
            if processor() != figures["processor"]:
                entry["processor"] = processor()
            times[study.stem] = entry
            print(f"{study.stem}: {entry['trials']} trials, {entry['wall_seconds']:.2f} s wall, "
                  f"{entry['cpu_seconds']:.2f} s cpu", flush=True)
            # Written after each study, so nothing measured is lost; the studies in name order.
            output.write_text(json.dumps({**figures, "studies": dict(sorted(times.items()))},
                                         indent=2) + "\n")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except RuntimeError as error:
        print(f"time_studies.py: {error}", file=sys.stderr)
        sys.exit(1)
