"""The Markdown subset tools/paper_report.py writes, rendered as one HTML page and one LaTeX
document.

    blocks  = parse(markdown)              # raises MarkdownError naming the line
    html    = to_html(markdown)            # a complete page: inline CSS, no network resource
    latex   = to_latex(markdown, folder)   # a complete article for pdflatex (booktabs, longtable)

The subset: headings (#, ##, ###); paragraphs (lines joined until a blank line); `- ` bullet
lists whose items may continue on lines indented by two spaces; pipe tables (a header row, a
`|---|` row, rows with as many cells; `\\|` is a literal bar); indented code blocks (four
spaces); a figure, `![caption](path)` alone on its lines; HTML comments (dropped); inline
**bold**, *italic*, `code` and backslash escapes of ASCII punctuation. Anything else (links,
block quotes, numbered or nested lists, fences, raw HTML, an unclosed delimiter, a character
LaTeX is not given here) raises MarkdownError with its line number: nothing is dropped silently.

The same Markdown always renders to the same bytes. In LaTeX a figure path ending in .svg is
typeset from the PDF (or else PNG) of the same name in `folder`; when there is neither, the
document names the path instead.
"""

import dataclasses
import html
import pathlib
import re


class MarkdownError(ValueError):
    pass


@dataclasses.dataclass
class Block:
    kind: str  # heading, paragraph, list, table, code, figure
    line: int  # 1-based line of the block's first line
    level: int = 0  # headings
    text: str = ""  # heading, paragraph, code; figure: its caption
    items: list = dataclasses.field(default_factory=list)  # list items; table rows of cells
    path: str = ""  # figure


FIGURE = re.compile(r"^!\[([^\]]*)\]\(([^()\s]+)\)$")
HEADING = re.compile(r"^(#{1,3}) (\S.*)$")
UNSUPPORTED_LINE = [
    (re.compile(r"^#{4,} "), "a heading deeper than ###"),
    (re.compile(r"^#+[^#\s]"), "a heading without a space after its #"),
    (re.compile(r"^\s*>"), "a block quote"),
    (re.compile(r"^\s*\d+[.)] "), "a numbered list"),
    (re.compile(r"^\s*[*+] "), "a list marker other than '- '"),
    (re.compile(r"^\s*(```|~~~)"), "a fenced code block"),
    (re.compile(r"^\s*([-*_] *){3,}$"), "a horizontal rule"),
    (re.compile(r"^\s*<(?!!--)"), "raw HTML"),
    (re.compile(r"^ ?-\s*$|^=+\s*$"), "a setext heading or an empty list item"),
]


def fail(line, why, text):
    raise MarkdownError(f"line {line}: {why}: {text.strip()[:80]!r}")


def check_line(number, line):
    if "\t" in line:
        fail(number, "a tab", line)
    for pattern, why in UNSUPPORTED_LINE:
        if pattern.search(line):
            fail(number, why, line)


def table_cells(number, line):
    """A pipe-table row's cells, stripped, with \\| unescaped to |."""
    if not (line.startswith("|") and line.rstrip().endswith("|")) or line.rstrip().endswith("\\|"):
        fail(number, "a table row must start and end with |", line)
    cells = re.split(r"(?<!\\)\|", line.strip()[1:-1])
    return [c.strip().replace("\\|", "|") for c in cells]


