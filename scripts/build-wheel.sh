#!/usr/bin/env bash
# Builds the Python package's wheel, target/wheels/breathing_torso-*.whl (py/pyproject.toml):
#
#   1. the distributable FMUs (scripts/deploy.sh: linux64 against glibc 2.17, win64 where its
#      toolchain is had; FMI 2.0 and 3.0) into py/python/breathing_torso/fmu/, so that they
#      ship inside the wheel (breathing_torso.fmu_path());
#   2. `maturin build --profile wheel` (release code without debug info) of the extension
#      module (py/, pyo3 abi3: one wheel for every CPython >= 3.9) with maturin from
#      python/requirements-wheel.txt in .venv. The wheel is
#      built for manylinux2014 (glibc 2.17) with cargo-zigbuild's zig (`--zig`), the same
#      baseline as the FMU's library; maturin's own audit checks the glibc symbol versions.
#
# Usage: bash scripts/build-wheel.sh [--platforms linux64,win64]   (the FMUs' platforms)
set -euo pipefail
cd "$(dirname "$0")/.."
PLATFORMS=linux64,win64
while [ $# -gt 0 ]; do
  case "$1" in
    --platforms) PLATFORMS=$2; shift 2 ;;
    *) echo "build-wheel.sh: unknown argument $1 (known: --platforms LIST)" >&2; exit 2 ;;
  esac
done
bash scripts/python-env.sh
.venv/bin/python -m pip install -q --disable-pip-version-check -r python/requirements-wheel.txt
FMU_DIR=py/python/breathing_torso/fmu
mkdir -p "$FMU_DIR"
echo "== FMUs into $FMU_DIR (scripts/deploy.sh)"
bash scripts/deploy.sh --platforms "$PLATFORMS" --out "$FMU_DIR/BreathingTorso.fmu"
echo "== wheel (maturin, manylinux2014)"
rm -f target/wheels/breathing_torso-*.whl
# deploy.sh installed ziglang and cargo-zigbuild into .venv; maturin --zig runs them.
PATH="$PWD/.venv/bin:$PATH" .venv/bin/maturin build --profile wheel --zig --compatibility manylinux2014 \
  -m py/Cargo.toml -i "$PWD/.venv/bin/python" --out target/wheels
ls -l target/wheels/breathing_torso-*.whl
