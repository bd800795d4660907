"""The distributable FMU as it ships (fmu/BreathingTorso.fmu, written by scripts/deploy.sh):
at most 4 MB, every binary stripped (no debug section) and free of build-machine paths, the
linux64 binary needing no glibc symbol version above 2.17 (objdump -T), fmpy's validation
clean.
"""

import os
import pathlib
import re
import shutil
import subprocess
import zipfile

import pytest
from fmpy.validation import validate_fmu

ROOT = pathlib.Path(__file__).resolve().parents[2]
FMU = ROOT / "fmu" / "BreathingTorso.fmu"
MAX_BYTES = 4_000_000
GLIBC_BASELINE = (2, 17)


@pytest.fixture(scope="module")
def binaries():
    assert FMU.is_file(), f"{FMU} missing: build it with `bash scripts/deploy.sh` (scripts/test.sh does)"
    with zipfile.ZipFile(FMU) as z:
        return {n.split("/")[1]: z.read(n) for n in z.namelist()
                if n.startswith("binaries/") and not n.endswith("/")}


def objdump(args, data, tmp_path, name):
    if shutil.which("objdump") is None:
        pytest.skip("objdump (binutils) is not installed")
    path = tmp_path / name
    path.write_bytes(data)
    return subprocess.run(["objdump", *args, str(path)], check=True, capture_output=True, text=True).stdout


def test_fmu_is_at_most_4_mb_and_validates():
    assert FMU.stat().st_size <= MAX_BYTES, f"{FMU.stat().st_size} bytes"
    assert validate_fmu(str(FMU)) == []


def test_linux64_is_present(binaries):
    assert "linux64" in binaries


def test_binaries_are_stripped(binaries, tmp_path):
    for platform, data in binaries.items():
        sections = objdump(["-h"], data, tmp_path, platform)
        names = re.findall(r"^\s*\d+\s+(\S+)", sections, re.M)
        assert names, sections
        debug = [n for n in names if n.startswith((".debug", ".zdebug"))]
        assert debug == [], f"{platform} carries {debug}"
        if platform == "linux64":
            symbols = objdump(["-t"], data, tmp_path, platform)
            assert "no symbols" in symbols, f"{platform} keeps a symbol table"


def test_no_build_machine_paths(binaries):
    cargo_home = os.environ.get("CARGO_HOME", str(pathlib.Path.home() / ".cargo"))
    for platform, data in binaries.items():
        for path in {str(ROOT), cargo_home, str(pathlib.Path.home())}:
            assert (path + "/").encode() not in data, f"{platform} contains {path}/"


def test_linux64_glibc_baseline(binaries, tmp_path):
    table = objdump(["-T"], binaries["linux64"], tmp_path, "linux64")
    versions = {tuple(int(x) for x in v.split(".")) for v in re.findall(r"GLIBC_([0-9][0-9.]*)", table)}
    assert versions, "no GLIBC_ symbol versions: not a glibc build?"
    above = sorted(v for v in versions if v > GLIBC_BASELINE)
    assert above == [], f"needs glibc {'.'.join(map(str, max(above)))} > 2.17"
