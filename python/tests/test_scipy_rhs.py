"""The C ABI right-hand side from Python: scipy's RK45 integrating `bt_rhs` reproduces the lung
volume of the library's own integrator (`bt_advance_to`), so an external integrator sees the
same model, drive included.

Scene: default subject, level of detail 0 (631 states, to keep the test short), quiet breathing
drive, 0.5 s from rest, read at the 56 Hz frames. Both sides run at rtol 1e-8, atol 1e-10; at
these tolerances each is within about 1e-8 L of a DOP853 rtol 1e-12 reference
(`torso bench work-precision`: Dormand-Prince 5(4) at rtol 1e-8 gives 1.0e-8 L over 1 s at this
level of detail, scipy RK45 at 1e-7 gives 6e-8 L over 0.5 s), so they must agree within 1e-6 L,
a margin of ~20x for round-off and different step sequences. 1e-6 L is 2e-6 of the lung volume
and far below what the drive moves in 0.5 s (checked to exceed 1e-3 L), so a right-hand side
that ignored the drive, or evaluated it at another time, fails.

The cdylib is built by scripts/test.sh (`cargo build --release`) before pytest runs.
"""

import ctypes
import pathlib
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "python"))

import bench_scipy  # noqa: E402

QUIET = {"scene.level_of_detail": 0, "drive.frequency": 0.25, "drive.ribs.amplitude": 0.2,
         "drive.diaphragm.amplitude": 0.25, "drive.diaphragm.phase": 0.1}
RTOL, ATOL = 1e-8, 1e-10
FRAMES = 28  # 0.5 s at 56 Hz


@pytest.fixture(scope="module")
def lib():
    path = bench_scipy.LIB
    assert path.is_file(), f"{path} missing: build it with `cargo build --release` (scripts/test.sh does)"
    return bench_scipy.load_library(path)


def native_lung(lib, t_eval):
    """Lung volume per frame from the library's own integrator at the same tolerances."""
    torso = bench_scipy.Torso(lib, {**QUIET, "solver.rtol": RTOL, "solver.atol": ATOL})
    try:
        out, v = [], ctypes.c_double()
        for t in t_eval:
            if t > 0:
                assert lib.bt_advance_to(torso.h, t, None) == 0, lib.bt_last_error(torso.h)
            assert lib.bt_read_by_name(torso.h, b"volume.lung", ctypes.byref(v)) == 0
            out.append(v.value)
        return np.array(out)
    finally:
        torso.close()


def test_scipy_rk45_on_the_c_abi_rhs_matches_the_native_integrator(lib):
    t_eval = np.arange(FRAMES + 1) / 56.0
    torso = bench_scipy.Torso(lib, QUIET)
    try:
        wall, calls, sol = bench_scipy.run_scipy(torso, "RK45", RTOL, t_eval, cap=60.0)
        assert sol.status == 0, sol.message
        # ours, not scipy's bookkeeping: every evaluation went through bt_rhs
        assert calls == sol.nfev > 0
        print(f"\nscipy RK45 on bt_rhs, 0.5 s, LOD 0, rtol {RTOL:g}: nfev {sol.nfev}, {wall:.3f} s")
        scipy_lung = np.array([torso.read_frame(t, sol.y[:, i])[0] for i, t in enumerate(t_eval)])
    finally:
        torso.close()
    native = native_lung(lib, t_eval)
    assert np.ptp(native) > 1e-3, "the drive moves the lung volume"
    diff = np.max(np.abs(scipy_lung - native))
    print(f"max |lung(scipy) - lung(native)| = {diff:.2e} L over {FRAMES + 1} frames")
    assert diff < 1e-6


def test_rhs_and_set_state_reject_bad_arguments(lib):
    torso = bench_scipy.Torso(lib, QUIET)
    try:
        y = torso.y0.copy()
        out = np.empty(torso.n)
        assert lib.bt_rhs(torso.h, 0.0, y.ctypes.data, out.ctypes.data, torso.n - 1) != 0
        assert b"state length" in lib.bt_last_error(torso.h)
        assert lib.bt_rhs(torso.h, float("nan"), y.ctypes.data, out.ctypes.data, torso.n) != 0
        y[3] = float("inf")
        assert lib.bt_set_state(torso.h, 0.0, y.ctypes.data, torso.n) != 0
        assert b"state[3]" in lib.bt_last_error(torso.h)
        # a rejected state changes nothing: the rest state is still there
        assert np.array_equal(torso.state(), torso.y0)
    finally:
        torso.close()


def _header_fields(struct):
    """The member names of `typedef struct <struct> { ... }` in include/breathing_torso.h, in
    order (comments dropped; arrays by their name)."""
    import re

    text = (ROOT / "include" / "breathing_torso.h").read_text()
    body = re.search(r"typedef struct %s \{(.*?)\} %s;" % (struct, struct), text, re.S).group(1)
    body = re.sub(r"/\*.*?\*/", "", body, flags=re.S)
    return [re.search(r"(\w+)\s*(\[\d+\])?\s*;", line).group(1)
            for line in body.splitlines() if line.strip().endswith(";")]


@pytest.mark.parametrize("cls,struct", [(bench_scipy.Config, "BtConfig"),
                                        (bench_scipy.Drive, "BtDrive"),
                                        (bench_scipy.Subject, "BtSubject"),
                                        (bench_scipy.Wave, "BtWave")])
def test_the_ctypes_structures_follow_the_header(cls, struct):
    """bench_scipy's ctypes mirrors of the C ABI's structures name the header's members in the
    header's order: `bt_config_default` writes the whole `BtConfig`, so a mirror short of a
    member is written past its end."""
    assert [name for name, _ in cls._fields_] == _header_fields(struct)
