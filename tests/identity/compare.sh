#!/usr/bin/env bash
# Compares two trees written by outputs.sh byte for byte, wall times masked (the seconds and
# ratios in summary.json, the timing row of report.html, progress lines; manifest.json holds
# the hashes of those files and is skipped). Prints every file that differs; exit 1 if any.
# Usage: tests/identity/compare.sh OLD_DIR NEW_DIR
A=$1; B=$2; bad=0
norm() {
  python3 - "$1" <<'PY'
import re, sys
t = open(sys.argv[1], errors="replace").read()
t = re.sub(r'"([a-z_]*seconds|ratio_[a-z_]+)": [0-9.e+-]+', r'"\1": T', t)
t = re.sub(r'(<tr><td>this run[^<]*</td>)(<td>[^<]*</td>){5}', r'\1TIMES', t)
t = re.sub(r'[0-9]+\.[0-9]+ s\b', 'T s', t)
t = re.sub(r'\(ratio [0-9.]+\)', '(ratio R)', t)
t = re.sub(r'\([0-9.]+× the analytic time\)', '(R× the analytic time)', t)
t = re.sub(r'/tmp/[A-Za-z0-9._-]+/', '/tmp/X/', t)
t = "\n".join(l for l in t.split("\n")
              if not re.match(r'^(quadrature|derivatives|monte carlo|sweep speeds)[^:]*: \d+/\d+$', l))
sys.stdout.write(t)
PY
}
for f in $(cd "$A" && find . -type f | sort); do
  case $f in */manifest.json) continue;; esac
  if [ ! -f "$B/$f" ]; then echo "missing $f"; bad=1; continue; fi
  if ! cmp -s "$A/$f" "$B/$f" && ! cmp -s <(norm "$A/$f") <(norm "$B/$f"); then
    echo "differs: $f"; bad=1
  fi
done
for f in $(cd "$B" && find . -type f | sort); do [ -f "$A/$f" ] || { echo "extra $f"; bad=1; }; done
echo "compared: $([ $bad = 0 ] && echo identical || echo DIFFERENT)"
exit $bad
