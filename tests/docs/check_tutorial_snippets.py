#!/usr/bin/env python3
"""Checks that every code block of docs/writing-a-kernel.md is code that is compiled (or run).

The tutorial's code lives in files that the build compiles: examples/kernel-plugin/ (built out of
tree against the installed package, verify-plugin'ed and its study run by the ctest
plugins.install_and_build_example) and the framework's headers. Each fenced block of the page is
checked according to its language tag:

  cpp, cmake, toml   an excerpt of one such file. The block's first line may name the file in a
                     comment (`// inverse_multiquadric.hpp`, `# CMakeLists.txt`,
                     `// rkhs/kernel/kernel.hpp`), resolved against examples/kernel-plugin/ and then
                     framework/include/; without it every file of examples/kernel-plugin/ is
                     tried. A marker line (`// ...` in C++, optionally followed by a remark, or
                     `# ...` in CMake and TOML) stands for any number of skipped lines of the
                     file; every other line must equal the next line of the file (trailing
                     whitespace ignored), so the rest of the block is consecutive runs of the
                     file's lines, in order.
  sh                 not compiled: shell commands a reader types. The same steps (install,
                     configure, build, verify-plugin, list, run) are run by
                     tests/plugin/install_and_build_plugin.sh.
  (none), text,      not compiled: sample output of rkhs-study, pasted from a real run.
  console
  anything else      an error: a new kind of block needs a rule here first.

Indented (four-space) blocks are the page's formulas, not code, and are not fenced blocks.

And the page, read as the files it excerpts, must give a reader everything the compiler needs:
every #include line and every top-level RKHS_* macro line of the example's .hpp and .cpp files,
and every line of its CMakeLists.txt and study file that is not a comment, appears in a block.

A failure names the page's line, the first line of the block that does not match, and what the
file has there.

Usage: check_tutorial_snippets.py [--self-test] [PAGE [REPOSITORY]]
  PAGE defaults to docs/writing-a-kernel.md, REPOSITORY to the checkout this script is in.
  --self-test first checks the checker on small pages that must fail (and one that must pass).
Exit status 0 when every block matches.
"""
import pathlib
import re
import sys
import tempfile

EXAMPLE_DIR = "examples/kernel-plugin"
SEARCH_ROOTS = [EXAMPLE_DIR, "framework/include"]
EXCERPT_TAGS = {"cpp": "//", "c++": "//", "cmake": "#", "toml": "#"}
NOT_COMPILED = {
    "sh": "shell commands; tests/plugin/install_and_build_plugin.sh runs the same steps",
    "": "sample output of a real run",
    "text": "sample output of a real run",
    "console": "sample output of a real run",
}
SOURCE_SUFFIXES = (".hpp", ".cpp", ".h", ".toml", ".txt", ".cmake")


class Block:
    def __init__(self, tag, fence_line):
        self.tag = tag
        self.fence_line = fence_line  # 1-based line of the opening fence
        self.lines = []  # (page line number, text without trailing whitespace)


def fenced_blocks(page_lines, errors, page_name):
    """Every fenced block (``` or ~~~, up to three spaces of indentation) of the page."""
    blocks, block, fence = [], None, None
    for number, raw in enumerate(page_lines, start=1):
        text = raw.rstrip()
        if block is None:
            match = re.match(r"^ {0,3}(`{3,}|~{3,})\s*([^\s`]*)", text)
            if match:
                fence = match.group(1)
                block = Block(match.group(2).lower(), number)
        elif re.match(r"^ {0,3}" + re.escape(fence[0]) + "{" + str(len(fence)) + r",}\s*$", text):
            blocks.append(block)
            block = None
        else:
            block.lines.append((number, text))
    if block is not None:
        errors.append(f"{page_name}:{block.fence_line}: code block is never closed")
    return blocks


def is_marker(text, comment):
    stripped = text.strip()
    if comment == "//":
        return stripped == "// ..." or stripped.startswith("// ... ")
    return stripped == "# ..."


def example_files(repository):
    root = repository / EXAMPLE_DIR
    return sorted(p for p in root.rglob("*")
                  if p.is_file() and "build" not in p.relative_to(root).parts)


def named_source(block, comment, repository):
    """The file a block names on its first line, as (path or None, error or None)."""
    if not block.lines:
        return None, None
    match = re.match(r"^\s*" + re.escape(comment) + r"\s*(\S+)\s*$", block.lines[0][1])
    if not match or not match.group(1).endswith(SOURCE_SUFFIXES):
        return None, None
    name = match.group(1)
    for root in SEARCH_ROOTS:
        candidate = repository / root / name
        if candidate.is_file():
            return candidate, None
    return None, (f"names '{name}', which is in neither "
                  + " nor ".join(f"{root}/" for root in SEARCH_ROOTS))


