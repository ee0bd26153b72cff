"""Console excerpts of a Markdown page checked against a real run (standard library only).

A fenced block that follows a line

    <!-- console: rkhs-study ARGS -->

is what `rkhs-study ARGS` prints on standard output. A variant marker
`<!-- console VARIANT: rkhs-study ARGS -->` (one word) is checked only when the caller asks for
that variant, after it has changed something the page describes (docs/writing-a-kernel.md's
"Try lying" edit, checked by tests/plugin/install_and_build_plugin.sh).

Where the marker follows a ```sh block, that block's last command (a trailing `# comment` aside)
must end in `rkhs-study ARGS`: the command a reader types is the command that is run.

Each excerpt runs in a fresh folder that holds a symbolic link to every entry of a base folder
but `results` (so no store or output of an earlier run is reused). Its lines must appear in the
output in order: a line `...` (indented or not) stands for any number of lines, every other line
must equal the next printed line, trailing whitespace aside, where a duration (`0.17 s`) matches
any duration and a replacement OLD=NEW given by the caller reads OLD in the excerpt as NEW (a
reader's home folder for the test's work folder). The excerpt either ends with `...` or with the
output's last line.
"""
import re
import shutil
import subprocess

MARKER = re.compile(r"^<!-- console(?: ([a-z]+))?: rkhs-study (.+?) -->\n```[^\n]*\n(.*?)^```",
                    re.MULTILINE | re.DOTALL)
SHELL_BLOCK_BEFORE = re.compile(r"```sh\n((?:(?!```).*\n)*?)```\n$")
DURATION = re.compile(r"\d+(?:\.\d+)? s\b")


def excerpts(page, variant=None):
    """(line of the marker, arguments, block) of every excerpt of `variant` (None: unlabelled)."""
    found = []
    for match in MARKER.finditer(page):
        if match.group(1) == variant:
            line = page.count("\n", 0, match.start()) + 1
            found.append((line, match.group(2), match.group(3)))
    return found


def shell_command_mismatch(page, line, arguments):
    """A problem when the ```sh block right above a marker does not end in its command."""
    before = "\n".join(page.split("\n")[:line - 1]) + "\n"
    block = SHELL_BLOCK_BEFORE.search(before)
    if not block:
        return None
    commands = [re.sub(r"\s+#.*$", "", text).rstrip() for text in block.group(1).splitlines()]
    commands = [text for text in commands if text]
    if commands and not re.search(r"(?:^|/)rkhs-study " + re.escape(arguments) + "$",
                                  commands[-1]):
        return (f"the ```sh block above runs `{commands[-1]}`, the marker "
                f"`rkhs-study {arguments}`: they must be the same command")
    return None


def line_matches(excerpt, printed, replacements):
    """Whether a line of an excerpt says what a printed line says, durations aside."""
    for old, new in replacements:
        excerpt = excerpt.replace(old, new)
    pattern = r"\d+(?:\.\d+)? s\b".join(re.escape(part) for part in DURATION.split(excerpt))
    return re.fullmatch(pattern, printed.rstrip()) is not None


def mismatch(block, printed, replacements=()):
    """The first problem of an excerpt against printed lines, or None."""
    at, skipping = 0, False
    for line in block.rstrip("\n").split("\n"):
        if line.strip() == "...":
            skipping = True
            continue
        end = len(printed) if skipping else min(at + 1, len(printed))
        found = next((i for i in range(at, end) if line_matches(line, printed[i], replacements)),
                     None)
        if found is None:
            near = printed[at] if at < len(printed) else "the end of the output"
            return f"says\n    {line}\n  where the command prints\n    {near}"
        at, skipping = found + 1, False
    if not skipping and at < len(printed):
        return f"ends before the output does (next: {printed[at]}); end it with `...`"
    return None


def check(page_name, page, executable, base, work, problems, variant=None, replacements=(),
          timeout=300):
    """Checks every excerpt of `variant` on `page`; appends problems, returns how many were run."""
    found = excerpts(page, variant)
    for line, arguments, block in found:
        where = f"{page_name}:{line}: the console excerpt of `rkhs-study {arguments}`"
        problem = shell_command_mismatch(page, line, arguments)
        if problem:
            problems.append(f"{where}: {problem}")
            continue
        folder = work / "console"
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
        for entry in base.iterdir():
            if entry.name != "results":
                (folder / entry.name).symlink_to(entry.resolve())
        result = subprocess.run([executable, *arguments.split()], cwd=folder, capture_output=True,
                                text=True, timeout=timeout)
        problem = mismatch(block, result.stdout.splitlines(), replacements)
        if problem:
            problems.append(f"{where} {problem}")
    return len(found)


def self_test():
    """The matcher on small cases that must pass and fail; raises AssertionError otherwise."""
    printed = ["a: 3 trials in 0.17 s", "b", "c", "d"]
    assert mismatch("a: 3 trials in 2.5 s\nb\n...\n", printed) is None
    assert mismatch("...\nc\nd\n", printed) is None
    assert mismatch("a: 3 trials in 0.17 s\nc\n...\n", printed) is not None  # b skipped silently
    assert mismatch("a: 4 trials in 0.17 s\n...\n", printed) is not None
    assert mismatch("a: 3 trials in 0.17 s\nb\n", printed) is not None  # ends early
    assert mismatch("...\nd\ne\n", printed) is not None  # beyond the end
    assert mismatch("x /home/you/p\n", ["x /tmp/w/p"], [("/home/you", "/tmp/w")]) is None
    page = ("```sh\n$HOME/rkhs/bin/rkhs-study list kernel   # all\n```\n"
            "<!-- console: rkhs-study list kernel -->\n```\nk\n```\n"
            "<!-- console lying: rkhs-study verify-plugin x.so -->\n```\n...\n```\n")
    assert [(a, b) for _, a, b in excerpts(page)] == [("list kernel", "k\n")]
    assert [a for _, a, _ in excerpts(page, "lying")] == ["verify-plugin x.so"]
    assert shell_command_mismatch(page, 4, "list kernel") is None
    assert shell_command_mismatch(page, 4, "list target") is not None
