#!/usr/bin/env bash
# Opens a report in headless Chromium (Debian: `apt-get install chromium`, or `make report-deps`): prints
# how many of its images and videos the browser loaded, and writes a screenshot of the top of the page.
# Exits non-zero unless every image and video loaded.
#   scripts/check-report.sh [DIR]   (default run/report)
set -euo pipefail
dir=$(cd "${1:-run/report}" && pwd)
page="file://$dir/index.html"
browser=$(command -v chromium || command -v chromium-browser || command -v google-chrome || true)
if [ -z "$browser" ]; then
    echo "check-report: no Chromium found; install it with 'make report-deps' (Debian: apt-get install chromium)" >&2
    exit 2
fi
flags=(--headless --no-sandbox --disable-gpu --hide-scrollbars --virtual-time-budget=20000)
loaded=$("$browser" "${flags[@]}" --dump-dom "$page" 2>/dev/null | grep -o 'data-loaded="[^"]*"' | sed 's/data-loaded="\(.*\)"/\1/' || true)
"$browser" "${flags[@]}" --window-size=1200,2400 --screenshot="$dir/screenshot.png" "$page" >/dev/null 2>&1
echo "$page: ${loaded:-nothing reported: the load check of the page did not run}; screenshot $dir/screenshot.png"
# "images N/M, videos K/L": every one loaded?
echo "$loaded" | tr -d , | awk '{ split($2, i, "/"); split($4, v, "/"); exit !(i[1] == i[2] && v[1] == v[2] && i[2] > 0) }'
