#!/usr/bin/env python3
"""Behaviour of every shipped study, pinned: trials.csv, rates.csv and the verdicts of
`rkhs-study check` for each studies/*.toml are compared with the golden files in
tests/golden/studies/<study>/.

Adaptive studies run on a short horizon (one lap, one snapshot; a laps axis becomes one lap and
the limit) so the whole check takes a few minutes on two cores; approximation studies run as
shipped. Numbers must agree to 1e-9 relative: the last digits of a double depend on the
processor (glibc picks its exp, log and sin by CPU features at run time, and Eigen its kernels
at build time; rkhs-study's own run-time choice of dense kernels is fixed to the baseline here,
DENSE_KERNELS), so a refactoring that changes no formula stays well inside that, while a change
of method does not. Values that ill-conditioned computations leave at round-off also agree
within 1e-7 of their column's largest magnitude (COLUMN_ROUND_OFF; fits through them are then
reported, not compared), and flat fits are not compared on R^2 and AIC (FLAT_FIT). Text must match exactly. Columns may be added, never removed, renamed or
changed; rows must match in number and order. Verdicts must match line for line, except the
first line's wall time.

Usage:
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR                 compare every study
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR --study NAME    compare studies/NAME.toml
                                                                          (ctest: golden.NAME)
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR --stale         only: no golden files
                                                                          for a study not shipped
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR --record        write the golden files
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR --study NAME --record
                                                                          write NAME's only
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR --study NAME --sanitizer
                                                                          NAME as a sanitizer build
                                                                          checks it (below)

Under a sanitizer (--sanitizer; the asan and tsan builds pass it), a study in SANITIZER_GRIDS
runs on a smaller grid of n: the same code paths, but its largest systems cost hours under ASan
+ UBSan (paper_converged's lap maps at n = 100). Each trial it runs is compared with its row of
the golden trials.csv (same columns, same order); rates.csv and the verdicts are fits and
checks over the whole grid, so they are not compared, and the check says so.

The plots are rendered too (the run is made with plots), and every one is checked: each
plots/<stem>.gp has its .svg (well-formed XML), .png (a valid PNG of sane size, not one
uniform colour: decoded here, zlib and the PNG filters) and .pdf (a PDF whose cross-reference
offset points at its table). For the studies in PLOT_GOLDEN_STUDIES the gnuplot scripts
themselves are pinned as well, against tests/golden/plots/<study>/<stem>.gp: the same files,
numbers within 1e-9 relative, the rest exactly. Without gnuplot on PATH the plots are not
checked (a note says so).

Record only when a change of behaviour is intended, and say why in the commit.
Standard library only.
"""
import collections
import csv
import itertools
import math
import os
import pathlib
import re
import shutil
import struct
import subprocess
import sys
import xml.etree.ElementTree
import zlib

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


# Study -> (the [grid] n line of the shipped study, the line a sanitizer build runs instead, the
# values of n it keeps). paper_converged: more than two hours under ASan + UBSan at n = 10..100
# on 2 cores (docs/sanitizers.md), n = 10..40 keeps every kernel, law and horizon.
SANITIZER_GRIDS = {
    "paper_converged": ("n = { from = 10, to = 100, step = 10 }",
                        "n = { from = 10, to = 40, step = 10 }", {"10", "20", "30", "40"}),
}


def sanitizer_grid(study, text):
    """The study's text on its sanitizer grid, and the values of n kept (None: unchanged)."""
    if study.stem not in SANITIZER_GRIDS:
        return text, None
    shipped, smaller, kept = SANITIZER_GRIDS[study.stem]
    if text.count(shipped) != 1:
        raise SystemExit(f"{study}: expected the line '{shipped}' once (SANITIZER_GRIDS in {__file__})")
    return text.replace(shipped, smaller), kept


