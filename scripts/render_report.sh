#!/bin/sh
# Render an HTML report to a PNG screenshot with headless Chromium: Debian's `chromium-headless-shell` where
# installed (the same Chromium without its windowing layers: the same PNG, byte for byte, in a third of the CPU),
# else its `chromium`; CHROMIUM=PATH names another.
#
#   scripts/render_report.sh out/demo/report.html [out/demo/report.png] [HEIGHT]
#
# Look at the PNG to check the report renders with all its figures. Network access is switched off
# as far as Chromium allows: the report is self-contained and must not need it.
set -eu
html=${1:?usage: render_report.sh REPORT.html [SCREENSHOT.png] [HEIGHT]}
png=${2:-${html%.html}.png}
height=${3:-4000}
chromium=${CHROMIUM:-$(command -v chromium-headless-shell || command -v chromium || command -v chromium-browser \
    || echo /usr/bin/chromium)}
[ -x "$chromium" ] || { echo "render_report.sh: chromium not found (apt-get install chromium-headless-shell)" >&2; exit 2; }
profile=$(mktemp -d)
trap 'rm -rf "$profile"' EXIT
abs=$(cd "$(dirname "$html")" && pwd)/$(basename "$html")
out=$(cd "$(dirname "$png")" && pwd)/$(basename "$png")
"$chromium" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
    --disable-background-networking --disable-component-update --disable-sync \
    --hide-scrollbars --user-data-dir="$profile" --window-size=1200,"$height" \
    --screenshot="$out" "file://$abs" >/dev/null 2>&1
[ -s "$out" ] || { echo "render_report.sh: no screenshot written" >&2; exit 1; }
echo "$out"