def segments_of(lines, comment):
    """The block's lines as runs between marker lines: a list of lists of (number, text)."""
    segments, current = [], []
    for number, text in lines:
        if is_marker(text, comment):
            if current:
                segments.append(current)
            current = []
        else:
            current.append((number, text))
    if current:
        segments.append(current)
    return segments


def match_file(segments, file_lines):
    """Matches the runs in order, each at its earliest place after the previous one (earliest is
    optimal for ordered runs). Returns (covered file line indices, None) or (None, failure) with
    failure = (page line, block text, file line index or None, cursor)."""
    covered, cursor = [], 0
    for segment in segments:
        texts = [text for _, text in segment]
        best_length, best_start = -1, None
        for start in range(cursor, len(file_lines) - len(texts) + 1):
            length = 0
            while length < len(texts) and file_lines[start + length] == texts[length]:
                length += 1
            if length == len(texts):
                best_length, best_start = length, start
                break
            if length > best_length:
                best_length, best_start = length, start
        if best_length == len(texts):
            covered.extend(range(best_start, best_start + len(texts)))
            cursor = best_start + len(texts)
            continue
        number, text = segment[max(best_length, 0)]
        at = best_start + best_length if best_length > 0 else None
        return None, (number, text, at, cursor)
    return covered, None


def describe(page_name, failure, path, file_lines, repository, others):
    number, text, at, cursor = failure
    name = path.relative_to(repository)
    shown = lambda line: line if line.strip() else "(a blank line)"
    if at is None and cursor == 0 and others:
        return (f"{page_name}:{number}: matches no file of {EXAMPLE_DIR}/: no file has the "
                f"block's line\n    {shown(text)}")
    nor = f" (nor any other file of {EXAMPLE_DIR}/)" if others else ""
    message = f"{page_name}:{number}: does not match {name}{nor}: the block has\n    {shown(text)}\n"
    if at is not None and at < len(file_lines):
        message += f"  where {name}:{at + 1} has\n    {shown(file_lines[at])}"
    elif at is not None:
        message += f"  where {name} has ended"
    else:
        after = f" after line {cursor}" if cursor else ""
        message += f"  and no line of {name}{after} is that line"
    return message


def check_page(page, repository):
    """Returns (errors, summary)."""
    page_name = (str(page.relative_to(repository)) if page.is_relative_to(repository)
                 else page.name)
    page_lines = page.read_text(encoding="utf-8").splitlines()
    errors = []
    blocks = fenced_blocks(page_lines, errors, page_name)
    covered = {}  # path -> set of file line indices shown by some block
    counts = {}
    examples = example_files(repository)
    for block in blocks:
        counts[block.tag] = counts.get(block.tag, 0) + 1
        if block.tag in NOT_COMPILED:
            continue
        if block.tag not in EXCERPT_TAGS:
            errors.append(f"{page_name}:{block.fence_line}: code block tagged '{block.tag}': "
                          f"no rule checks it (tests/docs/check_tutorial_snippets.py knows "
                          f"{', '.join(sorted(set(EXCERPT_TAGS) | set(NOT_COMPILED) - {''}))} "
                          f"and untagged output)")
            continue
        comment = EXCERPT_TAGS[block.tag]
        path, error = named_source(block, comment, repository)
        if error:
            errors.append(f"{page_name}:{block.lines[0][0]}: the block {error}")
            continue
        lines = block.lines[1:] if path else block.lines
        segments = segments_of(lines, comment)
        if not segments:
            errors.append(f"{page_name}:{block.fence_line}: empty {block.tag} block")
            continue
        candidates = [path] if path else examples
        failures = []
        for candidate in candidates:
            file_lines = [line.rstrip() for line in
                          candidate.read_text(encoding="utf-8").splitlines()]
            shown, failure = match_file(segments, file_lines)
            if shown is not None:
                covered.setdefault(candidate, set()).update(shown)
                break
            failures.append((failure, candidate, file_lines))
        else:
            # Report against the file that matched furthest into the block.
            failure, candidate, file_lines = max(failures, key=lambda f: f[0][0])
            errors.append(describe(page_name, failure, candidate, file_lines, repository,
                                   others=path is None))

    # Completeness: what a reader needs to rebuild the example from the page.
    for path in examples:
        name = path.relative_to(repository)
        file_lines = [line.rstrip() for line in path.read_text(encoding="utf-8").splitlines()]
        if path.suffix in (".hpp", ".cpp", ".h"):
            needed = [i for i, line in enumerate(file_lines)
                      if re.match(r"^\s*#\s*include\b", line) or re.match(r"^RKHS_[A-Z_]+\(", line)]
        else:
            needed = [i for i, line in enumerate(file_lines)
                      if line.strip() and not line.lstrip().startswith("#")]
        missing = [i for i in needed if i not in covered.get(path, set())]
        if missing:
            errors.append(f"{page_name}: no block shows these lines of {name}, which a reader "
                          f"copying the page needs:\n"
                          + "\n".join(f"  {name}:{i + 1}: {file_lines[i]}" for i in missing))

    checked = sum(n for tag, n in counts.items() if tag in EXCERPT_TAGS)
    skipped = ", ".join(f"{n} {tag or 'untagged'} ({NOT_COMPILED[tag]})"
                        for tag, n in sorted(counts.items()) if tag in NOT_COMPILED)
    summary = (f"{page_name}: {len(blocks)} code blocks: {checked} cpp/cmake/toml blocks match "
               f"their files; not compiled: {skipped or 'none'}")
    return errors, summary


