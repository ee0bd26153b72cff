#!/usr/bin/env python3
"""Dependencies point down: no file of a lower layer includes a header of a higher one.

The layers, bottom to top, are the folders of framework/include/rkhs/, framework/internal/rkhs/
and framework/src/, then the MPI runner (framework/mpi/) and the command (framework/cli/). The
built-in plugins (plugins/) sit beside the framework: they may include the layers a plugin module
may use (up to plugin/) and each other's headers (plugins/internal/rkhs/integrators/, kernels/,
plants/, targets/), and no framework layer includes them. docs/architecture.md draws the same
picture.

A layer's headers sit under one of two roots, included the same way (rkhs/<layer>/x.hpp): the
public ones under framework/include/rkhs/ (installed: the plugin API, the study and result types)
and the internal ones under framework/internal/rkhs/ (not installed). A public header includes
public headers only, or the installed package would not compile.

Every `#include "rkhs/<folder>/..."` (or `<rkhs/<folder>/...>`) of every C++ file below
framework/ and plugins/ (.hpp, .cpp, .h, .ipp, .inl, .tpp, .cc, .cxx, .hh) is checked; a file of
layer L may include layer M only when M is L or below it. Also fails, each with a self-test:
  - a folder that the table below does not name (a new layer must be placed), or a file outside
    every layer folder, a header at the root of rkhs/ included;
  - an include of `rkhs/<file>` with no layer folder;
  - any other quoted include that climbs (`..`) or does not resolve, from the including file's
    folder or its layer's root, to a file of the same layer: a private header stays in its layer;
  - a public header (framework/include/rkhs/) that includes a header that is not public: an
    internal one, a built-in plugin's, or none at all.

The library's layers are also framework/CMakeLists.txt's RKHS_LAYERS (one object library each,
linked against the layers below only: the layer check); --cmake-layers "core;kernel;..." checks
that both name the same layers in the same order.

Usage: check_include_direction.py SOURCE_DIR [--self-test] [--cmake-layers LIST].
Standard library only.
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

INCLUDE = re.compile(r'^\s*#\s*include\s+[<"]rkhs/(?:([a-z_0-9]+)/)?([^">]+)[">]', re.M)
LOCAL_INCLUDE = re.compile(r'^\s*#\s*include\s+"((?!rkhs/)[^"]+)"', re.M)
# Generated into the build tree's rkhs/ (cmake/version.hpp.in): the project's version, below every
# layer, the one header at the root of rkhs/.
GENERATED_ROOT_HEADERS = {"version.hpp"}
# The two roots of the framework's headers: public (installed) and internal (this build only).
PUBLIC_AND_INTERNAL = (("framework", "include"), ("framework", "internal"))
SUFFIXES = (".hpp", ".cpp", ".h", ".ipp", ".inl", ".tpp", ".cc", ".cxx", ".hh")


def layer_of(path, source):
    """(kind, layer) of a file: ("framework", "core"), ("plugins", None), or None if unplaced."""
    rel = path.relative_to(source).parts
    if rel[0] == "plugins":
        return ("plugins", None)
    if rel[:4] == ("framework", "mpi", "internal", "rkhs"):
        return ("framework", rel[4]) if len(rel) >= 6 else None
    if rel[:2] == ("framework", "mpi"):
        return ("framework", "mpi")
    if rel[:2] == ("framework", "cli"):
        return ("framework", "cli")
    if rel[:2] in PUBLIC_AND_INTERNAL and rel[2] == "rkhs" and len(rel) >= 5:
        return ("framework", rel[3])
    if rel[:2] == ("framework", "src") and len(rel) >= 4:
        return ("framework", rel[2])
    return None


def layer_roots(path, source, placed):
    """The folders a quoted include of a file of this layer resolves against: its own folder and
    its layer's roots (headers and sources)."""
    kind, layer = placed
    if kind == "plugins":
        return [path.parent, source / "plugins"]
    if layer in ("mpi", "cli"):
        return [path.parent, source / "framework" / layer, source / "framework" / layer / "src"]
    return [path.parent, source / "framework" / "src" / layer,
            source / "framework" / "include" / "rkhs" / layer,
            source / "framework" / "internal" / "rkhs" / layer]


