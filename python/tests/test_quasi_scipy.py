"""The quasi-static mode's reduced right-hand side from Python: scipy's DOP853 (an independent
integrator, of another order and step control) integrating `bt_quasi_rate` reproduces the lung
volume of the library's own Dormand-Prince 5(4) run (`bt_advance_to`) over 4 s of quiet
breathing at level of detail 0, both at rtol 1e-9, atol 1e-11 (the handle's rtol also sets the
static solves' tolerance, 1e-11 m, on both sides).

The bound comes from the tolerances. The reduced equation dV/dt = (P_ao - P_alv(V, t)) / R_aw
contracts: the alveolar pressure rises with the volume (checked at every factorisation of the
static solver, `dynamics::statics`), so the difference of two solutions from the same start never
grows, and each integrator's global error is at most the sum of its local errors, each held by
the error control below rtol |V| + atol (Hairer, Norsett & Wanner, eq. II.4.11; scipy's
`solve_ivp` uses the same scale). Reading at the frames from the continuous extensions adds at
most one more local error per side. So the two runs agree within

    (N_ours + N_scipy + 2) (rtol max |V| + atol),

N the steps of each (ours from `bt_advance_to`'s statistics; scipy's at most nfev / 12, DOP853's
twelve evaluations per step, rejected steps included). With some 500 steps in all this is about
2e-6 L, where a rate evaluated 1 ms off in time would already be 2e-4 L off (the flow reaches
0.2 L/s), so a right-hand side that is not the library's own fails. The static solves, converged
to 1e-2 rtol in metres, add an error the tolerance study in `model/torso/quasi.rs` found below
the integration error (the lung-volume error at rtol 1e-6 and 1e-8 unchanged between 1e-3 and
1e-2 rtol).

The cdylib is built by scripts/test.sh (`cargo build --release`) before pytest runs.
"""

import ctypes
import pathlib
import sys
import time

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "python"))

import bench_scipy  # noqa: E402

RTOL, ATOL = 1e-9, 1e-11
SCENE = {"scene.level_of_detail": 0, "drive.frequency": 0.25, "drive.ribs.amplitude": 0.2,
         "drive.diaphragm.amplitude": 0.25, "drive.diaphragm.phase": 0.1,
         "solver.rtol": RTOL, "solver.atol": ATOL}
FRAMES = 224  # 4 s at 56 Hz
DOP853_STAGES = 12


class Stats(ctypes.Structure):
    """`BtAdvanceStats`."""
    _fields_ = [("steps", ctypes.c_uint64), ("rejected", ctypes.c_uint64), ("rhs_evaluations", ctypes.c_uint64)]


@pytest.fixture(scope="module")
def lib():
    path = bench_scipy.LIB
    assert path.is_file(), f"{path} missing: build it with `cargo build --release` (scripts/test.sh does)"
    return bench_scipy.load_library(path)


def native(lib, t_eval):
    """Lung volume per frame and accepted steps of the library's own quasi-static run."""
    torso = bench_scipy.QuasiTorso(lib, SCENE)
    try:
        out, steps, v, stats = [], 0, ctypes.c_double(), Stats()
        for t in t_eval:
            if t > 0:
                rc = lib.bt_advance_to(torso.h, t, ctypes.byref(stats))
                assert rc == 0, lib.bt_last_error(torso.h)
                steps += stats.steps
            assert lib.bt_read_by_name(torso.h, b"volume.lung", ctypes.byref(v)) == 0
            out.append(v.value)
        return np.array(out), steps
    finally:
        torso.close()


def test_scipy_dop853_on_the_reduced_rhs_matches_the_native_integrator(lib):
    t_eval = np.arange(FRAMES + 1) / 56.0
    torso = bench_scipy.QuasiTorso(lib, SCENE)
    try:
        start = time.perf_counter()
        wall, calls, sol = bench_scipy.run_scipy(torso, "DOP853", RTOL, t_eval, cap=60.0)
        assert sol.status == 0, sol.message
        assert calls == sol.nfev > 0  # every evaluation went through bt_quasi_rate
        assert torso.failures == 0
        scipy_lung = sol.y[0]
        print(f"\nscipy DOP853 on bt_quasi_rate, 4 s, LOD 0, rtol {RTOL:g}: nfev {sol.nfev}, {wall:.3f} s")
    finally:
        torso.close()
    ours, steps = native(lib, t_eval)
    print(f"library quasi-static run: {steps} steps, {time.perf_counter() - start:.2f} s for both")
    assert np.ptp(ours) > 0.1, "the drive moves the lung volume"
    scipy_steps = sol.nfev / DOP853_STAGES
    bound = (steps + scipy_steps + 2) * (RTOL * np.max(np.abs(ours)) + ATOL)
    diff = np.max(np.abs(scipy_lung - ours))
    print(f"max |V(scipy) - V(library)| = {diff:.2e} L over {FRAMES + 1} frames; bound {bound:.2e} L")
    assert diff <= bound


def test_the_reduced_rhs_rejects_bad_arguments_and_other_modes(lib):
    torso = bench_scipy.QuasiTorso(lib, SCENE)
    inertial = bench_scipy.Torso(lib, {k: v for k, v in SCENE.items() if not k.startswith("solver.")})
    try:
        rate = ctypes.c_double()
        assert lib.bt_quasi_rate(torso.h, 0.0, -1.0, ctypes.byref(rate)) == -2  # BT_ERR_INVALID
        assert b"lung volume" in lib.bt_last_error(torso.h)
        assert lib.bt_quasi_rate(inertial.h, 0.0, 3.0, ctypes.byref(rate)) == -6  # BT_ERR_STATE
        assert b"quasi-static" in lib.bt_last_error(inertial.h)
    finally:
        torso.close()
        inertial.close()
