#!/usr/bin/env bash
# What the FMI 2.0 layer adds per communication step (benches/c/fmu_overhead.c): the FMU's
# library run through fmi2DoStep + fmi2GetReal and through the C ABI in one process, reading
# the four volumes and the 60 markers of the default grid at each of FRAMES steps.
#   bash scripts/bench-fmu-overhead.sh [FRAMES [REPEATS [METHOD]]]   (defaults 1000 7 0)
# METHOD is solver.method: 0 Dormand-Prince (inertial), 4 quasi-static.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -d .venv ] || bash scripts/python-env.sh
headers=$(ls -d .venv/lib/python3*/site-packages/fmpy/c-code | head -1)
cargo build --release --quiet
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
target/release/torso fmu build --out "$out/BreathingTorso.fmu" >/dev/null
(cd "$out" && unzip -q BreathingTorso.fmu)
guid=$(sed -n 's/.*guid="\([^"]*\)".*/\1/p' "$out/modelDescription.xml" | head -1)
gcc -std=c11 -D_POSIX_C_SOURCE=199309L -O2 -I "$headers" -o "$out/fmu_overhead" \
  benches/c/fmu_overhead.c -ldl
"$out/fmu_overhead" "$out/binaries/linux64/BreathingTorso.so" "$guid" "${1:-1000}" "${2:-7}" "${3:-0}"
