#!/usr/bin/env bash
# Typesets the rates.tex of two runs with pdflatex, as an author would \input it into a paper:
# the default study (flagged values, infinite condition numbers, negative eigenvalues,
# exponential and power-law rates, 13 metrics) and a small study fitted against the fill
# distance (an h column). The document must compile with booktabs and siunitx, and every table
# must fit the page: no overfull line, no float too large for the page.
# Usage: typeset_rates.sh RKHS_STUDY_EXECUTABLE SOURCE_DIR WORK_DIR   (exit 77: no pdflatex)
set -euo pipefail
executable=$1 source=$2 work=$3
if ! command -v pdflatex > /dev/null; then
  echo "typeset_rates: pdflatex not found (ci/setup installs texlive-latex-base," \
       "texlive-latex-recommended and texlive-science)" >&2
  exit 77
fi
rm -rf "$work" && mkdir -p "$work"
"$executable" run "$source/studies/gram_and_power.toml" --out "$work/default" --quiet --no-store \
  --no-plots > /dev/null
cat > "$work/fill_distance.toml" << 'TOML'
[study]
name = "against_h"
abscissa = "h"
evaluation_points = 512
metrics = ["fill_distance", "power_function_sup", "l2_error"]
[domain]
length = 1.0
[grid]
n = [8, 16, 32, 64]
[[kernel]]
name = "wendland"
k = [1, 2]
[[centres]]
name = "random"
seed = 3
TOML
"$executable" run "$work/fill_distance.toml" --out "$work/against_h" --quiet --no-store \
  --no-plots > /dev/null
for run in default against_h; do
  cat > "$work/$run.tex" << TEX
\documentclass[11pt]{article}
\usepackage[a4paper,margin=25mm]{geometry}
\usepackage{booktabs}
\usepackage{siunitx}
\begin{document}
\input{$work/$run/rates.tex}
\end{document}
TEX
  (cd "$work" && pdflatex -interaction=nonstopmode -halt-on-error "$run.tex" > "$run.out" 2>&1) || {
    echo "typeset_rates: $run/rates.tex does not compile:" >&2
    grep -A3 '^!' "$work/$run.out" >&2 || tail -20 "$work/$run.out" >&2
    exit 1
  }
  [[ -s $work/$run.pdf ]] || { echo "typeset_rates: no $run.pdf" >&2; exit 1; }
  if grep -E 'Overfull \\hbox|Float too large' "$work/$run.log" >&2; then
    echo "typeset_rates: a table of $run/rates.tex does not fit the page" >&2
    exit 1
  fi
  tables=$(grep -c '\\begin{table}' "$work/$run/rates.tex")

  echo "typeset_rates: $run: $tables tables typeset"
done