def run_study(exe, source, work, study, sanitizer=False):
    """Runs `check` on the (shortened) study; returns the output folder, the verdict lines and
    the values of n kept on a sanitizer grid (None: the whole grid ran)."""
    name = study.stem
    work.mkdir(parents=True, exist_ok=True)
    definition = work / f"{name}.toml"
    text, kept = sanitizer_grid(study, study.read_text()) if sanitizer else (study.read_text(), None)
    definition.write_text(shortened(text))
    out = work / name
    shutil.rmtree(out, ignore_errors=True)
    # The baseline dense kernels (rkhs/approx/dense_kernels.hpp): the golden files do not depend
    # on the processor's vector width, which moves ill-conditioned values in their last digits
    # (the tests of the dense kernels compare every variant with the baseline).
    environment = dict(os.environ, RKHS_STUDY_DENSE_KERNELS=DENSE_KERNELS)
    result = subprocess.run(
        [exe, "check", "--no-store", "--quiet", "--threads", "2", "--out", name,
         "--data-dir", str(source / "studies" / "data"), definition.name],
        cwd=work, capture_output=True, text=True, check=False, env=environment)
    # 0 all pass, 1 a failure, 3 inconclusive: short horizons fail some expectations, and that
    # is pinned too. 2 (bad input) or a crash is an error of this check.
    if result.returncode not in (0, 1, 3):
        raise SystemExit(f"{name}: rkhs-study check exited {result.returncode}\n{result.stderr}")
    lines = result.stdout.splitlines()
    if lines:
        lines[0] = WALL_TIME.sub("", lines[0])
    return out, lines, kept


def read_csv(path):
    with open(path, newline="", encoding="utf-8") as handle:
        rows = list(csv.reader(handle))
    if not rows:
        raise SystemExit(f"{path}: empty")
    return rows[0], rows[1:]


RELATIVE_TOLERANCE = 1e-9

# The dense kernels the studies run with (RKHS_STUDY_DENSE_KERNELS): the baseline x86-64 ones,
# which every x86-64 processor runs, so that the files pin behaviour, not vector width.
DENSE_KERNELS = "x86-64"


# The fit statistics of rates.csv are dimensionless numbers of order one (slopes, their standard
# errors and intervals, R^2, AIC differences): a slope of 6.2e-5 against 6.2025e-5 is the same
# flat series on two processors, so they also match within an absolute 1e-6.
FIT_COLUMNS = {"rate", "std_error", "ci_low", "ci_high", "r_squared", "delta_aic"}
FIT_ABSOLUTE_TOLERANCE = 1e-6

# Round-off of ill-conditioned computations. A value of trials.csv also matches within 1e-7 of
# the largest magnitude in its golden column: a Gram matrix of condition up to 1e9 (Wendland
# k = 2 at n = 1024 in 2-D) leaves that much of the quantity's scale in round-off, and processors
# differ there (the L2 projection of a Gaussian trial at n = 50, 3.3e-9 on one machine and 1.8e-9
# on another, is round-off of a quantity of order 1; ||Pi||_{H -> H}, 1 in exact arithmetic, is
# 1 + 1.6e-7 on one and 1 + 1.8e-7 on the other). A fit through such a value may fit round-off:
# a rates.csv row of that metric and trial group that differs is reported as not compared.
COLUMN_ROUND_OFF = 1e-7

# A fit whose rate and interval lie within 1e-3 of 0 is a flat series: its R^2 and AIC difference
# measure the scatter of values equal to a few parts in 1e4 or better, which processors round
# differently, so those two are not compared for it (the rate and interval are, within
# FIT_ABSOLUTE_TOLERANCE).
FLAT_FIT = 1e-3


def column_scales(header, rows):
    """The largest finite magnitude in each column (0 for text)."""
    scales = {}
    for index, column in enumerate(header):
        largest = 0.0
        for row in rows:
            try:
                value = abs(float(row[index]))
            except (ValueError, IndexError):
                continue
            if math.isfinite(value):
                largest = max(largest, value)
        scales[column] = largest
    return scales


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


