#!/usr/bin/env bash
# The whole test suite, set-up included: the Rust tests, then the Python package built as a
# wheel, installed into .venv and tested with pytest against the command line.
# Python packages come from PyPI, pinned in python/requirements-dev.txt.
set -euo pipefail
cd "$(dirname "$0")"
cargo test --release
cargo build --release --bin modaltol
if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv
fi
.venv/bin/pip install --quiet --disable-pip-version-check -r python/requirements-dev.txt
rm -f target/wheels/modaltol-*.whl
.venv/bin/maturin build --release --quiet -m python/Cargo.toml -o target/wheels
.venv/bin/pip install --quiet --disable-pip-version-check --force-reinstall --no-deps \
    target/wheels/modaltol-*.whl
MODALTOL_BIN="$PWD/target/release/modaltol" .venv/bin/pytest -q python/tests
