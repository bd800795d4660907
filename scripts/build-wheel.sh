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
#   3. with win64 among the platforms and mingw-w64 at hand, the win64 wheel too
#      (x86_64-pc-windows-gnu, abi3: it imports python3.dll alone).
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
# The win64 wheel, cross-built with Debian's mingw-w64 where scripts/deploy.sh found it (the
# same toolchain as the FMU's win64 DLL); pyo3 makes the python3.dll import library itself
# (its generate-import-lib feature), as no Windows Python is at hand to link against.
if [[ ",$PLATFORMS," == *",win64,"* ]] && command -v x86_64-w64-mingw32-gcc >/dev/null &&
  rustup target list --installed 2>/dev/null | grep -qx x86_64-pc-windows-gnu; then
  echo "== win64 wheel (maturin, x86_64-pc-windows-gnu)"
  PATH="$PWD/.venv/bin:$PATH" .venv/bin/maturin build --profile wheel --target x86_64-pc-windows-gnu \
    -m py/Cargo.toml -i "$PWD/.venv/bin/python" --out target/wheels
else
  echo "== win64 wheel: skipped (no x86_64-w64-mingw32-gcc or Rust target x86_64-pc-windows-gnu)"
fi
ls -l target/wheels/breathing_torso-*.whl
