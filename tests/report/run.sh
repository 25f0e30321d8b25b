#!/usr/bin/env bash
# Browser test of the reports (`make test-report`, part of `make test`): headless Chromium from
# Debian's packages (installed when missing) opens the committed figures/default/index.html,
# every image must decode and a screenshot is taken; then the same page with one PNG
# truncated must fail (the check can fail). When Chromium cannot be had: an error under CI,
# a skip with a message otherwise.
set -euo pipefail
repo=$(cd "$(dirname "$0")/../.." && pwd)
find_chromium() { command -v chromium || command -v chromium-browser || true; }
chromium=$(find_chromium)
if [ -z "$chromium" ] && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    echo "installing chromium (apt-get, about 20 s)"
    { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium; } >/dev/null 2>&1 || true
    chromium=$(find_chromium)
fi
if [ -z "$chromium" ]; then
    if [ -n "${CI:-}" ]; then
        echo "error: chromium is needed for the report test and could not be installed" >&2
        exit 1
    fi
    echo "skipped: no chromium (install it: apt-get install chromium)"
    exit 0
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
page="$repo/figures/default/index.html"
[ -f "$page" ] || { echo "error: $page is missing (make figures)" >&2; exit 1; }
python3 "$repo/tests/report/check_report.py" "$chromium" "$page" "$work/default.png"
# Negative controls: a corrupt image, a missing image.
for broken in corrupt missing; do
    cp -r "$repo/figures/default" "$work/$broken"
    png="$work/$broken/fig3.png"
    if [ "$broken" = corrupt ]; then
        printf '%080d' 0 | dd of="$png" bs=1 seek=0 conv=notrunc 2>/dev/null
    else
        rm "$png"
    fi
    if python3 "$repo/tests/report/check_report.py" "$chromium" "$work/$broken/index.html" "$work/$broken.png"; then
        echo "error: a page with a $broken image passed the report check" >&2
        exit 1
    fi
done
echo "report test passed"