def compare_csv(golden_path, actual_path, kept_n=None, round_off=None, skipped=None):
    """Differences between two CSV files, golden columns only (added columns are allowed); with
    kept_n, only the golden rows whose n is in it (a sanitizer grid).

    trials.csv: numbers also match within COLUMN_ROUND_OFF of their column's scale; each
    (metric, trial group) matched only so is added to the set `round_off`. rates.csv: a row that
    differs and whose metric and group are in `round_off` is not a problem but described in
    `skipped`; flat fits (FLAT_FIT) are not compared on r_squared and delta_aic."""
    golden_header, golden_rows = read_csv(golden_path)
    actual_header, actual_rows = read_csv(actual_path)
    problems = []
    is_rates = actual_path.name == "rates.csv"
    scales = column_scales(golden_header, golden_rows) if not is_rates else {}
    if kept_n is not None:
        if "n" not in golden_header:
            return [f"{golden_path}: no column n to select the sanitizer grid's rows by"]
        golden_rows = [row for row in golden_rows if row[golden_header.index("n")] in kept_n]
    missing = [c for c in golden_header if c not in actual_header]
    if missing:
        problems.append(f"{actual_path}: columns removed or renamed: {', '.join(missing)}")
        return problems
    if len(golden_rows) != len(actual_rows):
        problems.append(f"{actual_path}: {len(actual_rows)} rows, golden has {len(golden_rows)}")
        return problems
    where = {c: actual_header.index(c) for c in golden_header}
    # The group of a trial: its axis columns without n (those rates.csv has before `metric`).
    group_columns = []
    for number, (golden, actual) in enumerate(zip(golden_rows, actual_rows), start=2):
        if is_rates:
            row = dict(zip(golden_header, golden))
            axes = golden_header[:golden_header.index("metric")]
            key = (row["metric"], tuple(row[c] for c in axes))
            through_round_off = round_off is not None and key in round_off
            problems_before = len(problems)
            try:
                flat = max(abs(float(row[c])) for c in ("rate", "ci_low", "ci_high")) <= FLAT_FIT
            except ValueError:
                flat = False
        for column, value in zip(golden_header, golden):
            found = actual[where[column]]
            if is_rates and flat and column in ("r_squared", "delta_aic"):
                continue
            if not is_rates and not same_value(value, found) and round_off is not None:
                try:
                    difference = abs(float(value) - float(found))
                except ValueError:
                    difference = math.inf
                if difference <= COLUMN_ROUND_OFF * scales.get(column, 0.0):
                    if not group_columns:
                        group_columns = round_off_axes(golden_path)
                    row = dict(zip(golden_header, golden))
                    round_off.add((column, tuple(row.get(c, "") for c in group_columns)))
                    continue
            if not same_value(value, found, column if is_rates else ""):
                problems.append(f"{actual_path}:{number}: column {column}: found '{found}', "
                                f"golden '{value}'")
                if len(problems) >= 20 and not (is_rates and through_round_off):
                    return problems + ["(more differences not shown)"]
        if is_rates and through_round_off and len(problems) > problems_before:
            del problems[problems_before:]
            if skipped is not None:
                skipped.append(f"line {number}: {row['metric']} {row['kind']} {row['model']} "
                               f"({', '.join(f'{c}={row[c]}' for c in axes if row[c])})")
    return problems


# The studies whose gnuplot scripts are pinned (tests/golden/plots/<study>/): iso8608 has the
# grid of panels (84 groups), legends and ranges of a real study.
def round_off_axes(trials_path):
    """The axis columns of the study's rates.csv beside trials.csv (those before `metric`)."""
    header, _ = read_csv(trials_path.with_name("rates.csv"))
    return header[:header.index("metric")] if "metric" in header else []


PLOT_GOLDEN_STUDIES = {"iso8608"}
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def compare_script(golden_path, actual_path):
    """Differences between two gnuplot scripts: numbers within RELATIVE_TOLERANCE, the rest
    exactly, line by line."""
    golden = golden_path.read_text().splitlines()
    actual = actual_path.read_text().splitlines()
    if len(golden) != len(actual):
        return [f"{actual_path}: {len(actual)} lines, golden has {len(golden)}"]
    problems = []
    for number, (want, got) in enumerate(zip(golden, actual), start=1):
        if want == got:
            continue
        want_numbers, got_numbers = NUMBER.findall(want), NUMBER.findall(got)
        same = (NUMBER.sub("#", want) == NUMBER.sub("#", got)
                and len(want_numbers) == len(got_numbers)
                and all(same_value(a, b) for a, b in zip(want_numbers, got_numbers)))
        if not same:
            at = next((i for i, (a, b) in enumerate(zip(want, got)) if a != b),
                      min(len(want), len(got)))
            start = max(0, at - 60)
            problems.append(f"{actual_path}:{number}, column {at + 1}: found "
                            f"'...{got[start:at + 80]}', golden '...{want[start:at + 80]}'")
            if len(problems) >= 10:
                return problems + ["(more differences not shown)"]
    return problems


def add_bytes(a, b):
    """(a + b) mod 256 byte by byte, in one big-integer operation (no carries between bytes)."""
    n = len(a)
    low, high = int.from_bytes(b"\x7f" * n, "big"), int.from_bytes(b"\x80" * n, "big")
    x, y = int.from_bytes(a, "big"), int.from_bytes(b, "big")
    return (((x & low) + (y & low)) ^ ((x ^ y) & high)).to_bytes(n, "big")


