"""The FMUs' win64 DLL under Wine against their linux64 binary: tests/c/fmi_run.c, built for
both platforms (gcc and mingw-w64), runs the FMI 2.0 co-simulation calling sequence on each
binary of fmu/BreathingTorso.fmu, and tests/c/fmi3_run.c the FMI 3.0 one on each binary of
fmu/BreathingTorso3.fmu, with the same drive and inputs; the lung volume at every
communication point must agree within 1e-9 relative.

Skipped, saying why, when an FMU has no win64 binary (scripts/deploy.sh builds it when
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
FMU3 = ROOT / "fmu" / "BreathingTorso3.fmu"
HEADERS = pathlib.Path(fmpy.__file__).parent / "c-code"
HARNESS = ROOT / "tests" / "c" / "fmi_run.c"
HARNESS3 = ROOT / "tests" / "c" / "fmi3_run.c"
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


def unpack_with_win64(fmu, dll_entry, tmp_path):
    """Unpacks `fmu` into tmp_path/fmu, skipping (saying why) without a win64 binary or a tool."""
    assert fmu.is_file(), f"{fmu} missing: build it with `bash scripts/deploy.sh` (scripts/test.sh does)"
    with zipfile.ZipFile(fmu) as z:
        if dll_entry not in z.namelist():
            pytest.skip(f"skipped: {fmu.relative_to(ROOT)} has no win64 binary (scripts/deploy.sh printed why)")
        z.extractall(tmp_path / "fmu")
    for tool in ["gcc", "x86_64-w64-mingw32-gcc", "wine"]:
        if shutil.which(tool) is None:
            pytest.skip(f"skipped: {tool} is not installed (as root, scripts/test.sh installs gcc-mingw-w64-x86-64 and wine)")


def build_harness(source, tmp_path):
    """The harness built with gcc (tmp_path/NAME) and mingw-w64 (tmp_path/win/NAME.exe, with
    the bcryptprimitives stand-in beside it when Wine lacks the DLL)."""
    name = source.stem
    linux_exe = tmp_path / name
    run(["gcc", "-std=c11", "-O1", "-Wall", "-Wextra", "-Werror", f"-I{HEADERS}", str(source), "-o", str(linux_exe), "-ldl"])
    win_dir = tmp_path / "win"
    win_dir.mkdir(exist_ok=True)
    win_exe = win_dir / f"{name}.exe"
    run(["x86_64-w64-mingw32-gcc", "-std=c11", "-O1", "-Wall", "-Wextra", "-Werror", f"-I{HEADERS}", str(source),
         "-o", str(win_exe), "-static"])
    if not wine_has_bcryptprimitives():
        run(["x86_64-w64-mingw32-gcc", "-std=c11", "-O1", "-Wall", "-Wextra", "-Werror", "-shared", str(SHIM),
             "-o", str(win_dir / "bcryptprimitives.dll"), "-ladvapi32"])
    return linux_exe, win_exe


def wine_path(path):
    return "Z:" + str(path).replace("/", "\\")


def wine(cmd, tmp_path):
    env = dict(os.environ, WINEPREFIX=str(tmp_path / "wineprefix"), WINEDEBUG="-all",
               WINEDLLOVERRIDES="mscoree,mshtml=")
    return run(["wine", *cmd], env=env)


def drive_args(md):
    """The drive and input both runs are given, as VR=VALUE."""
    vr = {v.name: v.valueReference for v in md.modelVariables}
    return vr["volume.lung"], [f"{vr['drive.ribs.amplitude']}=0.12", f"{vr['drive.diaphragm.amplitude']}=0.3",
                               f"{vr['drive.diaphragm.phase']}=0.1", f"{vr['activation.external_obliques']}=0.05"]


def compare(linux, windows, label):
    assert [k for k, _ in windows] == [k for k, _ in linux] == list(range(1, STEPS + 1))
    lung = [v for _, v in linux]
    assert max(lung) - min(lung) > 0.2, "the torso breathes: the comparison covers a breath"
    worst = max(abs(w - l) / abs(l) for (_, w), (_, l) in zip(windows, linux))
    print(f"{label}: win64 under wine against linux64: largest relative difference of volume.lung {worst:.3g}")
    assert worst <= RELATIVE_TOLERANCE


def test_win64_dll_under_wine_matches_linux64(tmp_path):
    unpack_with_win64(FMU, "binaries/win64/BreathingTorso.dll", tmp_path)
    md = read_model_description(str(FMU))
    output, inputs = drive_args(md)
    args = [md.guid, str(STEPS), repr(H), str(output), *inputs]
    linux_exe, win_exe = build_harness(HARNESS, tmp_path)
    linux = volumes(run([str(linux_exe), str(tmp_path / "fmu/binaries/linux64/BreathingTorso.so"), *args]))
    windows = volumes(wine([str(win_exe), wine_path(tmp_path / "fmu/binaries/win64/BreathingTorso.dll"), *args], tmp_path))
    compare(linux, windows, "FMI 2.0")


def test_fmi3_win64_dll_under_wine_matches_linux64(tmp_path):
    unpack_with_win64(FMU3, "binaries/x86_64-windows/BreathingTorso.dll", tmp_path)
    md = read_model_description(str(FMU3))
    assert md.fmiVersion == "3.0"
    output, inputs = drive_args(md)
    resources = tmp_path / "fmu" / "resources"
    resources.mkdir(exist_ok=True)
    linux_exe, win_exe = build_harness(HARNESS3, tmp_path)
    tail = [str(STEPS), repr(H), str(output), *inputs]
    linux = volumes(run([str(linux_exe), str(tmp_path / "fmu/binaries/x86_64-linux/BreathingTorso.so"),
                         md.guid, str(resources) + "/", *tail]))
    windows = volumes(wine([str(win_exe), wine_path(tmp_path / "fmu/binaries/x86_64-windows/BreathingTorso.dll"),
                            md.guid, wine_path(resources) + "\\", *tail], tmp_path))
    compare(linux, windows, "FMI 3.0")
