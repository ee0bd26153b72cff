#!/usr/bin/env python3
"""The dense kernels' variants share no code (framework/internal/rkhs/approx/dense_kernels.hpp).

Each object file given is one variant, compiled for its own instruction set with Eigen's
namespace renamed to rkhs_eigen_<variant>. A weak or unique symbol (an inline function or
template instantiation that the linker merges across objects) outside that namespace could make
code compiled for AVX-512 run on a processor without it, or the reverse; a static initialiser
would run such code before any check. Both are refused.

Usage: check_dense_variants.py OBJECT... Needs nm and readelf (binutils).
"""
import re
import subprocess
import sys

# Linker-generated references that carry no code.
HARMLESS = re.compile(r"^DW\.ref\.__gxx_personality_v0$")


def problems(path):
    variant = re.search(r"rkhs_dense_([a-z0-9]+)\.dir", path)
    if not variant:
        return [f"{path}: not the object of a rkhs_dense_<variant> target"]
    namespace = f"rkhs_eigen_{variant.group(1)}"
    found = []
    symbols = subprocess.run(["nm", "--defined-only", "-C", path], capture_output=True,
                             text=True, check=True).stdout
    for line in symbols.splitlines():
        parts = line.split(maxsplit=2)
        if len(parts) < 3 or parts[1] not in ("W", "V", "u", "w", "v"):
            continue
        name = parts[2]
        if namespace in name or HARMLESS.match(name):
            continue
        found.append(f"{path}: shared symbol outside {namespace}: {name}")
    sections = subprocess.run(["readelf", "-S", "-W", path], capture_output=True, text=True,
                              check=True).stdout
    for section in (".init_array", ".ctors"):
        if section in sections:
            found.append(f"{path}: has a static initialiser ({section})")
    return found


def main():
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    found = [p for path in sys.argv[1:] for p in problems(path)]
    for line in found:
        print(line)
    print(f"{len(sys.argv) - 1} variant objects checked, {len(found)} problems")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
