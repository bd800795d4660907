#!/usr/bin/env bash
# Tests the Python package as a user installs it: builds the wheel (scripts/build-wheel.sh),
# checks that it is manylinux2014 (auditwheel show: glibc 2.17 symbol versions, no library
# outside the manylinux policy) and that the FMUs inside carry no pyo3, installs it into a fresh venv in a temporary folder (no
# source tree on the path), and runs the package's tests (py/tests, copied there) with
# pytest against the `torso` tool built from the same source (target/release/torso).
#
# Usage: bash scripts/test-wheel.sh [--no-build] [pytest arguments...]
#   --no-build  test the wheel already in target/wheels
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
BUILD=1
if [ "${1:-}" = "--no-build" ]; then
  BUILD=0
  shift
fi
if [ "$BUILD" = 1 ]; then
  bash scripts/build-wheel.sh
fi
cargo build --release --bin torso
wheels=(target/wheels/breathing_torso-*manylinux*.whl)
[ -f "${wheels[0]}" ] || { echo "test-wheel.sh: no wheel in target/wheels" >&2; exit 1; }
WHEEL=${wheels[0]}
win=(target/wheels/breathing_torso-*win_amd64.whl)
if [ -f "${win[0]}" ]; then
  # No Windows Python runs here: the win64 wheel is checked as a file. abi3 for CPython
  # >= 3.9, both FMUs inside, and an extension module that exports PyInit__native and
  # imports python3.dll (the stable ABI) and no version's own python3X.dll.
  echo "== ${win[0]}: $(stat -c %s "${win[0]}") bytes"
  WINDIR=$(mktemp -d)
  .venv/bin/python -m zipfile -e "${win[0]}" "$WINDIR"
  case "${win[0]}" in *-cp39-abi3-win_amd64.whl) ;; *) echo "test-wheel.sh: ${win[0]} is not a cp39-abi3 win_amd64 wheel" >&2; exit 1 ;; esac
  [ "$(find "$WINDIR" -name '*.fmu' | wc -l)" = 2 ] || { echo "test-wheel.sh: the win64 wheel lacks its FMUs" >&2; exit 1; }
  dump=$(x86_64-w64-mingw32-objdump -p "$WINDIR/breathing_torso/_native.pyd")
  grep -q 'DLL Name: python3.dll' <<<"$dump" || { echo "test-wheel.sh: _native.pyd does not import python3.dll" >&2; exit 1; }
  if grep -qE 'DLL Name: python3[0-9]+\.dll' <<<"$dump"; then
    echo "test-wheel.sh: _native.pyd imports a versioned python3X.dll (not abi3)" >&2
    exit 1
  fi
  grep -q 'PyInit__native' <<<"$dump" || { echo "test-wheel.sh: _native.pyd does not export PyInit__native" >&2; exit 1; }
  echo "   abi3 win_amd64, both FMUs inside, _native.pyd imports python3.dll and exports PyInit__native"
  rm -rf "$WINDIR"
fi
echo "== $WHEEL: $(stat -c %s "$WHEEL") bytes"
echo "== auditwheel show"
.venv/bin/python -m pip install -q --disable-pip-version-check -r python/requirements-wheel.txt
show=$(.venv/bin/auditwheel show "$WHEEL")
echo "$show"
grep -q 'manylinux_2_17_x86_64' <<<"$show" || {
  echo "test-wheel.sh: the wheel is not manylinux2014 (manylinux_2_17) compatible" >&2
  exit 1
}
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
echo "== the FMUs in the wheel carry no Python binding"
.venv/bin/python - "$WHEEL" <<'PY'
import sys, zipfile, io
wheel = zipfile.ZipFile(sys.argv[1])
fmus = [n for n in wheel.namelist() if n.endswith(".fmu")]
assert len(fmus) == 2, f"expected the FMI 2.0 and 3.0 FMUs in the wheel, found {fmus}"
for name in fmus:
    fmu = zipfile.ZipFile(io.BytesIO(wheel.read(name)))
    for binary in (n for n in fmu.namelist() if n.startswith("binaries/") and not n.endswith("/")):
        data = fmu.read(binary)
        for needle in (b"PyInit_", b"pyo3", b"Py_IsInitialized"):
            assert needle not in data, f"{name}:{binary} contains {needle!r}"
        print(f"   {name}:{binary}: {len(data)} bytes, no pyo3")
PY
echo "== fresh venv in $WORK"
python3 -m venv "$WORK/venv"
# fmpy runs the bundled FMUs, pandas the table results
"$WORK/venv/bin/python" -m pip install -q --disable-pip-version-check "$WHEEL" pytest fmpy pandas
cp -r py/tests "$WORK/tests"
cd "$WORK"
BT_TORSO="$ROOT/target/release/torso" BT_DATA="$ROOT/data" BT_SOURCE="$ROOT" \
  "$WORK/venv/bin/python" -m pytest -q -rs -p no:cacheprovider tests "$@"
