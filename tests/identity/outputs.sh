#!/usr/bin/env bash
# Every output of every shipped example, for a byte-for-byte comparison of two binaries across
# a restructuring (see compare.sh): sweep with AD and FD sensitivities (and the transfer where
# the model has one), modal as text and JSON, check, sensitivity, frf, analyze --samples 300,
# a governor analysis split into two shards and merged, a Sobol-sampled analysis, drawings, an
# allocation and Sobol indices.
# Usage: tests/identity/outputs.sh BINARY /tmp/OUTDIR   (from the repository root; about 2
# minutes; keep OUTDIR under /tmp, whose path compare.sh masks in the messages)
set -u
BIN=$(realpath "$1"); OUT=$2
rm -rf "$OUT"; mkdir -p "$OUT"
for f in examples/*.toml; do
  n=$(basename "$f" .toml)
  tr=""; "$BIN" sweep "$f" --transfer model --speed 0:1:1 >/dev/null 2>&1 && tr="--transfer model"
  "$BIN" sweep "$f" --sensitivity $tr -o "$OUT/$n.sweep.csv" 2>"$OUT/$n.sweep.err"; echo $? >>"$OUT/$n.sweep.err"
  "$BIN" sweep "$f" --sensitivity --derivatives fd $tr -o "$OUT/$n.sweepfd.csv" 2>"$OUT/$n.sweepfd.err"
  "$BIN" modal "$f" >"$OUT/$n.modal.txt" 2>&1
  "$BIN" modal "$f" --format json >"$OUT/$n.modal.json" 2>&1
  "$BIN" check "$f" >"$OUT/$n.check.txt" 2>&1
  "$BIN" sensitivity "$f" >"$OUT/$n.sens.txt" 2>&1
  "$BIN" frf "$f" >"$OUT/$n.frf.txt" 2>&1
  "$BIN" analyze "$f" --samples 300 -o "$OUT/$n.analyze" >"$OUT/$n.analyze.out" 2>&1
done
f=examples/governor.toml
for k in 1 2; do "$BIN" analyze $f --samples 300 --shard $k/2 -o "$OUT/shard$k" >/dev/null 2>&1; done
"$BIN" merge --model $f "$OUT/shard1/shard-1-of-2.json" "$OUT/shard2/shard-2-of-2.json" -o "$OUT/merged" >"$OUT/merge.out" 2>&1
"$BIN" analyze examples/rotating_pendulum.toml --samples 300 --sampling sobol -o "$OUT/sobol" >/dev/null 2>&1
# The drawings, the allocation and the Sobol indices (added with issue 54's table redesign).
for n in governor rotating_blade spinning_spatial_fourbar; do
  "$BIN" draw examples/$n.toml -o "$OUT/$n.draw.svg" >/dev/null 2>&1
  "$BIN" draw examples/$n.toml --mode 1 -o "$OUT/$n.draw.html" >/dev/null 2>&1
done
"$BIN" allocate examples/governor_specification.toml --speed 1.4:2.1:0.05 -o "$OUT/allocate" >"$OUT/allocate.out" 2>&1
"$BIN" analyze examples/governor_specification.toml --speed 1.4:2.1:0.05 --samples 300 --sobol 64 -o "$OUT/sobolidx" >/dev/null 2>&1
