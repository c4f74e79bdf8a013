#!/usr/bin/env bash
# Opens `modaltol draw`'s HTML page of every shipped example in headless Chromium and checks
# that it loads offline (nothing fetched: no http(s) resource in the page), that every mode can
# be selected (the canvas then shows it), and that the animation advances (the canvas at two
# moments differs). Keeps screenshots where CHECK_DRAWING_SHOTS names a folder.
# Usage: tests/browser/check_drawing.sh [target/release/modaltol]. Needs chromium (see
# check_report.sh, which installs it).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${1:-$root/target/release/modaltol}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
browse() {
  local attempt
  for attempt in 1 2; do
    if timeout -k 10 120 chromium "$@"; then
      return 0
    fi
    echo "check_drawing: chromium did not finish (attempt $attempt of 2)" >&2
  done
  return 1
}
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --user-data-dir="$dir/profile")
# The probe checks the page opened animating a mode (the canvas names it), shows the
# equilibrium, selects every mode in turn (the canvas must say it shows it and differ from the
# equilibrium's), then takes the canvas twice 700 ms apart on the first mode.
probe='<script>window.addEventListener("load",()=>{const s=document.getElementById("mode"),c=document.getElementById("view");const opened=(s.options.length<2)+(c.dataset.mode!=="0")>0;s.value="-1";s.dispatchEvent(new Event("change"));const still=c.toDataURL();let ok=opened?0:-1000;const n=s.options.length-1;for(let k=0;k<n;k++){s.value=String(k);s.dispatchEvent(new Event("change"));if(c.dataset.mode===String(k+1)\&\&c.toDataURL()!==still)ok++;}s.value=n>0?"0":"-1";s.dispatchEvent(new Event("change"));const a=c.toDataURL();setTimeout(()=>{const b=c.toDataURL();document.title="modes "+ok+"/"+n+(a!==b?" animates":" still");},700);});</script></body>'
failed=0
for model in "$root"/examples/*.toml; do
  name=$(basename "$model" .toml)
  page="$dir/$name.html"
  if ! "$bin" draw "$model" -o "$page" 2>"$dir/err"; then
    echo "check_drawing: FAILED, modaltol draw $name: $(cat "$dir/err")" >&2
    failed=1
    continue
  fi
  if grep -Eo '(src|href)="https?:[^"]*"|url\(https?:' "$page" | grep -q .; then
    echo "check_drawing: FAILED, $name's page fetches from the network" >&2
    failed=1
  fi
  sed "s|</body>|$probe|" "$page" > "$dir/check.html"
  dom=$(browse "${flags[@]}" --virtual-time-budget=3000 --dump-dom "file://$dir/check.html" 2>/dev/null)
  title=$(printf '%s' "$dom" | grep -o '<title>[^<]*</title>' | head -1)
  read -r ok total motion <<<"$(printf '%s' "$title" | sed -n 's|.*modes \([0-9]*\)/\([0-9]*\) \([a-z]*\).*|\1 \2 \3|p')"
  if [ -z "${total:-}" ] || [ "$ok" != "$total" ] || { [ "$total" -gt 0 ] && [ "$motion" != animates ]; }; then
    echo "check_drawing: FAILED, $name: the browser reports ${title:-no title}" >&2
    failed=1
  else
    echo "$name: $ok/$total modes selectable, ${motion}"
  fi
  if [ -n "${CHECK_DRAWING_SHOTS:-}" ]; then
    mkdir -p "$CHECK_DRAWING_SHOTS"
    for t in 200 900; do
      browse "${flags[@]}" --virtual-time-budget=$t --window-size=1000,1100 \
        --screenshot="$CHECK_DRAWING_SHOTS/${name}_$t.png" "file://$page#mode=1" >/dev/null 2>&1 || true
    done
  fi
done
exit $failed