def parse(markdown):
    """The blocks of `markdown`, in order; MarkdownError for anything outside the subset."""
    lines = markdown.split("\n")
    blocks, k = [], 0
    while k < len(lines):
        line, number = lines[k], k + 1
        if not line.strip():
            k += 1
        elif line.lstrip().startswith("<!--"):
            while "-->" not in lines[k]:
                k += 1
                if k == len(lines):
                    fail(number, "an HTML comment without -->", line)
            if lines[k].split("-->", 1)[1].strip():
                fail(k + 1, "text after -->", lines[k])
            k += 1
        elif line.startswith("    "):
            code = []
            while k < len(lines) and (lines[k].startswith("    ") or not lines[k].strip()):
                code.append(lines[k][4:])
                k += 1
            blocks.append(Block("code", number, text="\n".join(code).rstrip("\n")))
        elif line.startswith("#"):
            check_line(number, line)
            found = HEADING.match(line)
            if not found:
                fail(number, "a heading", line)
            blocks.append(Block("heading", number, level=len(found.group(1)),
                                text=found.group(2).strip()))
            k += 1
        elif line.startswith("- "):
            items = []
            while k < len(lines) and lines[k].strip():
                check_line(k + 1, lines[k][2:] if lines[k].startswith("- ") else lines[k])
                if lines[k].startswith("- "):
                    items.append((k + 1, lines[k][2:].strip()))
                elif lines[k].lstrip().startswith("- "):
                    fail(k + 1, "a nested list", lines[k])
                elif lines[k].startswith("  ") and not lines[k].startswith("   "):
                    items[-1] = (items[-1][0], items[-1][1] + " " + lines[k].strip())
                else:
                    fail(k + 1, "a list line that neither starts an item ('- ') nor continues "
                             "one (two spaces)", lines[k])
                k += 1
            blocks.append(Block("list", number, items=items))
        elif line.startswith("|"):
            rows = []
            while k < len(lines) and lines[k].strip():
                rows.append(table_cells(k + 1, lines[k]))
                k += 1
            if len(rows) < 2 or not all(re.fullmatch(r"-{3,}", c) for c in rows[1]):
                fail(number, "a table needs a header row and a |---| row of plain dashes", line)
            for offset, row in enumerate(rows):
                if len(row) != len(rows[0]):
                    fail(number + offset, f"{len(row)} cells in a table of {len(rows[0])} "
                                          "columns (an unescaped | in a cell?)", lines[number + offset - 1])
            blocks.append(Block("table", number, items=[rows[0]] + rows[2:]))
        elif line.startswith("!["):
            found = FIGURE.match(line)
            if not found or (k + 1 < len(lines) and lines[k + 1].strip()):
                fail(number, "a figure must be ![caption](path) alone, then a blank line", line)
            blocks.append(Block("figure", number, text=found.group(1), path=found.group(2)))
            k += 1
        else:
            text = []
            while k < len(lines) and lines[k].strip():
                check_line(k + 1, lines[k])
                if lines[k].startswith(("#", "- ", "|", "![", "    ")) or "<!--" in lines[k]:
                    fail(k + 1, "a block inside a paragraph (a blank line must come first)",
                         lines[k])
                text.append(lines[k].strip())
                k += 1
            blocks.append(Block("paragraph", number, text=" ".join(text)))
    for block in blocks:
        for text in inline_texts(block):
            inline(text, block.line)  # every inline span checked before anything renders
    return blocks


def inline_texts(block):
    if block.kind in ("heading", "paragraph", "figure"):
        return [block.text]
    if block.kind == "list":
        return [text for _, text in block.items]
    if block.kind == "table":
        return [cell for row in block.items for cell in row]
    return []


INLINE = re.compile(r"`([^`]*)`|\*\*(.+?)\*\*|\*(\S(?:.*?\S)?)\*|\\([!-/:-@\[-`{-~])")


def inline(text, line):
    """`text` as spans (kind, content), kind one of text, code, bold, italic; bold and italic
    hold spans; MarkdownError for links, raw HTML and unmatched delimiters."""
    spans, at = [], 0
    for found in INLINE.finditer(text):
        spans += plain(text[at:found.start()], line)
        code, bold, italic, escaped = found.groups()
        if code is not None:
            spans.append(("code", code))
        elif bold is not None:
            spans.append(("bold", inline(bold, line)))
        elif italic is not None:
            spans.append(("italic", inline(italic, line)))
        else:
            spans.append(("text", escaped))
        at = found.end()
    return spans + plain(text[at:], line)


def plain(text, line):
    if not text:
        return []
    for pattern, why in ((r"[`*]", "an unmatched ` or *"), (r"\]\(", "a link"),
                         (r"<[A-Za-z/!]", "raw HTML")):
        if re.search(pattern, text):
            fail(line, why, text)
    return [("text", text)]


# HTML ---------------------------------------------------------------------------------------

CSS = """body { font-family: sans-serif; max-width: 72em; margin: 2em auto; padding: 0 1em;
       line-height: 1.45; color: #1a1a1a; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.88em; }
th, td { border: 1px solid #b0b0b0; padding: 0.25em 0.5em; text-align: left;
         vertical-align: top; }
th { background: #eeeeee; }
code, pre { font-family: monospace; background: #f4f4f4; }
pre { padding: 0.6em; overflow-x: auto; }
figure { margin: 1.5em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #dddddd; }
figcaption { font-size: 0.9em; color: #444444; }"""


