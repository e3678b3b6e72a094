#!/usr/bin/env bash
# Renders reports/index.html in headless Chromium (1400 px wide) to
# reports/index.png and fails on any console error or when the page's own
# check (an inline script that counts the inline SVG figures and writes the
# result into #page-check) did not report "page-check ok".
# Without Chromium it prints "chromium not available: skipped" and exits 0.
#
# Usage: scripts/check-report.sh [REPORT_DIR]   (default: reports)
set -euo pipefail

report_dir="${1:-reports}"
html="$report_dir/index.html"
png="$report_dir/index.png"

browser=""
for candidate in chromium chromium-browser; do
    if command -v "$candidate" >/dev/null 2>&1; then
        browser="$candidate"
        break
    fi
done
if [[ -z "$browser" ]]; then
    echo "chromium not available: skipped"
    exit 0
fi
if [[ ! -f "$html" ]]; then
    echo "check-report: $html does not exist (run: cargo xtask reproduce)" >&2
    exit 1
fi

url="file://$(cd "$(dirname "$html")" && pwd)/$(basename "$html")"
profile="$(mktemp -d)"
logs="$(mktemp -d)"
trap 'rm -rf "$profile" "$logs"' EXIT

# --virtual-time-budget lets the inline script run before the DOM is dumped.
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run
    --disable-background-networking --disable-component-update --disable-sync
    --hide-scrollbars --user-data-dir="$profile" --enable-logging=stderr --v=0
    --virtual-time-budget=5000)

status=0
if ! "$browser" "${flags[@]}" --window-size=1400,2400 --screenshot="$png" "$url" \
    >"$logs/shot.out" 2>"$logs/shot.err"; then
    echo "check-report: chromium failed to take the screenshot:" >&2
    cat "$logs/shot.err" >&2
    status=1
fi
if ! "$browser" "${flags[@]}" --window-size=1400,2400 --dump-dom "$url" \
    >"$logs/dom.html" 2>"$logs/dom.err"; then
    echo "check-report: chromium failed to dump the DOM:" >&2
    cat "$logs/dom.err" >&2
    status=1
fi

# Console errors from the page (not Chromium's own start-up chatter).
if grep -h -E "Uncaught|Failed to load|ERR_FILE_NOT_FOUND|Refused to|net::ERR" "$logs/shot.err" "$logs/dom.err"; then
    echo "check-report: the page logged errors (above)" >&2
    status=1
fi

# The element's text as the script left it (the script's own source also contains "page-check").
check_line="$(grep -o 'id="page-check"[^>]*>[^<]*' "$logs/dom.html" | sed 's/^[^>]*>//' || true)"
if [[ "$check_line" == "page-check ok:"* ]]; then
    echo "check-report: $check_line"
else
    echo "check-report: the page's own check did not pass: ${check_line:-script did not run}" >&2
    status=1
fi

if [[ -s "$png" ]]; then
    echo "check-report: screenshot $png"
else
    echo "check-report: no screenshot written" >&2
    status=1
fi
exit "$status"
