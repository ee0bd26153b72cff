#!/usr/bin/env python3
"""tools/report_render.py renders the Markdown subset of tools/paper_report.py as HTML and LaTeX.

A sample of every construct must give the expected HTML and LaTeX fragments; LaTeX's special
characters and the page's unicode characters must be escaped; constructs outside the subset must
raise MarkdownError naming their line; the same Markdown must render to the same bytes; and the
LaTeX must be structurally sound (\\begin and \\end paired, braces balanced). Then docs/paper.md
itself must render, so the page never leaves the subset. Standard library only.

usage: check_report_render.py SRC
"""
import pathlib
import re
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent.parent / "tools"))
import report_render  # noqa: E402

SAMPLE = """# Title with `code`

<!-- a comment
over two lines -->

A paragraph with **bold**, *italic* and `a_b{c}`,
wrapped: 50 % & #1 $2 {x} ~ ^ \\\\ a_b, ΔAIC ≥ 1 ± 2 and "quoted".

    python3 tools/paper_report.py --out DIR

- first item
  continued
- second item

| a | b \\| c |
|---|---|
| 1 | **x** |

![the caption](figures/s/plot.svg)
"""

HTML_FRAGMENTS = [
    "<h1>Title with <code>code</code></h1>",
    "<p>A paragraph with <strong>bold</strong>, <em>italic</em> and <code>a_b{c}</code>, "
    "wrapped: 50 % &amp; #1 $2 {x} ~ ^ \\ a_b, ΔAIC ≥ 1 ± 2 and \"quoted\".</p>",
    "<pre><code>python3 tools/paper_report.py --out DIR</code></pre>",
    "<ul>\n<li>first item continued</li>\n<li>second item</li>\n</ul>",
    "<thead><tr><th>a</th><th>b | c</th></tr></thead>",
    "<tr><td>1</td><td><strong>x</strong></td></tr>",
    '<figure><img src="figures/s/plot.svg" alt="the caption"><figcaption>the caption'
    "</figcaption></figure>",
]

LATEX_FRAGMENTS = [
    r"\section*{Title with \texttt{code}}",
    r"\textbf{bold}, \emph{italic} and \texttt{a\char95\relax{}\allowbreak{}b\char123\relax{}c"
    r"\char125\relax{}}",
    r"50 \% \& \#1 \$2 \{x\} \textasciitilde{} \textasciicircum{} \textbackslash{} a\_\allowbreak{}b, "
    r"$\Delta$AIC $\geq$ 1 $\pm$ 2 and ``quoted''.",
    "\\begin{verbatim}\npython3 tools/paper_report.py --out DIR\n\\end{verbatim}",
    "\\begin{itemize}\n\\item first item continued\n\\item second item\n\\end{itemize}",
    r"a & b $|$ c \\", r"1 & \textbf{x} \\", r"\toprule", r"\bottomrule",
    r"{\small the caption (figure: \texttt{figures/\allowbreak{}s/\allowbreak{}plot.svg})}",
]

# (Markdown, the line its error must name)
OUTSIDE_THE_SUBSET = [
    ("text\n\nsee [the page](docs/paper.md)\n", 3),
    ("> quoted\n", 1),
    ("1. first\n", 1),
    ("- item\n  - nested\n", 2),
    ("#### too deep\n", 1),
    ("```\ncode\n```\n", 1),
    ("| a | b |\n|---|---|\n| 1 | x || y |\n", 3),
    ("| a |\n| 1 |\n", 1),
    ("text <b>bold</b>\n", 1),
    ("an *unclosed emphasis\n", 1),
    ("<!-- never closed\n", 1),
    ("para\n- not a list without a blank line\n", 2),
    ("![caption](a.svg) and text\n", 1),
]


def structure_errors(latex):
    """Unpaired \\begin/\\end or unbalanced braces (escaped braces and \\char codes aside)."""
    errors, stack = [], []
    for kind, name in re.findall(r"\\(begin|end)\{([^}]*)\}", latex):
        if kind == "begin":
            stack.append(name)
        elif not stack or stack.pop() != name:
            errors.append(f"\\end{{{name}}} without its \\begin")
    errors += [f"\\begin{{{name}}} never ended" for name in stack]
    body = re.sub(r"\\begin\{verbatim\}.*?\\end\{verbatim\}", "", latex, flags=re.S)
    depth = 0
    for brace in re.findall(r"(?<!\\)[{}]", body):
        depth += 1 if brace == "{" else -1
        if depth < 0:
            errors.append("a } closes nothing")
            depth = 0
    if depth:
        errors.append(f"{depth} {{ never closed")
    return errors


def self_test():
    page, latex = report_render.to_html(SAMPLE), report_render.to_latex(SAMPLE)
    for fragment in HTML_FRAGMENTS:
        assert fragment in page, f"HTML lacks {fragment!r}:\n{page}"
    for fragment in LATEX_FRAGMENTS:
        assert fragment in latex, f"LaTeX lacks {fragment!r}:\n{latex}"
    assert "comment" not in page and "comment" not in latex
    assert page == report_render.to_html(SAMPLE) and latex == report_render.to_latex(SAMPLE)
    assert latex.startswith(r"\documentclass") and latex.endswith("\\end{document}\n")
    assert not structure_errors(latex), structure_errors(latex)
    assert structure_errors(r"\begin{a}{\end{b}")  # the structural check catches both
    for markdown, line in OUTSIDE_THE_SUBSET:
        try:
            report_render.parse(markdown)
        except report_render.MarkdownError as error:
            assert str(error).startswith(f"line {line}:"), (markdown, str(error))
        else:
            raise AssertionError(f"no error for {markdown!r}")
    try:
        report_render.to_latex("a ✓ b\n")
    except report_render.MarkdownError as error:
        assert "U+2713" in str(error) and str(error).startswith("line 1:")
    else:
        raise AssertionError("a character without a LaTeX form passed")


def main(argv):
    self_test()
    page = (pathlib.Path(argv[0]) / "docs" / "paper.md").read_text()
    report_render.to_html(page)
    errors = structure_errors(report_render.to_latex(page))
    if errors:
        sys.exit("docs/paper.md renders to unbalanced LaTeX: " + "; ".join(errors))
    print("report_render: the sample and docs/paper.md render as HTML and LaTeX")


if __name__ == "__main__":
    main(sys.argv[1:])
