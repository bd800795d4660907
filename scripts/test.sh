#!/usr/bin/env bash
# Runs every test of the project: formatting, lints, Rust tests, C and Python tests.
# Installs what it needs itself (Rust crates through cargo, a Python venv with fmpy, zig and
# cargo-zigbuild; as root, mingw-w64 and wine from apt for the win64 binary and its test).
# Ends with one line over all stages: `N passed, N failed` (each test of cargo test and
# pytest counts once, every other stage once); the exit status is 1 when anything failed.
set -uo pipefail
cd "$(dirname "$0")/.."

passed=0
failed=0
failures=()
log=$(mktemp)
trap 'rm -f "$log"' EXIT

summary() {
  local IFS=';'
  echo "== summary: $passed passed, $failed failed${failures[*]:+ (failed stages: ${failures[*]})}"
}

# stage NAME required|optional COMMAND...: runs COMMAND, counts its tests (cargo test's
# `test result:` lines, pytest's closing line) or the stage itself as one check. A required
# stage that fails stops the run (what follows needs it).
stage() {
  local name=$1 need=$2
  shift 2
  echo "== $name"
  "$@" 2>&1 | tee "$log"
  local status=${PIPESTATUS[0]} p=0 f=0 line
  while read -r line; do
    p=$((p + $(grep -oE '[0-9]+ passed' <<<"$line" | grep -oE '[0-9]+' || echo 0)))
    f=$((f + $(grep -oE '[0-9]+ failed' <<<"$line" | grep -oE '[0-9]+' || echo 0)))
    f=$((f + $(grep -oE '[0-9]+ errors?' <<<"$line" | grep -oE '[0-9]+' || echo 0)))
  done < <(grep -E '^test result: |[0-9]+ (passed|failed|errors?).* in [0-9.]+s' "$log")
  if [ $((p + f)) -eq 0 ]; then
    if [ "$status" -eq 0 ]; then p=1; else f=1; fi
  elif [ "$status" -ne 0 ] && [ "$f" -eq 0 ]; then
    f=1 # the stage failed outside any test (a test binary that did not compile)
  fi
  passed=$((passed + p))
  failed=$((failed + f))
  if [ "$status" -ne 0 ]; then
    failures+=("$name")
    if [ "$need" = required ]; then
      summary
      exit 1
    fi
  fi
}

stage "cargo fmt --check" optional cargo fmt --all -- --check
stage "cargo clippy" optional cargo clippy --all-targets --release -- -D warnings
# The Python binding (py/) is a workspace member outside the root package's targets.
stage "cargo clippy (Python binding, py/)" optional cargo clippy --release -p breathing-torso-python -- -D warnings
# fmpy also supplies the official FMI 2.0 headers for the Rust tests.
stage "python venv" required bash scripts/python-env.sh
# The C tests link the cdylib; the Python tests load the FMU.
stage "release library" required cargo build --release
stage "FMU" required target/release/torso fmu build --out fmu/BreathingTorso.fmu
stage "FMU (FMI 3.0)" required target/release/torso fmu build --fmi-version 3 --out fmu/BreathingTorso3.fmu
stage "cargo test" optional cargo test --release --no-fail-fast

built_once() {
  local rebuild
  rebuild=$(cargo build --release -v 2>&1)
  if ! grep -q "Fresh breathing-torso" <<<"$rebuild"; then
    echo "cargo build --release after cargo test --release rebuilds the crate:"
    grep -E "Dirty|Compiling" <<<"$rebuild"
    return 1
  fi
  echo "the crate was built once for build and test"
}
stage "the crate is built once for build and test (Cargo.toml: resolver)" optional built_once

# The distributable FMU replaces the development one for the Python tests.
stage "distributable FMU: stripped linux64 (glibc 2.17) and win64 binaries, checked (scripts/deploy.sh)" \
  optional bash scripts/deploy.sh --out fmu/BreathingTorso.fmu

# The Python package as a user installs it: the wheel (manylinux2014, the distributable FMUs
# inside), auditwheel's check, a fresh venv outside the source tree and the package's tests.
stage "Python package: wheel, auditwheel, fresh venv, py/tests (scripts/test-wheel.sh)" \
  optional bash scripts/test-wheel.sh
# python/fit_slp.py reads recordings with the package: the same wheel goes into .venv.
stage "Python package into .venv" optional \
  bash -c '.venv/bin/python -m pip install -q --disable-pip-version-check --force-reinstall --no-deps target/wheels/breathing_torso-*manylinux*.whl'

if ! command -v wine >/dev/null && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
  echo "== wine (runs the win64 binary against linux64, FMI 2.0 and FMI 3.0, in python/tests/test_fmu_win64.py)"
  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends wine wine64) \
    >/dev/null 2>&1 || echo "wine could not be installed: the win64 test will say it is skipped" >&2
fi

if [ -d python/tests ] && ls python/tests/test_*.py >/dev/null 2>&1; then
  # -rs prints why a test is skipped
  stage "python tests" optional .venv/bin/python -m pytest -q -rs python/tests
fi

summary
[ "$failed" -eq 0 ]
