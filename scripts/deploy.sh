#!/usr/bin/env bash
# Builds the distributable FMU, fmu/BreathingTorso.fmu, with one shared library per platform:
#
#   linux64  built against glibc 2.17 (cargo-zigbuild, with zig from the `ziglang` PyPI
#            package, both installed into .venv from python/requirements-deploy.txt); the
#            dynamic symbol table is checked with `objdump -T`: no GLIBC_ version above 2.17;
#   win64    built for x86_64-pc-windows-gnu with Debian's mingw-w64 (the Rust target is
#            added with rustup, the compiler installed with apt-get when running as root);
#            its imports are checked: Windows system DLLs only.
#
# Both use the `fmu` cargo profile (release code, no debug info, stripped) and remap the build
# machine's paths (--remap-path-prefix); no path of the project or of the cargo home may be
# left in a binary, and the packaged FMU must stay at most 4 MB (4,000,000 bytes). Only the
# cdylib is built for these targets (`cargo rustc --crate-type cdylib`: with the rlib beside
# it, link-time optimisation would not run and the PE linker would keep the whole command-line
# tool), and without the default feature `tools`, so the command-line tool, the benchmarks and
# clap are not even compiled into it. win64 is skipped, saying why, when its toolchain cannot be had; linux64 cannot be
# skipped.
#
# The same binaries are packaged a second time as the FMI 3.0 FMU, BreathingTorso3.fmu beside
# the FMI 2.0 one (the library exports both interfaces), under the same size limit.
# python/tests/test_fmu_win64.py (run by scripts/test.sh after this script) then runs each
# FMU's win64 DLL under Wine against its linux64 binary: tests/c/fmi_run.c the FMI 2.0
# calling sequence, tests/c/fmi3_run.c the FMI 3.0 one.
#
# Usage: bash scripts/deploy.sh [--platforms linux64,win64] [--out fmu/BreathingTorso.fmu]
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
PLATFORMS=linux64,win64
OUT=fmu/BreathingTorso.fmu
GLIBC_BASELINE=2.17
MAX_BYTES=4000000
while [ $# -gt 0 ]; do
  case "$1" in
    --platforms) PLATFORMS=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    *) echo "deploy.sh: unknown argument $1 (known: --platforms LIST, --out FILE)" >&2; exit 2 ;;
  esac
done

fail() { echo "deploy.sh: $*" >&2; exit 1; }
wants() { case ",$PLATFORMS," in *",$1,"*) return 0 ;; *) return 1 ;; esac; }
for p in ${PLATFORMS//,/ }; do
  case "$p" in linux64 | win64) ;; *) fail "unknown platform $p (known: linux64, win64)" ;; esac