def self_test():
    """The checker on small pages and a small example directory: what must fail fails."""
    header = ["#pragma once", "// contract", "", "#include <vector>", "", "namespace x {",
              "struct K {", "  double f() const;", "  int a_;", "};", "}  // namespace x"]
    source = ["#include \"k.hpp\"", "", "double x::K::f() const { return 1; }",
              "", "RKHS_REGISTER_KERNEL(x::K)"]
    good = ("```cpp\n// k.hpp\n#pragma once\n// ... the contract\n\n#include <vector>\n"
            "// ...\n  int a_;\n};\n```\n"
            "```cpp\n#include \"k.hpp\"\n// ...\nRKHS_REGISTER_KERNEL(x::K)\n```\n"
            "```sh\nanything\n```\n```\noutput\n```\n")
    cases = {
        "passes": (good, None),
        "a changed line": (good.replace("  int a_;", "  int b_;"),
                           "page.md:8: does not match"),
        "an elision without marker": (good.replace("// ...\n  int a_;", "  ...\n  int a_;"),
                                      "page.md:7: does not match"),
        "a missing include": (good.replace("#include \"k.hpp\"\n// ...\n", ""),
                              "examples/kernel-plugin/k.cpp:1: #include"),
        "an unknown tag": (good + "```python\nx\n```\n", "tagged 'python'"),
        "a misnamed file": (good.replace("// k.hpp", "// kk.hpp"), "names 'kk.hpp'"),
        "an unclosed block": (good + "```cpp\n", "never closed"),
    }
    failed = []
    with tempfile.TemporaryDirectory() as directory:
        repository = pathlib.Path(directory)
        (repository / EXAMPLE_DIR).mkdir(parents=True)
        (repository / EXAMPLE_DIR / "k.hpp").write_text("\n".join(header) + "\n")
        (repository / EXAMPLE_DIR / "k.cpp").write_text("\n".join(source) + "\n")
        page = repository / "page.md"
        for name, (text, expected) in cases.items():
            page.write_text(text)
            errors, _ = check_page(page, repository)
            report = "\n".join(errors)
            if expected is None and errors:
                failed.append(f"self-test '{name}': unexpected errors:\n{report}")
            elif expected is not None and expected not in report:
                failed.append(f"self-test '{name}': expected an error containing '{expected}', "
                              f"got:\n{report or '(no error)'}")
    return failed


def main(arguments):
    run_self_test = "--self-test" in arguments
    arguments = [a for a in arguments if a != "--self-test"]
    repository = (pathlib.Path(arguments[1]) if len(arguments) > 1
                  else pathlib.Path(__file__).resolve().parents[2])
    page = pathlib.Path(arguments[0]) if arguments else repository / "docs/writing-a-kernel.md"
    if run_self_test:
        failed = self_test()
        if failed:
            print("\n".join(failed))
            return 1
        print("self-test: the checker finds changed lines, unmarked elisions, missing includes, "
              "unknown tags, misnamed files and unclosed blocks")
    errors, summary = check_page(page.resolve(), repository.resolve())
    if errors:
        print("\n".join(errors))
        print(f"FAILED: {len(errors)} problem(s); the page's code blocks must be excerpts of "
              f"{EXAMPLE_DIR}/ (or framework/include/), see tests/docs/check_tutorial_snippets.py")
        return 1
    print(summary)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