def png_image(path):
    """(width, height, channels, pixel bytes) of an 8-bit PNG (grey, RGB, palette, with or
    without alpha, not interlaced): chunks and CRCs checked, zlib, the five PNG filters undone."""
    data = path.read_bytes()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("no PNG signature")
    position, chunks, idat = 8, {}, b""
    while position < len(data):
        length, kind = struct.unpack(">I4s", data[position:position + 8])
        body = data[position + 8:position + 8 + length]
        crc, = struct.unpack(">I", data[position + 8 + length:position + 12 + length])
        if zlib.crc32(kind + body) != crc:
            raise ValueError(f"bad CRC in chunk {kind!r}")
        if kind == b"IDAT":
            idat += body
        else:
            chunks.setdefault(kind, body)
        position += 12 + length
        if kind == b"IEND":
            break
    if b"IHDR" not in chunks or b"IEND" not in chunks or not idat:
        raise ValueError("IHDR, IDAT or IEND missing")
    width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", chunks[b"IHDR"])
    channels = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}.get(colour)
    if depth != 8 or channels is None or interlace != 0:
        raise ValueError(f"unsupported PNG: depth {depth}, colour type {colour}, interlace {interlace}")
    raw = zlib.decompress(idat)
    stride = width * channels
    if len(raw) != height * (stride + 1):
        raise ValueError(f"{len(raw)} bytes of image data, {height * (stride + 1)} expected")
    pixels, previous = bytearray(), bytes(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        row = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if kind == 1:  # Sub: a running sum per channel
            for c in range(channels):
                row[c::channels] = bytes(map((255).__and__, itertools.accumulate(row[c::channels])))
        elif kind == 2:  # Up
            row = bytearray(add_bytes(row, previous))
        elif kind in (3, 4):  # Average, Paeth: byte by byte
            for i in range(stride):
                left = row[i - channels] if i >= channels else 0
                up = previous[i]
                if kind == 3:
                    row[i] = (row[i] + (left + up) // 2) & 255
                    continue
                corner = previous[i - channels] if i >= channels else 0
                estimate = left + up - corner
                pa, pb, pc = abs(estimate - left), abs(estimate - up), abs(estimate - corner)
                predictor = left if pa <= pb and pa <= pc else up if pb <= pc else corner
                row[i] = (row[i] + predictor) & 255
        elif kind != 0:
            raise ValueError(f"unknown filter {kind} in row {y}")
        pixels += row
        previous = bytes(row)
    return width, height, channels, bytes(pixels)


# A plot is not blank: more than this share of its pixels differ from the commonest colour.
LEAST_INK = 0.01


def check_png(path):
    width, height, channels, pixels = png_image(path)
    if not (200 <= width <= 8000 and 150 <= height <= 8000):
        return [f"{path}: {width} x {height} pixels is not a sane plot size"]
    # The background: the commonest colour of a sample of pixels; then every pixel of that
    # colour counted, channel by channel, as bits of big integers.
    sample = collections.Counter(pixels[i:i + channels]
                                 for i in range(0, len(pixels), channels * 101))
    background = sample.most_common(1)[0][0]
    same = -1
    for c in range(channels):
        table = bytes(1 if value == background[c] else 0 for value in range(256))
        bits = int.from_bytes(pixels[c::channels].translate(table), "big")
        same = bits if same < 0 else same & bits
    ink = 1 - same.bit_count() / (width * height)
    if ink <= LEAST_INK:
        return [f"{path}: blank ({ink:.2%} of the pixels differ from the background)"]
    return []


def check_pdf(path):
    data = path.read_bytes()
    if not data.startswith(b"%PDF-1.") or b"%%EOF" not in data[-64:]:
        return [f"{path}: not a PDF (header or %%EOF missing)"]
    found = re.search(rb"startxref\s+(\d+)\s+%%EOF\s*$", data)
    if not found:
        return [f"{path}: no startxref"]
    offset = int(found.group(1))
    if not (data[offset:offset + 4] == b"xref" or re.match(rb"\d+ \d+ obj", data[offset:offset + 32])):
        return [f"{path}: startxref {offset} does not point at a cross-reference table"]
    if not re.search(rb"/Type\s*/Page[^s]", data):
        return [f"{path}: no page"]
    return []


def check_plots(out, study, source, record):
    """The rendered plots of a run (and, for PLOT_GOLDEN_STUDIES, their scripts)."""
    plots = out / "plots"
    if shutil.which("gnuplot") is None:
        print(f"{study}: note: gnuplot is not installed, the plots were not checked")
        return []
    scripts = sorted(plots.glob("*.gp")) if plots.is_dir() else []
    if not scripts:
        return [f"{plots}: no plot"]
    problems = [f"{log}: gnuplot failed: {log.read_text()[:300]}" for log in plots.glob("*.log")]
    for script in scripts:
        for extension in (".svg", ".png", ".pdf"):
            image = script.with_suffix(extension)
            if not image.exists():
                problems.append(f"{image}: missing")
                continue
            try:
                if extension == ".svg":
                    if not xml.etree.ElementTree.parse(image).getroot().tag.endswith("svg"):
                        problems.append(f"{image}: not an SVG document")
                elif extension == ".png":
                    problems += check_png(image)
                else:
                    problems += check_pdf(image)
            except (ValueError, zlib.error, struct.error, xml.etree.ElementTree.ParseError) as e:
                problems.append(f"{image}: {e}")
    if study not in PLOT_GOLDEN_STUDIES:
        return problems
    golden = source / "tests" / "golden" / "plots" / study
    if record:
        shutil.rmtree(golden, ignore_errors=True)
        golden.mkdir(parents=True)
        for script in scripts:
            shutil.copyfile(script, golden / script.name)
        print(f"recorded {golden}")
        return problems
    names, expected = {s.name for s in scripts}, {s.name for s in golden.glob("*.gp")}
    if names != expected:
        problems.append(f"{plots}: scripts {sorted(names)}, golden has {sorted(expected)}")
    for name in sorted(names & expected):
        problems += compare_script(golden / name, plots / name)
    return problems


def main(argv):
    options = argv[4:]
    if len(argv) < 4 or options not in ([], ["--record"], ["--stale"]) and not (
            len(options) in (2, 3) and options[0] == "--study"
            and options[2:] in ([], ["--record"], ["--sanitizer"])):
        raise SystemExit(__doc__)
    sanitizer = options[-1:] == ["--sanitizer"]
    exe = str(pathlib.Path(argv[1]).resolve())
    source, work = pathlib.Path(argv[2]).resolve(), pathlib.Path(argv[3]).resolve()
    record = options[-1:] == ["--record"]
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
        out, verdicts, kept_n = run_study(exe, source, work, study, sanitizer)
        golden = golden_root / study.stem
        if record:
            golden.mkdir(parents=True, exist_ok=True)
            for name in ("trials.csv", "rates.csv"):
                shutil.copyfile(out / name, golden / name)
            (golden / "verdicts.txt").write_text("\n".join(verdicts) + "\n")
            print(f"recorded {golden}")
            failures += [f"{study.stem}: {p}" for p in check_plots(out, study.stem, source, True)]
            continue
        if not golden.is_dir():
            failures.append(f"{study.stem}: no golden files in {golden} (record them with --record)")
            continue
        problems = []
        if kept_n is not None:
            problems += compare_csv(golden / "trials.csv", out / "trials.csv", kept_n)
            print(f"{study.stem}: sanitizer grid, n in {{{', '.join(sorted(kept_n, key=int))}}}: "
                  "trials.csv compared row by row; rates.csv and the verdicts (whole grid) not "
                  "compared")
            expected = verdicts
        else:
            round_off, skipped = set(), []
            for name in ("trials.csv", "rates.csv"):
                problems += compare_csv(golden / name, out / name, round_off=round_off,
                                        skipped=skipped)
            for fit in skipped:
                print(f"{study.stem}: rates.csv: not compared, a fit through round-off: {fit}")
            expected = (golden / "verdicts.txt").read_text().splitlines()
        if verdicts != expected:
            for number, (want, got) in enumerate(zip(expected, verdicts), start=1):
                if want != got:
                    problems.append(f"verdicts line {number}: found '{got}', golden '{want}'")
                    break
            if len(verdicts) != len(expected):
                problems.append(f"verdicts: {len(verdicts)} lines, golden has {len(expected)}")
        problems += check_plots(out, study.stem, source, False)
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
