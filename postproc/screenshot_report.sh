#!/usr/bin/env bash
# Screenshot of a report built by postproc/report.py, taken with headless Chromium, so that the
# report can be looked at without a desktop.
#
# Usage: postproc/screenshot_report.sh REPORT_DIR [OUT.png] [--height PX]
#   REPORT_DIR  directory holding report.html (and its PNGs)
#   OUT.png     the screenshot (default: REPORT_DIR/screenshot.png)
#   --height    window height in pixels (default 6000; the page is captured down to it)
#
# Needs Debian's chromium package (apt-get install -y chromium). Exit codes: 0 written;
# 2 bad arguments, no report.html, or no chromium; 1 chromium failed.
set -u

usage() { echo "usage: $0 REPORT_DIR [OUT.png] [--height PX]" >&2; exit 2; }

HEIGHT=6000
ARGS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --height) [ $# -ge 2 ] || usage; HEIGHT=$2; shift 2 ;;
    -h|--help) usage ;;
    *) ARGS+=("$1"); shift ;;
  esac
done
[ ${#ARGS[@]} -ge 1 ] && [ ${#ARGS[@]} -le 2 ] || usage
case "$HEIGHT" in ''|*[!0-9]*) echo "error: --height must be a number of pixels" >&2; exit 2 ;; esac

DIR=${ARGS[0]}
REPORT="$DIR/report.html"
if [ ! -f "$REPORT" ]; then
  echo "error: $REPORT: no such file (build it with postproc/report.py RESULTS.h5 -o $DIR)" >&2
  exit 2
fi
OUT=${ARGS[1]:-$DIR/screenshot.png}

CHROMIUM=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$CHROMIUM" ]; then
  echo "error: chromium not found (Debian: apt-get install -y chromium)" >&2
  exit 2
fi

REPORT_ABS=$(cd "$(dirname "$REPORT")" && pwd)/report.html
OUT_DIR=$(cd "$(dirname "$OUT")" 2>/dev/null && pwd) \
  || { echo "error: $(dirname "$OUT"): no such directory" >&2; exit 2; }
OUT_ABS="$OUT_DIR/$(basename "$OUT")"

# A private profile directory: no interference with (or from) another Chromium.
PROFILE=$(mktemp -d)
trap 'rm -rf "$PROFILE"' EXIT

rm -f "$OUT_ABS"
"$CHROMIUM" --headless --no-sandbox --disable-gpu --disable-dev-shm-usage \
  --disable-background-networking --hide-scrollbars --no-first-run \
  --user-data-dir="$PROFILE" --window-size="1400,$HEIGHT" \
  --screenshot="$OUT_ABS" "file://$REPORT_ABS" > "$PROFILE/chromium.log" 2>&1
rc=$?
if [ $rc -ne 0 ] || [ ! -s "$OUT_ABS" ]; then
  echo "error: chromium failed (exit $rc):" >&2
  tail -n 20 "$PROFILE/chromium.log" >&2
  exit 1
fi
echo "$OUT_ABS"
