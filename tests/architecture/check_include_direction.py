#!/usr/bin/env python3
"""Dependencies point down: no file of a lower layer includes a header of a higher one.

The layers, bottom to top, are the folders of framework/include/rkhs/ and framework/src/, then
the MPI runner (framework/mpi/) and the command (framework/cli/). The built-in plugins
(plugins/) sit beside the framework: they may include the layers a plugin module may use (up
to plugin/) and each other's headers (rkhs/integrators/, rkhs/kernels/, rkhs/plants/, rkhs/targets/), and no framework layer
includes them. docs/architecture.md draws the same picture.

Every `#include "rkhs/<folder>/..."` of every .hpp and .cpp below framework/ and plugins/ is
checked; a file of layer L may include layer M only when M is L or below it. Also fails when a
folder exists that the table below does not name (a new layer must be placed), and when a header
or source lies outside every layer folder.

Usage: check_include_direction.py SOURCE_DIR [--self-test]. Standard library only.
"""
import pathlib
import re
import sys

# Bottom to top. A layer may include itself and every layer before it.
LAYERS = ["core", "kernel", "approx", "adaptive", "plugin", "rates", "study", "run", "verify",
          "report", "pipeline", "mpi", "cli"]
# The built-in plugins may use these layers (what a plugin module sees), and each other.
PLUGIN_MAY_USE = LAYERS[: LAYERS.index("plugin") + 1]
PLUGIN_HEADER_FOLDERS = ["integrators", "kernels", "plants", "targets"]

INCLUDE = re.compile(r'^\s*#\s*include\s+"rkhs/([a-z_0-9]+)/[^"]+"', re.M)


def layer_of(path, source):
    """(kind, layer) of a file: ("framework", "core"), ("plugins", None), or None if unplaced."""
    rel = path.relative_to(source).parts
    if rel[0] == "plugins":
        return ("plugins", None)
    if rel[:2] == ("framework", "mpi"):
        return ("framework", "mpi")
    if rel[:2] == ("framework", "cli"):
        return ("framework", "cli")
    if rel[:3] == ("framework", "include", "rkhs") and len(rel) >= 5:
        return ("framework", rel[3])
    if rel[:2] == ("framework", "src") and len(rel) >= 4:
        return ("framework", rel[2])
    return None


def violations(source):
    found = []
    files = [p for root in ("framework", "plugins") for p in (source / root).rglob("*")
             if p.suffix in (".hpp", ".cpp") and p.is_file()]
    if not files:
        return [f"no sources below {source}/framework"]
    for path in sorted(files):
        placed = layer_of(path, source)
        rel = path.relative_to(source)
        if placed is None:
            found.append(f"{rel}: outside every layer folder (framework/include/rkhs/<layer>/, "
                         "framework/src/<layer>/, framework/mpi/, framework/cli/, plugins/)")
            continue
        kind, layer = placed
        if kind == "framework" and layer not in LAYERS:
            found.append(f"{rel}: folder '{layer}' is not a layer of LAYERS in {__file__}")
            continue
        text = path.read_text(encoding="utf-8")
        for match in INCLUDE.finditer(text):
            target = match.group(1)
            line = text.count("\n", 0, match.start()) + 1
            where = f"{rel}:{line}: includes rkhs/{target}/"
            if target in PLUGIN_HEADER_FOLDERS:
                if kind != "plugins":
                    found.append(f"{where}: a framework layer ({layer}) includes a built-in plugin")
                continue
            if target not in LAYERS:
                found.append(f"{where}: no such layer")
                continue
            if kind == "plugins":
                if target not in PLUGIN_MAY_USE:
                    found.append(f"{where}: a built-in plugin may use only "
                                 f"{', '.join(PLUGIN_MAY_USE)}")
            elif LAYERS.index(target) > LAYERS.index(layer):
                found.append(f"{where}: layer {layer} includes the higher layer {target}")
    return found


def self_test():
    """The checker finds a planted upward include and accepts a downward one."""
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        root = pathlib.Path(tmp)
        (root / "framework/include/rkhs/core").mkdir(parents=True)
        (root / "framework/src/report").mkdir(parents=True)
        (root / "plugins/kernels").mkdir(parents=True)
        (root / "framework/include/rkhs/core/a.hpp").write_text('#include "rkhs/report/b.hpp"\n')
        (root / "framework/src/report/b.cpp").write_text('#include "rkhs/core/a.hpp"\n')
        (root / "plugins/kernels/k.cpp").write_text('#include "rkhs/run/run.hpp"\n')
        found = violations(root)
        assert len(found) == 2, found
        assert "layer core includes the higher layer report" in found[0], found
        assert "a built-in plugin may use only" in found[1], found


def main(argv):
    if len(argv) not in (2, 3) or (len(argv) == 3 and argv[2] != "--self-test"):
        raise SystemExit(__doc__)
    if len(argv) == 3:
        self_test()
    found = violations(pathlib.Path(argv[1]).resolve())
    if found:
        print("\n".join(found), file=sys.stderr)
        print(f"{len(found)} include(s) against the direction of the layers", file=sys.stderr)
        return 1
    print("every include points down the layers")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