done
as_root() { [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; }
apt_install() {
  as_root || return 1
  echo "   apt-get install $*"
  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$@") >/dev/null 2>&1
}

CARGO_HOME_DIR=${CARGO_HOME:-$HOME/.cargo}
# Only for the cross builds: the host's release build keeps its flags (and its cache).
CROSS_RUSTFLAGS="${RUSTFLAGS:+$RUSTFLAGS }--remap-path-prefix=$ROOT=/breathing-torso --remap-path-prefix=$CARGO_HOME_DIR=/cargo"

# No build-machine path may be left in a shipped binary.
check_paths() {
  local lib=$1 p
  for p in "$ROOT" "$CARGO_HOME_DIR" "$HOME"; do
    if grep -aqF -- "$p/" "$lib"; then
      fail "$lib contains the build path $p/: $(grep -aoF -- "$p/" "$lib" | head -1)"
    fi
  done
}

BINARIES=()

if wants linux64; then
  echo "== linux64: cdylib against glibc $GLIBC_BASELINE (cargo-zigbuild)"
  bash scripts/python-env.sh
  .venv/bin/python -m pip install -q --disable-pip-version-check -r python/requirements-deploy.txt
  command -v objdump >/dev/null || apt_install binutils || fail "objdump (binutils) is needed to check the glibc baseline"
  # cargo-zigbuild runs zig from the venv's `ziglang` package (python3 -m ziglang).
  PATH="$ROOT/.venv/bin:$PATH" RUSTFLAGS="$CROSS_RUSTFLAGS" cargo-zigbuild rustc --profile fmu --lib --crate-type cdylib --no-default-features \
    --target "x86_64-unknown-linux-gnu.$GLIBC_BASELINE"
  LIB=target/x86_64-unknown-linux-gnu/fmu/libbreathing_torso.so
  [ -f "$LIB" ] || fail "cargo-zigbuild wrote no $LIB"
  versions=$(objdump -T "$LIB" | grep -o 'GLIBC_[0-9][0-9.]*' | sed 's/^GLIBC_//' | sort -uV)
  newest=$(echo "$versions" | tail -1)
  [ -n "$newest" ] || fail "objdump -T $LIB shows no GLIBC_ symbol version"
  if [ "$(printf '%s\n%s\n' "$newest" "$GLIBC_BASELINE" | sort -V | tail -1)" != "$GLIBC_BASELINE" ]; then
    objdump -T "$LIB" | grep GLIBC_ >&2
    fail "$LIB needs GLIBC_$newest, above the baseline $GLIBC_BASELINE"
  fi
  echo "   glibc baseline ok: newest symbol version GLIBC_$newest <= $GLIBC_BASELINE"
  check_paths "$LIB"
  BINARIES+=(--binary "linux64=$LIB")
fi

win64_toolchain() {
  if ! rustup target list --installed 2>/dev/null | grep -qx x86_64-pc-windows-gnu; then
    echo "   rustup target add x86_64-pc-windows-gnu"
    rustup target add x86_64-pc-windows-gnu >/dev/null 2>&1 || { WHY="rustup could not add the target x86_64-pc-windows-gnu"; return 1; }
  fi
  if ! command -v x86_64-w64-mingw32-gcc >/dev/null; then
    apt_install gcc-mingw-w64-x86-64 || { WHY="x86_64-w64-mingw32-gcc is missing (Debian: apt-get install gcc-mingw-w64-x86-64, as root)"; return 1; }
  fi
  command -v x86_64-w64-mingw32-objdump >/dev/null || { WHY="x86_64-w64-mingw32-objdump is missing (binutils-mingw-w64-x86-64)"; return 1; }
}

if wants win64; then
  echo "== win64: DLL for x86_64-pc-windows-gnu (mingw-w64)"
  WHY=""
  if win64_toolchain; then
    CARGO_TARGET_X86_64_PC_WINDOWS_GNU_LINKER=x86_64-w64-mingw32-gcc RUSTFLAGS="$CROSS_RUSTFLAGS" \
      cargo rustc --profile fmu --lib --crate-type cdylib --no-default-features --target x86_64-pc-windows-gnu
    DLL=target/x86_64-pc-windows-gnu/fmu/breathing_torso.dll
    [ -f "$DLL" ] || fail "cargo wrote no $DLL"
    # A DLL that needs a mingw runtime DLL (libgcc_s, libwinpthread) would not load on a
    # Windows machine without mingw: only system DLLs may be imported.
    imports=$(x86_64-w64-mingw32-objdump -p "$DLL" | sed -n 's/^\s*DLL Name: //p' | sort -u)
    echo "   imports: $(echo $imports)"
    for dll in $imports; do
      case "$(echo "$dll" | tr 'A-Z' 'a-z')" in
        kernel32.dll | ntdll.dll | msvcrt.dll | ws2_32.dll | userenv.dll | advapi32.dll | bcrypt.dll | \
          bcryptprimitives.dll | api-ms-win-*.dll | ucrtbase.dll | shell32.dll | ole32.dll | oleaut32.dll | secur32.dll | synchronization.dll) ;;
        *) fail "$DLL imports $dll, which a plain Windows machine does not have" ;;
      esac
    done
    check_paths "$DLL"
    BINARIES+=(--binary "win64=$DLL")
  else
    echo "   win64 skipped: $WHY"
  fi
fi

[ ${#BINARIES[@]} -gt 0 ] || fail "no binary was built"
echo "== package $OUT"
cargo build --release --bin torso
target/release/torso fmu build --out "$OUT" "${BINARIES[@]}"
bytes=$(stat -c %s "$OUT")
[ "$bytes" -le "$MAX_BYTES" ] || fail "$OUT is $bytes bytes, above the limit of $MAX_BYTES"
echo "   $OUT: $bytes bytes (limit $MAX_BYTES)"
OUT3="$(dirname "$OUT")/BreathingTorso3.fmu"
echo "== package $OUT3 (FMI 3.0)"
target/release/torso fmu build --fmi-version 3 --out "$OUT3" "${BINARIES[@]}"
bytes=$(stat -c %s "$OUT3")
[ "$bytes" -le "$MAX_BYTES" ] || fail "$OUT3 is $bytes bytes, above the limit of $MAX_BYTES"
echo "   $OUT3: $bytes bytes (limit $MAX_BYTES)"
