#!/usr/bin/env bash
# Runs every test of the project: formatting, lints, Rust tests, C and Python tests.
# Installs what it needs itself (Rust crates through cargo, a Python venv with fmpy, zig and
# cargo-zigbuild; as root, mingw-w64 and wine from apt for the win64 binary and its test).
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== cargo fmt --check"
cargo fmt --all -- --check

echo "== cargo clippy"
cargo clippy --all-targets --release -- -D warnings

echo "== python venv (fmpy also supplies the official FMI 2.0 headers for the Rust tests)"
bash scripts/python-env.sh

echo "== release library (the C tests link the cdylib)"
cargo build --release

echo "== cargo test"
cargo test --release

echo "== distributable FMU: stripped linux64 (glibc 2.17) and win64 binaries, checked (scripts/deploy.sh)"
bash scripts/deploy.sh --out fmu/BreathingTorso.fmu

if ! command -v wine >/dev/null && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
  echo "== wine (runs the win64 binary against linux64 in python/tests/test_fmu_win64.py)"
  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends wine wine64) \
    >/dev/null 2>&1 || echo "wine could not be installed: the win64 test will say it is skipped" >&2
fi

if [ -d python/tests ] && ls python/tests/test_*.py >/dev/null 2>&1; then
  echo "== python tests (on the distributable FMU; -rs prints why a test is skipped)"
  bash scripts/python-env.sh
  .venv/bin/python -m pytest -q -rs python/tests
fi