def html_spans(spans):
    out = []
    for kind, content in spans:
        if kind == "text":
            out.append(html.escape(content, quote=False))
        elif kind == "code":
            out.append(f"<code>{html.escape(content, quote=False)}</code>")
        elif kind == "bold":
            out.append(f"<strong>{html_spans(content)}</strong>")
        else:
            out.append(f"<em>{html_spans(content)}</em>")
    return "".join(out)


def to_html(markdown):
    """`markdown` as a complete HTML page, titled by its first heading."""
    blocks = parse(markdown)
    title = next((b.text for b in blocks if b.kind == "heading"), "report")
    span = lambda text, block: html_spans(inline(text, block.line))
    body = []
    for b in blocks:
        if b.kind == "heading":
            body.append(f"<h{b.level}>{span(b.text, b)}</h{b.level}>")
        elif b.kind == "paragraph":
            body.append(f"<p>{span(b.text, b)}</p>")
        elif b.kind == "list":
            body.append("<ul>\n" + "\n".join(f"<li>{html_spans(inline(t, n))}</li>"
                                             for n, t in b.items) + "\n</ul>")
        elif b.kind == "code":
            body.append(f"<pre><code>{html.escape(b.text, quote=False)}</code></pre>")
        elif b.kind == "table":
            header, *rows = b.items
            cells = lambda row, tag: "".join(f"<{tag}>{span(c, b)}</{tag}>" for c in row)
            body.append("<table>\n<thead><tr>" + cells(header, "th") + "</tr></thead>\n<tbody>\n" +
                        "\n".join("<tr>" + cells(r, "td") + "</tr>" for r in rows) +
                        "\n</tbody>\n</table>")
        else:
            body.append(f'<figure><img src="{html.escape(b.path)}" alt="'
                        f'{html.escape(b.text)}"><figcaption>{span(b.text, b)}'
                        "</figcaption></figure>")
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f"<title>{html.escape(title, quote=False)}</title>\n<style>\n{CSS}\n</style>\n"
            "</head>\n<body>\n" + "\n".join(body) + "\n</body>\n</html>\n")


# LaTeX --------------------------------------------------------------------------------------

LATEX_ESCAPES = {
    "\\": r"\textbackslash{}", "{": r"\{", "}": r"\}", "$": r"\$", "&": r"\&", "#": r"\#",
    "%": r"\%", "_": r"\_", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}",
    "<": r"$<$", ">": r"$>$", "|": r"$|$",
    "Δ": r"$\Delta$", "≥": r"$\geq$", "≤": r"$\leq$", "±": r"$\pm$", "−": r"$-$",
    "×": r"$\times$", "·": r"$\cdot$", "→": r"$\to$", "∞": r"$\infty$", "≈": r"$\approx$",
    "σ": r"$\sigma$", "μ": r"$\mu$", "–": "--", "—": "---", "’": "'", "‘": "`",
}


def latex_text(text, line, code=False):
    """`text` with every LaTeX special character escaped, a line break allowed after / and _
    (paths) and, in code, after commas."""
    out = []
    for k, c in enumerate(text):
        if code and c in "\\{}$&#%_~^<>|\"":
            out.append(f"\\char{ord(c)}\\relax{{}}")  # typewriter fonts have every ASCII glyph
        elif c in LATEX_ESCAPES:
            out.append(LATEX_ESCAPES[c])
        elif ord(c) > 126 or (ord(c) < 32):
            fail(line, f"the character {c!r} (U+{ord(c):04X}) has no LaTeX form here", text)
        elif c == '"' and not code:
            out.append("``" if k == 0 or text[k - 1] in " ([" else "''")
        elif c == "-" and text[k + 1:k + 2] == "-":
            out.append("-{}")  # -- would typeset as a dash
        else:
            out.append(c)
        if c in "/_" or (code and c == ","):
            out.append(r"\allowbreak{}")
    return "".join(out)


def latex_spans(spans, line):
    out = []
    for kind, content in spans:
        if kind == "text":
            out.append(latex_text(content, line))
        elif kind == "code":
            out.append(r"\texttt{" + latex_text(content, line, code=True) + "}")
        elif kind == "bold":
            out.append(r"\textbf{" + latex_spans(content, line) + "}")
        else:
            out.append(r"\emph{" + latex_spans(content, line) + "}")
    return "".join(out)


