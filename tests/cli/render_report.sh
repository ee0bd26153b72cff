#!/usr/bin/env bash
# Renders a run's report.html in headless Chromium, as a reader would open it: the page must
# load offline, show the rate tables, and load every plot image; a screenshot is taken.
# Usage: render_report.sh RKHS_STUDY_EXECUTABLE STUDY.toml WORK_DIR
set -euo pipefail
executable=$1 study=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
"$executable" run "$study" --out "$work/run" --quiet --no-store
chromium=$(command -v chromium || command -v chromium-browser || true)
if [[ -z $chromium ]]; then
  echo "render_report: chromium not found (ci/setup installs the Debian package 'chromium')" >&2
  exit 1
fi
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run
       --disable-background-networking --disable-component-update --disable-sync)
page="file://$(realpath "$work/run/report.html")"
timeout 120 "$chromium" "${flags[@]}" --user-data-dir="$work/profile1" --dump-dom "$page" \
  > "$work/dom.html" 2> "$work/chromium.log"
timeout 120 "$chromium" "${flags[@]}" --user-data-dir="$work/profile2" --window-size=1200,2000 \
  --screenshot="$work/report.png" "$page" 2>> "$work/chromium.log"
loaded=$(grep -o 'data-images-loaded="[0-9]*/[0-9]*"' "$work/dom.html" | head -1 | cut -d'"' -f2)
tables=$(grep -c 'class="rates"' "$work/dom.html" || true)
echo "render_report: images loaded $loaded, rate tables $tables, screenshot $(stat -c %s "$work/report.png") bytes"
[[ -n $loaded ]] || { echo "render_report: the page's load script did not run" >&2; exit 1; }
[[ ${loaded%/*} == "${loaded#*/}" && ${loaded#*/} -gt 0 ]] || { echo "render_report: not every plot loaded ($loaded)" >&2; exit 1; }
[[ $tables -gt 0 ]] || { echo "render_report: no rate table in the page" >&2; exit 1; }
grep -q '<h2>Provenance</h2>' "$work/dom.html" || { echo "render_report: no provenance" >&2; exit 1; }
[[ $(stat -c %s "$work/report.png") -gt 10000 ]] || { echo "render_report: empty screenshot" >&2; exit 1; }
