"""Benchmark: fmpy `simulate_fmu` of 1000 frames at 56 Hz (quiet breathing, four volumes and,
when the model has a skin, the 60 markers of the default 10 x 6 grid recorded) against the same
scene run natively through the C ABI (`bt_advance_to` + `bt_read`, same library, no FMI layer).
Prints the median wall time of each and their ratio.

    cargo build --release && target/release/torso fmu build
    .venv/bin/python python/bench_fmu.py [repeats]
"""

import ctypes
import pathlib
import statistics
import sys
import time

from fmpy import simulate_fmu

ROOT = pathlib.Path(__file__).resolve().parents[1]
FMU = str(ROOT / "fmu" / "BreathingTorso.fmu")
LIB = str(ROOT / "target" / "release" / "libbreathing_torso.so")
FRAMES, RATE = 1000, 56.0
DRIVE = {"drive.ribs.amplitude": 0.2, "drive.diaphragm.amplitude": 0.25, "drive.diaphragm.phase": 0.1}
VOLUMES = ["volume.lung", "volume.thorax", "volume.abdomen", "volume.trunk"]
MARKERS = [f"marker[{i}].{a}" for i in range(1, 61) for a in "xyz"]


sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from bench_scipy import Config  # noqa: E402  (`BtConfig` of include/breathing_torso.h)


def markers_available(lib):
    c = Config()
    lib.bt_config_default(ctypes.byref(c))
    h = ctypes.c_void_p(lib.bt_create(ctypes.byref(c)))
    xyz = (ctypes.c_double * 180)()
    ok = lib.bt_read_markers(h, xyz, 180, None) == 0
    lib.bt_destroy(h)
    return ok


def run_fmu(outputs):
    t = time.perf_counter()
    simulate_fmu(FMU, stop_time=FRAMES / RATE, output_interval=1 / RATE, start_values=DRIVE, output=outputs)
    return time.perf_counter() - t


def run_native(lib, with_markers):
    c = Config()
    lib.bt_config_default(ctypes.byref(c))
    c.drive.ribs.amplitude, c.drive.diaphragm.amplitude, c.drive.diaphragm.phase = 0.2, 0.25, 0.1
    t = time.perf_counter()
    h = ctypes.c_void_p(lib.bt_create(ctypes.byref(c)))
    v = ctypes.c_double()
    xyz = (ctypes.c_double * 180)()
    for k in range(1, FRAMES + 1):
        if lib.bt_advance_to(h, ctypes.c_double(k / RATE), None) != 0:
            raise RuntimeError(lib.bt_last_error(h))
        for vr in (1000, 1001, 1002, 1003):
            lib.bt_read(h, ctypes.c_uint(vr), ctypes.byref(v))
        if with_markers:
            lib.bt_read_markers(h, xyz, 180, None)
    dt = time.perf_counter() - t
    lib.bt_destroy(h)
    return dt


def main():
    repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    lib = ctypes.CDLL(LIB)
    lib.bt_create.restype = ctypes.c_void_p
    lib.bt_last_error.restype = ctypes.c_char_p
    with_markers = markers_available(lib)
    outputs = VOLUMES + (MARKERS if with_markers else [])
    fmu = statistics.median(run_fmu(outputs) for _ in range(repeats))
    native = statistics.median(run_native(lib, with_markers) for _ in range(repeats))
    what = "4 volumes + 60 markers" if with_markers else "4 volumes (no skin in this build: markers skipped)"
    print(f"{FRAMES} frames at {RATE:g} Hz, {what}, median of {repeats}")
    print(f"  fmpy simulate_fmu : {fmu:.3f} s")
    print(f"  native C ABI      : {native:.3f} s")
    print(f"  ratio fmu/native  : {fmu / native:.2f}")


if __name__ == "__main__":
    main()