def is_public(path, source):
    """Whether a file is a public (installed) header: below framework/include/rkhs/."""
    return path.relative_to(source).parts[:3] == ("framework", "include", "rkhs")


def violations(source):
    found = []
    files = [p for root in ("framework", "plugins") for p in (source / root).rglob("*")
             if p.suffix in SUFFIXES and p.is_file()]
    if not files:
        return [f"no sources below {source}/framework"]
    for path in sorted(files):
        placed = layer_of(path, source)
        rel = path.relative_to(source)
        if placed is None:
            found.append(f"{rel}: outside every layer folder (framework/include/rkhs/<layer>/, "
                         "framework/internal/rkhs/<layer>/, framework/src/<layer>/, "
                         "framework/mpi/, framework/cli/, plugins/; "
                         "a header at the root of rkhs/ belongs under rkhs/<layer>/)")
            continue
        kind, layer = placed
        if kind == "framework" and layer not in LAYERS:
            found.append(f"{rel}: folder '{layer}' is not a layer of LAYERS in {__file__}")
            continue
        text = path.read_text(encoding="utf-8")
        for match in INCLUDE.finditer(text):
            target = match.group(1)
            line = text.count("\n", 0, match.start()) + 1
            if target is None and match.group(2) in GENERATED_ROOT_HEADERS:
                continue
            if target is None:
                found.append(f"{rel}:{line}: includes a header at the root of rkhs/, in no layer "
                             f"folder (rkhs/<layer>/...)")
                continue
            where = f"{rel}:{line}: includes rkhs/{target}/"
            public = source / "framework" / "include" / "rkhs" / target / match.group(2)
            if is_public(path, source) and not public.is_file():
                found.append(f"{rel}:{line}: a public header includes rkhs/{target}/"
                             f"{match.group(2)}, which is not a public header (not below "
                             f"framework/include/rkhs/): the installed package would not compile")
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
        for match in LOCAL_INCLUDE.finditer(text):
            name = match.group(1)
            line = text.count("\n", 0, match.start()) + 1
            where = f"{rel}:{line}: includes \"{name}\""
            if ".." in pathlib.PurePosixPath(name).parts:
                found.append(f"{where}: a relative include that climbs out of its folder; include "
                             f"another layer's header as rkhs/<layer>/...")
                continue
            resolved = [root / name for root in layer_roots(path, source, placed)
                        if (root / name).is_file()]
            if not resolved:
                found.append(f"{where}: not a file of its own layer (a private header stays in "
                             f"its layer's folder; another layer's header is rkhs/<layer>/...)")
            elif layer_of(resolved[0], source) != placed:
                found.append(f"{where}: resolves to {resolved[0].relative_to(source)}, in another "
                             f"layer than {rel}")
            elif is_public(path, source) and not is_public(resolved[0], source):
                found.append(f"{where}: a public header includes "
                             f"{resolved[0].relative_to(source)}, which is not a public header")
    return found


