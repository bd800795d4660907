"""The FMU's win64 DLL under Wine against its linux64 binary: tests/c/fmi_run.c, built for
both platforms (gcc and mingw-w64), runs the FMI 2.0 co-simulation calling sequence on each
binary of fmu/BreathingTorso.fmu with the same drive and inputs, and the lung volume at every
communication point must agree within 1e-9 relative.

Skipped, saying why, when the FMU has no win64 binary (scripts/deploy.sh builds it when
rustup's x86_64-pc-windows-gnu target and mingw-w64 can be had) or when gcc, mingw-w64 or Wine
is missing (scripts/test.sh installs them as root).
"""

import glob
import os
import pathlib
import shutil
import struct
import subprocess
import zipfile

import fmpy
import pytest
from fmpy import read_model_description

ROOT = pathlib.Path(__file__).resolve().parents[2]
FMU = ROOT / "fmu" / "BreathingTorso.fmu"
HEADERS = pathlib.Path(fmpy.__file__).parent / "c-code"
HARNESS = ROOT / "tests" / "c" / "fmi_run.c"
SHIM = ROOT / "tests" / "c" / "wine_bcryptprimitives.c"
RELATIVE_TOLERANCE = 1e-9
STEPS, H = 168, 1 / 56  # 3 s at the SLP frame rate


def wine_has_bcryptprimitives():
    patterns = ["/usr/lib/*/wine/x86_64-windows/bcryptprimitives.dll",
                "/usr/lib/wine/x86_64-windows/bcryptprimitives.dll",
                "/opt/wine*/lib*/wine/x86_64-windows/bcryptprimitives.dll"]
    return any(glob.glob(p) for p in patterns)


def run(cmd, **kw):
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600, **kw)
    assert p.returncode == 0, f"{cmd[0]} exited with {p.returncode}\nstdout:\n{p.stdout[-2000:]}\nstderr:\n{p.stderr[-4000:]}"
    return p.stdout


def volumes(text):
    """(step, value) from the harness's "step bits value" lines, exactly from the bits."""
    rows = [line.split() for line in text.splitlines()]
    return [(int(k), struct.unpack("<d", int(bits, 16).to_bytes(8, "little"))[0]) for k, bits, _ in rows]


def test_win64_dll_under_wine_matches_linux64(tmp_path):
    assert FMU.is_file(), f"{FMU} missing: build it with `bash scripts/deploy.sh` (scripts/test.sh does)"
    with zipfile.ZipFile(FMU) as z:
        names = z.namelist()
        if "binaries/win64/BreathingTorso.dll" not in names:
            pytest.skip("skipped: fmu/BreathingTorso.fmu has no win64 binary (scripts/deploy.sh printed why)")
        z.extractall(tmp_path / "fmu")
    for tool in ["gcc", "x86_64-w64-mingw32-gcc", "wine"]:
        if shutil.which(tool) is None:
            pytest.skip(f"skipped: {tool} is not installed (as root, scripts/test.sh installs gcc-mingw-w64-x86-64 and wine)")

    md = read_model_description(str(FMU))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    args = [md.guid, str(STEPS), repr(H), str(vr["volume.lung"]),
            f"{vr['drive.ribs.amplitude']}=0.12", f"{vr['drive.diaphragm.amplitude']}=0.3",
            f"{vr['drive.diaphragm.phase']}=0.1", f"{vr['activation.external_obliques']}=0.05"]

    linux_exe = tmp_path / "fmi_run"
    run(["gcc", "-std=c11", "-O1", "-Wall", "-Wextra", "-Werror", f"-I{HEADERS}", str(HARNESS), "-o", str(linux_exe), "-ldl"])
    win_dir = tmp_path / "win"
    win_dir.mkdir()
    run(["x86_64-w64-mingw32-gcc", "-std=c11", "-O1", "-Wall", "-Wextra", "-Werror", f"-I{HEADERS}", str(HARNESS),
         "-o", str(win_dir / "fmi_run.exe"), "-static"])
    if not wine_has_bcryptprimitives():
        run(["x86_64-w64-mingw32-gcc", "-std=c11", "-O1", "-Wall", "-Wextra", "-Werror", "-shared", str(SHIM),
             "-o", str(win_dir / "bcryptprimitives.dll"), "-ladvapi32"])

    linux = volumes(run([str(linux_exe), str(tmp_path / "fmu/binaries/linux64/BreathingTorso.so"), *args]))
    env = dict(os.environ, WINEPREFIX=str(tmp_path / "wineprefix"), WINEDEBUG="-all",
               WINEDLLOVERRIDES="mscoree,mshtml=")
    dll = "Z:" + str(tmp_path / "fmu/binaries/win64/BreathingTorso.dll").replace("/", "\\")
    windows = volumes(run(["wine", str(win_dir / "fmi_run.exe"), dll, *args], env=env))

    assert [k for k, _ in windows] == [k for k, _ in linux] == list(range(1, STEPS + 1))
    lung = [v for _, v in linux]
    assert max(lung) - min(lung) > 0.2, "the torso breathes: the comparison covers a breath"
    worst = max(abs(w - l) / abs(l) for (_, w), (_, l) in zip(windows, linux))
    print(f"win64 under wine against linux64: largest relative difference of volume.lung {worst:.3g}")
    assert worst <= RELATIVE_TOLERANCE
