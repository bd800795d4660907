#!/usr/bin/env bash
# Runs every test of the project: formatting, lints, Rust tests, C and Python tests.
# Installs what it needs itself (Rust crates through cargo, a Python venv with fmpy).
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== cargo fmt --check"
cargo fmt --all -- --check

echo "== cargo clippy"
cargo clippy --all-targets --release -- -D warnings

echo "== python venv (fmpy also supplies the official FMI 2.0 headers for the Rust tests)"
bash scripts/python-env.sh

echo "== release library and FMU (the C tests link the cdylib)"
cargo build --release
target/release/torso fmu build --out fmu/BreathingTorso.fmu

echo "== cargo test"
cargo test --release

echo "== the crate is built once for build and test (Cargo.toml: resolver)"
rebuild=$(cargo build --release -v 2>&1)
if ! grep -q "Fresh breathing-torso" <<<"$rebuild"; then
  echo "cargo build --release after cargo test --release rebuilds the crate:" >&2
  grep -E "Dirty|Compiling" <<<"$rebuild" >&2
  exit 1
fi

if [ -d python/tests ] && ls python/tests/test_*.py >/dev/null 2>&1; then
  echo "== python tests"
  bash scripts/python-env.sh
  .venv/bin/python -m pytest -q python/tests
fi