def self_test():
    """The checker finds each planted bypass and accepts the downward and local includes."""
    import tempfile

    def check(files, expected):
        with tempfile.TemporaryDirectory() as tmp:
            root = pathlib.Path(tmp)
            for name, text in files.items():
                (root / name).parent.mkdir(parents=True, exist_ok=True)
                (root / name).write_text(text)
            found = violations(root)
            assert len(found) == len(expected), (files, found)
            for message, part in zip(found, expected):
                assert part in message, (message, part)

    accepted = {"framework/include/rkhs/core/a.hpp": "",
                "framework/internal/rkhs/core/i.hpp": '#include "rkhs/core/a.hpp"\n',
                "framework/include/rkhs/run/p.hpp": '#include "rkhs/core/a.hpp"\n',
                "framework/src/report/b.cpp": '#include "rkhs/core/a.hpp"\n#include "c.hpp"\n',
                "framework/src/report/c.hpp": "#include <rkhs/core/a.hpp>\n",
                "framework/cli/commands/x.cpp": '#include "commands/y.hpp"\n',
                "framework/cli/commands/y.hpp": ""}
    check(accepted, [])
    # An upward include, quoted and in angle brackets; a built-in plugin above its layers.
    check({**accepted, "framework/src/core/u.cpp": '#include "rkhs/report/r.hpp"\n'},
          ["layer core includes the higher layer report"])
    check({**accepted, "framework/src/core/u.cpp": "#include <rkhs/report/r.hpp>\n"},
          ["layer core includes the higher layer report"])
    check({**accepted, "plugins/kernels/k.cpp": '#include "rkhs/run/run.hpp"\n'},
          ["a built-in plugin may use only"])
    # A header at the root of rkhs/ (in the MPI runner's tree) and its include.
    check({**accepted, "framework/mpi/internal/rkhs/d.hpp": "",
           "framework/mpi/src/m.cpp": '#include "rkhs/d.hpp"\n'},
          ["outside every layer folder", "a header at the root of rkhs/"])
    # A relative include into another layer's sources, and one that resolves elsewhere.
    check({**accepted, "framework/src/core/v.cpp": '#include "../report/c.hpp"\n'},
          ["climbs out of its folder"])
    check({**accepted, "framework/src/core/w.cpp": '#include "c.hpp"\n'},
          ["not a file of its own layer"])
    # A public header that includes an internal header (of its own layer or a lower one, quoted,
    # in angle brackets or relative to its folder), a built-in plugin's, or nothing; an internal
    # header may include either.
    check({**accepted, "framework/include/rkhs/core/b.hpp": '#include "rkhs/core/i.hpp"\n'},
          ["a public header includes rkhs/core/i.hpp, which is not a public header"])
    check({**accepted, "framework/include/rkhs/run/q.hpp": "#include <rkhs/core/i.hpp>\n"},
          ["a public header includes rkhs/core/i.hpp"])
    check({**accepted, "framework/internal/rkhs/core/j.hpp": "",
           "framework/include/rkhs/core/b.hpp": '#include "j.hpp"\n'},
          ["which is not a public header"])
    check({**accepted, "framework/include/rkhs/run/q.hpp": '#include "rkhs/kernels/g.hpp"\n'},
          ["not a public header", "a framework layer (run) includes a built-in plugin"])
    check({**accepted, "framework/include/rkhs/run/q.hpp": '#include "rkhs/core/none.hpp"\n'},
          ["not a public header"])
    check({**accepted, "framework/internal/rkhs/run/r.hpp": '#include "rkhs/core/i.hpp"\n'
                                                            '#include "rkhs/run/p.hpp"\n'}, [])
    # Files of other suffixes are checked as well.
    for suffix in (".ipp", ".h"):
        upward = '#include "rkhs/cli/z.hpp"\n'
        check({**accepted, f"framework/internal/rkhs/core/t{suffix}": upward},
              ["layer core includes the higher layer cli"])


def main(argv):
    arguments = argv[1:]
    cmake_layers = None
    if "--cmake-layers" in arguments:
        at = arguments.index("--cmake-layers")
        if at + 1 >= len(arguments):
            raise SystemExit(__doc__)
        cmake_layers = arguments[at + 1].split(";")
        del arguments[at:at + 2]
    if len(arguments) not in (1, 2) or (len(arguments) == 2 and arguments[1] != "--self-test"):
        raise SystemExit(__doc__)
    if len(arguments) == 2:
        self_test()
    library_layers = LAYERS[: LAYERS.index("pipeline") + 1]
    if cmake_layers is not None and cmake_layers != library_layers:
        print(f"RKHS_LAYERS of framework/CMakeLists.txt ({', '.join(cmake_layers)}) is not LAYERS "
              f"of {__file__} up to pipeline ({', '.join(library_layers)})", file=sys.stderr)
        return 1
    found = violations(pathlib.Path(arguments[0]).resolve())
    if found:
        print("\n".join(found), file=sys.stderr)
        print(f"{len(found)} include(s) against the direction of the layers", file=sys.stderr)
        return 1
    print("every include points down the layers")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
