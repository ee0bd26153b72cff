#!/usr/bin/env python3
"""Exports the elevation grid of an OpenCRG file (binary KRBI data: big-endian 32-bit floats)
as a surface grid CSV for the `surface_csv` target (docs/roads.md, "Road surfaces in 2-D").

The CRG file stores, for each reference-line position u (reference_line_start_u ..
reference_line_end_u, step reference_line_increment), one record: the reference line's heading
phi (a column "reference line phi", when present) and the elevation of every long section
(long_section_v_right .. long_section_v_left, step long_section_v_increment). The grid is
exported in these road coordinates, u along the reference line and v across it (a curved
reference line is not unrolled into Cartesian x, y: a vehicle follows u and v).

The CSV written is the grid itself:
    u_m\\v_m,<v_1>,<v_2>,...        header: the lateral offsets, metres
    <u_1>,<z_11>,<z_12>,...        one row per u, elevations in metres
with u shifted to start at 0. --u-range, --v-range crop the grid (metres, u after the shift),
--stride keeps every k-th sample on both axes. Missing samples (NaN in the CRG file) inside
the exported grid are filled by linear interpolation along u between the nearest present
samples of the same long section (OpenCRG's own reading of a gap along the road), and the
number filled is printed; a long section whose missing samples reach its first or last u is
refused (nothing to interpolate from).

Usage:
  crg_to_surface_csv.py FILE.crg OUT.csv [--u-range FROM TO] [--v-range FROM TO] [--stride K]

Standard library only.
"""
import argparse
import math
import pathlib
import re
import struct
import sys


def read_crg(path):
    data = pathlib.Path(path).read_bytes()
    end = data.find(b"\n$$$$$$$$$$")
    if end < 0:
        sys.exit(f"{path}: no end of header (a line of $) found: not a CRG file")
    start = data.find(b"\n", end + 1) + 1
    header = data[:end].decode("latin-1")
    if "#:KRBI" not in header:
        sys.exit(f"{path}: only binary single-precision data (#:KRBI) is supported")

    def number(key):
        match = re.search(r"^\s*" + key + r"\s*=\s*(\S+)", header, re.M)
        if not match:
            sys.exit(f"{path}: header has no {key}")
        return float(match.group(1))

    u0, u1, du = (number(k) for k in ("reference_line_start_u", "reference_line_end_u",
                                      "reference_line_increment"))
    v0, v1, dv = (number(k) for k in ("long_section_v_right", "long_section_v_left",
                                      "long_section_v_increment"))
    columns = re.findall(r"^D:(.*?),", header, re.M)
    sections = [c for c in columns if c.startswith("long section")]
    has_phi = columns and columns[0] == "reference line phi"
    per_record = len(columns)
    records = round((u1 - u0) / du) + 1
    if len(sections) != round((v1 - v0) / dv) + 1:
        sys.exit(f"{path}: {len(sections)} long sections, the header's v range asks for "
                 f"{round((v1 - v0) / dv) + 1}")
    count = records * per_record
    if len(data) - start < 4 * count:
        sys.exit(f"{path}: {len(data) - start} bytes of data, {4 * count} expected")
    values = struct.unpack(f">{count}f", data[start:start + 4 * count])
    rows = [values[r * per_record:(r + 1) * per_record] for r in range(records)]
    first = 1 if has_phi else 0
    u = [i * du for i in range(records)]
    v = [v0 + i * dv for i in range(len(sections))]
    z = [list(row[first:first + len(sections)]) for row in rows]
    return u, v, z


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("crg")
    parser.add_argument("out")
    parser.add_argument("--u-range", nargs=2, type=float)
    parser.add_argument("--v-range", nargs=2, type=float)
    parser.add_argument("--stride", type=int, default=1)
    args = parser.parse_args()
    u, v, z = read_crg(args.crg)
    eps = 1e-9
    rows = [i for i in range(len(u))
            if not args.u_range or args.u_range[0] - eps <= u[i] <= args.u_range[1] + eps]
    cols = [j for j in range(len(v))
            if not args.v_range or args.v_range[0] - eps <= v[j] <= args.v_range[1] + eps]
    rows, cols = rows[::args.stride], cols[::args.stride]
    filled = 0
    for j in cols:
        present = [i for i in rows if not math.isnan(z[i][j])]
        if len(present) != len(rows):
            if not present or math.isnan(z[rows[0]][j]) or math.isnan(z[rows[-1]][j]):
                sys.exit(f"long section v = {v[j]:.2f} m: missing samples at the end of the "
                         "exported range; crop it with --u-range / --v-range")
            for i in rows:
                if math.isnan(z[i][j]):
                    before = max(p for p in present if p < i)
                    after = min(p for p in present if p > i)
                    w = (u[i] - u[before]) / (u[after] - u[before])
                    z[i][j] = (1 - w) * z[before][j] + w * z[after][j]
                    filled += 1
    with open(args.out, "w") as out:
        out.write("u_m\\v_m," + ",".join(f"{v[j]:.2f}" for j in cols) + "\n")
        for i in rows:
            out.write(f"{u[i] - u[rows[0]]:.2f}," + ",".join(f"{z[i][j]:.6f}" for j in cols) + "\n")
    print(f"{args.out}: {len(rows)} x {len(cols)} samples (u x v), {filled} missing samples "
          "filled along u")


if __name__ == "__main__":
    main()