def latex_table(rows, line):
    """A longtable in a small font. When the cells' natural widths exceed the text width, every
    column becomes a ragged p column at least as wide as its longest word, the rest of the line
    shared in proportion to the columns' longest cells (capped at 48 characters)."""
    columns = len(rows[0])
    size, budget = (r"\footnotesize", 115) if columns <= 7 else (r"\scriptsize", 135)
    # budget: characters of that size on the 483pt text width
    longest = [max(len(row[c]) for row in rows) for c in range(columns)]
    if sum(longest) + 2 * columns <= budget:
        spec = "l" * columns
    else:
        words = [max(len(w) for row in rows for w in row[c].split() or [""]) + 1
                 for c in range(columns)]
        wanted = [max(min(n, 48), w) for n, w in zip(longest, words)]
        spare = max(budget - 2 * columns - sum(words), 0)
        extra = sum(x - w for x, w in zip(wanted, words)) or 1
        shares = [w + spare * (x - w) / extra for x, w in zip(wanted, words)]
        padding = 6 / 483  # a column's two 3pt \tabcolsep on the 483pt of the text width
        spec = "".join(r">{\raggedright\arraybackslash}p{%.3f\linewidth}"
                       % (s / sum(shares) * (1 - padding * columns)) for s in shares)
    cells = lambda row: " & ".join(latex_spans(inline(c, line), line) for c in row) + r" \\"
    header, *body = rows
    return "\n".join([r"{" + size, r"\setlength{\tabcolsep}{3pt}",
                      r"\begin{longtable}{@{}" + spec + "@{}}", r"\toprule", cells(header),
                      r"\midrule", r"\endhead", *map(cells, body), r"\bottomrule",
                      r"\end{longtable}}"])


def latex_figure(block, folder):
    stem = pathlib.PurePosixPath(block.path).with_suffix("")
    caption = latex_spans(inline(block.text, block.line), block.line)
    for suffix in (".pdf", ".png"):
        if folder is not None and (folder / f"{stem}{suffix}").is_file():
            return (r"\begin{center}" "\n" r"\includegraphics[width=0.8\linewidth]{"
                    f"{stem}{suffix}" "}\\\\\n" r"{\small " + caption + "}\n" r"\end{center}")
    return (r"\begin{center}{\small " + caption + r" (figure: \texttt{" +
            latex_text(block.path, block.line, code=True) + r"})}\end{center}")


LATEX_PREAMBLE = r"""\documentclass[10pt]{article}
\usepackage[a4paper,margin=20mm]{geometry}
\usepackage{booktabs}
\usepackage{longtable}
\usepackage{array}
\usepackage{graphicx}
\setlength{\parindent}{0pt}
\setlength{\parskip}{0.6em}
\setlength{\emergencystretch}{3em}
\begin{document}
"""


def to_latex(markdown, folder=None):
    """`markdown` as a complete LaTeX document; `folder`: where figure paths are relative to."""
    sections = {1: r"\section*", 2: r"\subsection*", 3: r"\subsubsection*"}
    body = []
    for b in parse(markdown):
        if b.kind == "heading":
            body.append(sections[b.level] + "{" + latex_spans(inline(b.text, b.line), b.line) + "}")
        elif b.kind == "paragraph":
            body.append(latex_spans(inline(b.text, b.line), b.line))
        elif b.kind == "list":
            body.append("\\begin{itemize}\n" + "\n".join(
                r"\item " + latex_spans(inline(t, n), n) for n, t in b.items) + "\n\\end{itemize}")
        elif b.kind == "code":
            if r"\end{verbatim}" in b.text or re.search(r"[^\x20-\x7e\n]", b.text):
                fail(b.line, "a code block LaTeX's verbatim cannot hold", b.text)
            body.append("{\\small\n\\begin{verbatim}\n" + b.text + "\n\\end{verbatim}\n}")
        elif b.kind == "table":
            body.append(latex_table(b.items, b.line))
        else:
            body.append(latex_figure(b, folder))
    return LATEX_PREAMBLE + "\n\n".join(body) + "\n\n\\end{document}\n"
