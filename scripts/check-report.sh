#!/usr/bin/env bash
# Renders reports/index.html in headless Chromium (1400 px wide) to
# reports/index.png, and its first screen (1400 x 900) to
# reports/index-first-screen.png, and fails on any console error, when the
# page's own check (an inline script that counts the inline SVG figures and
# writes the result into #page-check) did not report "page-check ok", or when
# the findings summary (#summary) does not end within the first 900 px at
# 1400 px width (the same script writes where it ends into #summary-check).
# Without Chromium it prints "chromium not available: skipped" and exits 0.
#
# Usage: scripts/check-report.sh [REPORT_DIR]   (default: reports)
set -euo pipefail

report_dir="${1:-reports}"
html="$report_dir/index.html"
png="$report_dir/index.png"
first_png="$report_dir/index-first-screen.png"
# The first screen: the window a reader opens the page in.
first_w=1400
first_h=900

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
if ! "$browser" "${flags[@]}" --window-size="$first_w,$first_h" --screenshot="$first_png" "$url" \
    >"$logs/first.out" 2>"$logs/first.err"; then
    echo "check-report: chromium failed to take the first-screen screenshot:" >&2
    cat "$logs/first.err" >&2
    status=1
fi
# The DOM as the first screen lays it out (the summary's position depends on the width only).
if ! "$browser" "${flags[@]}" --window-size="$first_w,$first_h" --dump-dom "$url" \
    >"$logs/dom.html" 2>"$logs/dom.err"; then
    echo "check-report: chromium failed to dump the DOM:" >&2
    cat "$logs/dom.err" >&2
    status=1
fi

# Console errors from the page (not Chromium's own start-up chatter).
if grep -h -E "Uncaught|Failed to load|ERR_FILE_NOT_FOUND|Refused to|net::ERR" "$logs/shot.err" "$logs/first.err" "$logs/dom.err"; then
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

# The findings summary must end on the first screen.
summary_line="$(grep -o 'id="summary-check"[^>]*>[^<]*' "$logs/dom.html" | sed 's/^[^>]*>//' || true)"
if [[ "$summary_line" =~ ^summary-bottom\ ([0-9]+)\ width\ ([0-9]+)$ ]]; then
    bottom="${BASH_REMATCH[1]}"
    width="${BASH_REMATCH[2]}"
    if [[ "$width" -ne "$first_w" ]]; then
        echo "check-report: the page was laid out $width px wide, not $first_w" >&2
        status=1
    elif [[ "$bottom" -le "$first_h" ]]; then
        echo "check-report: findings summary ends at $bottom px, within the first screen ($first_w x $first_h)"
    else
        echo "check-report: findings summary ends at $bottom px, below the first screen ($first_w x $first_h)" >&2
        status=1
    fi
else
    echo "check-report: the findings summary was not measured: ${summary_line:-script did not run}" >&2
    status=1
fi

for shot in "$png" "$first_png"; do
    if [[ -s "$shot" ]]; then
        echo "check-report: screenshot $shot"
    else
        echo "check-report: no screenshot $shot written" >&2
        status=1
    fi
done
exit "$status"
