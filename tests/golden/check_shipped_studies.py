#!/usr/bin/env python3
"""Behaviour of every shipped study, pinned: trials.csv, rates.csv and the verdicts of
`rkhs-study check` for each studies/*.toml are compared with the golden files in
tests/golden/studies/<study>/.

Adaptive studies run on a short horizon (one lap, one snapshot; a laps axis becomes one lap and
the limit) so the whole check takes a few minutes on two cores; approximation studies run as
shipped, but for those in GOLDEN_TIERS, which run one of their tiers.

Values are compared by their floors, so that the files hold on every x86-64 processor and need
no re-recording for one: the last digits of a double depend on the processor (glibc picks its
exp, log, sin and pow by CPU features at run time; rkhs-study its dense kernels), and a value
computed from an ill-conditioned matrix, a difference of nearly equal numbers or an adaptive
integration moves by up to its floor (docs/metrics.md, "Floors"). So:
  - a value of trials.csv agrees with its golden one within the larger of ULPS ulps and its floor
    (the `<metric>_floor` column of the golden or the found row, the larger); an exact metric
    (no floor column) to ULPS ulps. The integrator's step counts have floors too (1 % of the
    count, FloorRule::step_controller): the step controller's accept/reject decisions near its
    tolerance follow the state's last bits, so the count is a measure of work compared as such;
  - a floor agrees with its golden one within a factor of FLOOR_FACTOR (an estimate of a size);
  - a fit in rates.csv agrees within the floors of its statistics (rate_floor for the rate, its
    standard error and interval; r_squared_floor; delta_aic_floor), computed from the floors of
    the values it used; a constant series' value and band within value_floor (the largest
    floor of its values);
  - text (flags, notes, reasons) and verdicts agree exactly but for their numbers, which agree
    within the row's floors or one unit of their last printed digit.
Columns may be added, never removed, renamed or changed; rows must match in number and order.
Verdicts must match line for line, except the first line's wall time.

Usage:
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR                 compare every study
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR --study NAME    compare studies/NAME.toml
                                                                          (ctest: golden.NAME)
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR --stale         only: no golden files
                                                                          for a study not shipped
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR --record        write the golden files
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR --study NAME --record
                                                                          write NAME's only
  check_shipped_studies.py RKHS_STUDY SOURCE_DIR WORK_DIR [--study NAME] --portable
                                                                          the same comparison as
                                                                          another processor runs
                                                                          it (PORTABLE_GLIBC_TUNABLES;
                                                                          ctest: golden_portable.NAME)
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


# Studies whose full tier takes minutes on 2 cores are pinned at a tier of theirs
# (`rkhs-study check --tier NAME`): the same code paths at smaller n. wendland_3d's full tier
# (n up to 35937 in 3-D) takes about 5 minutes, twice per CI run (golden and golden_portable);
# its quick tier about half a minute. docs/study-times.json times the full tiers.
GOLDEN_TIERS = {"wendland_3d": "quick"}


# --portable: the run another x86-64 processor would make. glibc's exp, log, sin and pow take
# their baseline SSE2 code paths instead of the FMA ones (GLIBC_TUNABLES masks the features glibc
# chooses them by): other bits in the last places of every value, the same files within floors.
# The dense kernels stay pinned to the baseline. With the widest variant (avx512) instead, 13 of
# 20 studies still match and 7 differ (checked on 914148b): asymptotic windows of series near
# their floors move (gram_and_power: a head point n = 10 kept instead of cut; paper_converged,
# paper_synthetic: a window n = 10..100 instead of 20..70), and one adaptive trial of
# paper_synthetic (Gaussian, pe_level_unresolved) moves by 1.75 times its integration floor
# (l2_error 1.8274997 against 1.8275095, floor 5.6e-6; 989 steps against 1051): that floor, an
# estimate from the integrator's tolerances, is too small where the Gram matrix is this badly
# conditioned (issue 48, the variant check: open).
PORTABLE_GLIBC_TUNABLES = "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX512F,-AVX"


def run_study(exe, source, work, study, sanitizer=False, portable=False):
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
    if portable:
        environment["GLIBC_TUNABLES"] = PORTABLE_GLIBC_TUNABLES
    tier = ["--tier", GOLDEN_TIERS[name]] if name in GOLDEN_TIERS else []
    result = subprocess.run(
        [exe, "check", "--no-store", "--quiet", "--threads", "2", "--out", name,
         "--data-dir", str(source / "studies" / "data"), *tier, definition.name],
        cwd=work, capture_output=True, text=True, check=False, env=environment)
    # 0 all pass, 1 a failure, 3 inconclusive: short horizons fail some expectations, and that
    # is pinned too; 5 a study with no [[expect]] (its trials run and its outputs are written
    # all the same). 2 (bad input) or a crash is an error of this check.
    if result.returncode not in (0, 1, 3, 5):
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


# The dense kernels the studies run with (RKHS_STUDY_DENSE_KERNELS): the baseline x86-64 ones,
# which every x86-64 processor runs, so that the files do not depend on the vector width.
DENSE_KERNELS = "x86-64"

# Numbers without a floor (axis values, exact metrics: MetricRow::floor = exact) agree to a few
# units in the last place.
ULPS = 4
ULP = 2.0 ** -52

# A floor column (`<metric>_floor` beside `<metric>`) is an estimate of a size, known to about
# its order of magnitude: the golden and the found floor agree within a factor of FLOOR_FACTOR.
# Floors computed from values that are themselves at round-off or set by the step sequence (the
# integration error's, a pairwise rate's between values at their floors) move with those values:
# by up to a factor of 2.03 and 3.9 under glibc's other code paths.
FLOOR_FACTOR = 4.0

# rates.csv: the floors of a fit's statistics (written beside them, rkhs/rates/rates.hpp
# FitFloors): rate_floor covers the rate, its standard error and interval.
RATE_FLOOR_COLUMNS = {"rate": "rate_floor", "std_error": "rate_floor", "ci_low": "rate_floor",
                      "ci_high": "rate_floor", "r_squared": "r_squared_floor",
                      "delta_aic": "delta_aic_floor", "value": "value_floor",
                      "band": "value_floor"}

NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def number(text):
    try:
        return float(text)
    except ValueError:
        return None


def floor_of(row, column):
    """The floor in `row` (a dict) named `column`, 0 when absent, empty or not a number."""
    value = number(row.get(column, "") or "")
    return value if value is not None and value == value and value > 0 else 0.0


def within(golden, found, tolerance=0.0):
    """Numbers within max(ULPS ulps, tolerance); infinities and NaN only equal to themselves."""
    if golden == found:
        return True
    if math.isinf(golden) or math.isinf(found) or golden != golden or found != found:
        return False
    return abs(golden - found) <= max(ULPS * ULP * max(abs(golden), abs(found)), tolerance)


def same_floor(golden, found, golden_value=None, found_value=None):
    """Two estimates of a floor, within a factor of FLOOR_FACTOR (or both empty), or both at
    least the value they are the floor of (the value unresolved in both runs, whatever its
    floor's size)."""
    if golden == found:
        return True
    a, b = number(golden), number(found)
    if a is None or b is None:
        return False
    if golden_value is not None and found_value is not None and a >= abs(golden_value) and \
            b >= abs(found_value):
        return True
    if math.isinf(a) or math.isinf(b):
        return a == b
    return abs(a - b) <= (FLOOR_FACTOR - 1) * min(abs(a), abs(b)) or within(a, b)


def same_text(golden, found, tolerance):
    """Text equal but for its numbers, each within `tolerance` or one unit of its last printed
    digit (a number printed to its digits may round the other way on another processor)."""
    if golden == found:
        return True
    want, got = NUMBER.findall(golden), NUMBER.findall(found)
    if NUMBER.sub("#", golden) != NUMBER.sub("#", found) or len(want) != len(got):
        return False
    for a, b in zip(want, got):
        x, y = float(a), float(b)
        mantissa = a.lower().split("e")[0]
        digits = len(mantissa.split(".")[1]) if "." in mantissa else 0
        exponent = int(a.lower().split("e")[1]) if "e" in a.lower() else 0
        last_digit = 10.0 ** (exponent - digits)
        if not (within(x, y, tolerance) or abs(x - y) <= last_digit * (1 + 1e-9)):
            return False
    return True


def compare_csv(golden_path, actual_path, kept_n=None):
    """Differences between two CSV files, golden columns only (added columns are allowed); with
    kept_n, only the golden rows whose n is in it (a sanitizer grid).

    Each value is compared within the larger of ULPS ulps and its floor: in trials.csv the
    `<metric>_floor` columns of the golden and the found row (the larger of the two), in
    rates.csv rate_floor, r_squared_floor and delta_aic_floor; floors themselves within a factor
    of FLOOR_FACTOR. Text compares exactly but for the numbers in it, which agree within the
    row's largest floor or one unit of their last printed digit."""
    golden_header, golden_rows = read_csv(golden_path)
    actual_header, actual_rows = read_csv(actual_path)
    problems = []
    is_rates = actual_path.name == "rates.csv"
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
    columns = set(golden_header) | set(actual_header)
    for line, (golden_values, actual_values) in enumerate(zip(golden_rows, actual_rows), start=2):
        golden = dict(zip(golden_header, golden_values))
        found = dict(zip(actual_header, actual_values))
        if is_rates:
            row_floor = max(floor_of(golden, c) for c in set(RATE_FLOOR_COLUMNS.values()))
            row_floor = max(row_floor, *(floor_of(found, c) for c in set(RATE_FLOOR_COLUMNS.values())))
        for column in golden_header:
            want, got = golden[column], found[column]
            if want == got:
                continue
            floor_column = (RATE_FLOOR_COLUMNS.get(column) if is_rates else column + "_floor")
            is_floor = column.endswith("_floor") and (column[:-len("_floor")] in columns or is_rates)
            a, b = number(want), number(got)
            if is_floor:
                of = "rate" if is_rates and column == "rate_floor" else column[:-len("_floor")]
                same = same_floor(want, got, number(golden.get(of, "") or ""),
                                  number(found.get(of, "") or ""))
            elif a is not None and b is not None:
                tolerance = 0.0
                if floor_column in columns:
                    tolerance = max(floor_of(golden, floor_column), floor_of(found, floor_column))
                same = within(a, b, tolerance)
            else:
                same = same_text(want, got, row_floor if is_rates else 0.0)
            if not same:
                where = f" (floor {floor_column})" if floor_column in columns else ""
                problems.append(f"{actual_path}:{line}: column {column}{where}: found '{got}', "
                                f"golden '{want}'")
                if len(problems) >= 20:
                    return problems + ["(more differences not shown)"]
    return problems


# The studies whose gnuplot scripts are pinned (tests/golden/plots/<study>/): iso8608 has the
# grid of panels (84 groups), legends and ranges of a real study.
PLOT_GOLDEN_STUDIES = {"iso8608"}


def compare_script(golden_path, actual_path):
    """Differences between two gnuplot scripts: numbers within 1e-9 relative, the rest
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
                and all(within(float(a), float(b), 1e-9 * max(abs(float(a)), abs(float(b))))
                        for a, b in zip(want_numbers, got_numbers)))
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
    if len(argv) < 4 or options not in ([], ["--record"], ["--stale"], ["--portable"]) and not (
            len(options) in (2, 3) and options[0] == "--study"
            and options[2:] in ([], ["--record"], ["--sanitizer"], ["--portable"])):
        raise SystemExit(__doc__)
    sanitizer = options[-1:] == ["--sanitizer"]
    portable = options[-1:] == ["--portable"]
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
        out, verdicts, kept_n = run_study(exe, source, work, study, sanitizer, portable)
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
            for name in ("trials.csv", "rates.csv"):
                problems += compare_csv(golden / name, out / name)
            expected = (golden / "verdicts.txt").read_text().splitlines()
        if verdicts != expected:
            for line, (want, got) in enumerate(zip(expected, verdicts), start=1):
                if not same_text(want, got, 0.0):
                    problems.append(f"verdicts line {line}: found '{got}', golden '{want}'")
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
