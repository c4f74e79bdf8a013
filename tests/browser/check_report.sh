#!/usr/bin/env bash
# Renders an `analyze` report in a real browser (headless Chromium from Debian's packages) and
# checks that the page loads and every plot on it decodes; keeps a screenshot for a look.
# Usage: tests/browser/check_report.sh [target/release/modaltol]. Installs Chromium when it is
# missing and apt-get is usable (as root, e.g. in CI).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${1:-$root/target/release/modaltol}
if ! command -v chromium >/dev/null; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    echo "installing chromium from Debian's packages" >&2
    apt-get update -qq >/dev/null && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
  else
    echo "check_report: chromium is not installed and cannot be installed here" >&2
    exit 1
  fi
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$bin" analyze "$root/examples/rotating_pendulum.toml" -o "$dir/out" --speed 0:6:0.05 --samples 50 --seed 1 2>/dev/null
# A probe in a copy of the page: the title becomes "loaded N/M" once the images have decoded.
probe='<script>window.addEventListener("load",()=>{const i=[...document.images];document.title="loaded "+i.filter(x=>x.complete\&\&x.naturalWidth>0).length+"/"+i.length;});</script></body>'
sed "s|</body>|$probe|" "$dir/out/report.html" > "$dir/out/check.html"
# Headless Chromium has been seen to hang for good (no output, no exit) on one run in many:
# each run is bounded, and a run that times out is tried once more before the check fails.
browse() {
  local attempt
  for attempt in 1 2; do
    if timeout -k 10 120 chromium "$@"; then
      return 0
    fi
    echo "check_report: chromium did not finish (attempt $attempt of 2)" >&2
  done
  return 1
}
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --user-data-dir="$dir/profile" --virtual-time-budget=10000)
dom=$(browse "${flags[@]}" --dump-dom "file://$dir/out/check.html" 2>/dev/null)
title=$(printf '%s' "$dom" | grep -o '<title>[^<]*</title>' | head -1)
loaded=$(printf '%s' "$title" | sed -n 's|.*loaded \([0-9]*\)/\([0-9]*\).*|\1 \2|p')
read -r ok total <<<"${loaded:-0 -1}"
if [ "$total" -lt 10 ] || [ "$ok" != "$total" ]; then
  echo "check_report: FAILED, the browser reports ${title:-no title}" >&2
  exit 1
fi
shot=${CHECK_REPORT_SCREENSHOT:-$dir/shot.png}
browse "${flags[@]}" --window-size=1100,2400 --screenshot="$shot" "file://$dir/out/report.html" >/dev/null 2>&1 || {
  echo "check_report: FAILED, chromium did not take the screenshot" >&2
  exit 1
}
size=$(stat -c %s "$shot")
if [ "$size" -lt 50000 ]; then
  echo "check_report: FAILED, the screenshot is only $size bytes" >&2
  exit 1
fi
echo "report.html renders in Chromium: $ok/$total plots decoded, screenshot $size bytes"
