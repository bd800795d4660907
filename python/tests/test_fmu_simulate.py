"""BreathingTorso.fmu simulated through fmpy: drive parameters and input arrays, bit-identical
replay from FMU states (in memory and serialised), reset, communication step sizes from
1e-4 s to 1 s, and eight instances on eight threads.
"""

import math
import os
import shutil
from pathlib import Path
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException

from test_fmu_calls import Host, fmu_path

QUIET = {"drive.ribs.amplitude": 0.2, "drive.diaphragm.amplitude": 0.25, "drive.diaphragm.phase": 0.1}
VOLUMES = ["volume.lung", "volume.thorax", "volume.abdomen", "volume.trunk", "pressure.abdomen"]


def run(host, f, t0, t1, h, names=("volume.lung",)):
    """Steps from t0 to t1 with step h (t = t0 + k h, as a master computes it); returns the
    outputs after every step."""
    vrs = [host.vr[n] for n in names]
    n = int(round((t1 - t0) / h))
    out = []
    for k in range(n):
        t = t0 + k * h
        f.doStep(currentCommunicationPoint=t, communicationStepSize=t0 + (k + 1) * h - t)
        out.append(f.getReal(vrs))
    return out


def native_lung(parameters, times):
    """volume.lung at `times` from the same library through the C ABI (bt_advance_to, no FMI
    layer), with the FMU's start values (bt_config_default) and `parameters` set by name."""
    import ctypes
    import sys
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    import bench_scipy

    lib = bench_scipy.load_library(bench_scipy.LIB)
    torso = bench_scipy.Torso(lib, parameters)
    try:
        out, v = [], ctypes.c_double()
        for t in times:
            if t > 0:
                assert lib.bt_advance_to(torso.h, t, None) == 0, lib.bt_last_error(torso.h)
            assert lib.bt_read_by_name(torso.h, b"volume.lung", ctypes.byref(v)) == 0
            out.append(v.value)
        return np.array(out)
    finally:
        torso.close()


def test_simulate_with_drive_parameters():
    r = simulate_fmu(fmu_path(), stop_time=8.0, output_interval=0.02, start_values=QUIET,
                     output=VOLUMES + ["solver.steps", "solver.rhs_evaluations"])
    assert r["time"][-1] == pytest.approx(8.0)
    for n in VOLUMES:
        assert np.all(np.isfinite(r[n])), n
    # The FMU computes what the library computes natively for the same drive and frames
    # (the same integrator stepping to the same communication points).
    native = native_lung(QUIET, r["time"])
    diff = np.max(np.abs(r["volume.lung"] - native))
    assert diff < 1e-9, f"FMU and C ABI differ by {diff} L"
    # ... and the thesis-range quiet drive breathes within the quiet target of the README's
    # table (0.35-0.8 L; a drive that did not reach the muscles would swing 4e-8 L).
    tidal = np.ptp(r["volume.lung"])
    assert 0.35 < tidal < 0.8, f"tidal volume {tidal} L"
    assert r["solver.steps"][-1] > 0 and r["solver.rhs_evaluations"][-1] > r["solver.steps"][-1]


def test_simulate_with_input_arrays():
    t = np.linspace(0.0, 8.0, 401)
    a = 0.15 * (1.0 - np.cos(2.0 * math.pi * 0.25 * t))
    signals = np.array(list(zip(t, a, 0.5 * a)),
                       dtype=[("time", np.float64), ("activation.diaphragm", np.float64),
                              ("activation.external_intercostals", np.float64)])
    off = {"drive.enabled": False}  # the inputs alone drive the muscles
    driven = simulate_fmu(fmu_path(), stop_time=8.0, output_interval=0.02, input=signals, start_values=off,
                          output=["volume.lung"])
    rest = simulate_fmu(fmu_path(), stop_time=8.0, output_interval=0.02, start_values=off, output=["volume.lung"])
    assert np.all(np.isfinite(driven["volume.lung"]))
    # With the drive off and no input the model stays at rest.
    assert np.ptp(rest["volume.lung"]) < 1e-6, np.ptp(rest["volume.lung"])
    # Inspiratory activation raises the lung volume above the resting run.
    assert (driven["volume.lung"] - rest["volume.lung"]).max() > 0.02


def test_default_fmu_breathes_the_quiet_scenario():
    from fmpy import read_model_description
    md = read_model_description(fmu_path())
    start = {v.name: v.start for v in md.modelVariables}
    # Drive::quiet (src/model/drive.rs): 0.25 Hz, ribs 0.096, diaphragm 0.24 0.1 rad ahead.
    assert start["drive.enabled"] == "true"
    assert [float(start[n]) for n in ["drive.frequency", "drive.ribs.amplitude", "drive.diaphragm.amplitude",
                                      "drive.diaphragm.phase", "drive.abdominals.amplitude"]] == [
        0.25, 0.096, 0.24, 0.1, 0.0]
    r = simulate_fmu(fmu_path(), stop_time=20.0, output_interval=1 / 56, output=["volume.lung"])
    # The quiet breath of the README's table (0.542 L, tests/physiology.rs), here over five
    # breaths from rest.
    assert abs(np.ptp(r["volume.lung"]) - 0.542) < 0.01, np.ptp(r["volume.lung"])


def test_quasi_static_method_breathes_as_the_inertial_one():
    # solver.method 4: the chest wall in equilibrium at every instant, the lung volume the only
    # state (docs/dynamics.md). Same laws without inertia and dampers: the tidal volume within
    # 1 % of the inertial formulation's (the bound of the mechanics issue, 34), and a restored
    # FMU state replays bit for bit.
    swings = []
    for method in (0, 4):
        r = simulate_fmu(fmu_path(), stop_time=12.0, output_interval=1 / 56,
                         start_values={"solver.method": method}, output=["volume.lung"])
        late = r["volume.lung"][r["time"] > 4.0]
        swings.append(float(np.ptp(late)))
    assert abs(swings[1] / swings[0] - 1) < 0.01, swings
    h = Host()
    try:
        f = h.initialize({**QUIET, "solver.method": 4})
        run(h, f, 0.0, 1.0, 0.05)
        state = f.getFMUstate()
        first = run(h, f, 1.0, 2.0, 0.05, VOLUMES)
        f.setFMUstate(state)
        assert run(h, f, 1.0, 2.0, 0.05, VOLUMES) == first
        f.freeFMUstate(state)
    finally:
        h.close()


def test_drive_enabled_switches_the_drive_between_steps():
    h = Host()
    try:
        f = h.initialize({"scene.level_of_detail": 0})
        vr = h.vr["drive.enabled"]
        assert f.getBoolean([vr]) == [True]
        lung = [v[0] for v in run(h, f, 0.0, 2.0, 0.1)]
        driven = np.ptp(lung)
        assert driven > 0.1, driven
        f.setBoolean([vr], [False])
        assert f.getBoolean([vr]) == [False]
        # Off: no activation, so no breath: over the last 2 s of 10 s off the lungs move by
        # less than a thousandth of the driven half-breath (the passive return to rest has a
        # slow tail of about 2e-5 L there, docs/dynamics.md).
        lung = [v[0] for v in run(h, f, 2.0, 12.0, 0.1)]
        assert np.ptp(lung[-20:]) < 1e-3 * driven, np.ptp(lung[-20:])
        f.setBoolean([vr], [True])
        lung = [v[0] for v in run(h, f, 12.0, 14.0, 0.1)]
        assert np.ptp(lung) > 0.1
    finally:
        h.close()


def test_fmu_state_replay_is_bit_identical():
    h = Host()
    try:
        f = h.initialize(QUIET)
        run(h, f, 0.0, 2.0, 0.02)
        state = f.getFMUstate()
        data = f.serializeFMUstate(state)
        first = run(h, f, 2.0, 4.0, 0.02, VOLUMES)
        f.setFMUstate(state)
        assert run(h, f, 2.0, 4.0, 0.02, VOLUMES) == first
        # A serialised state restores into another instance too.
        g_host = Host()
        try:
            g = g_host.initialize(QUIET)
            g.setFMUstate(g.deSerializeFMUstate(data))
            assert run(g_host, g, 2.0, 4.0, 0.02, VOLUMES) == first
        finally:
            g_host.close()
        f.freeFMUstate(state)
    finally:
        h.close()


def test_reset_then_rerun_is_identical():
    h = Host()
    try:
        f = h.initialize(QUIET)
        first = run(h, f, 0.0, 3.0, 0.05, VOLUMES)
        f.reset()
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        for name, value in QUIET.items():
            f.setReal([h.vr[name]], [value])
        f.exitInitializationMode()
        assert run(h, f, 0.0, 3.0, 0.05, VOLUMES) == first
    finally:
        h.close()


@pytest.mark.parametrize("step", [1e-4, 1e-3, 1e-2, 0.1, 1.0])
def test_communication_step_sizes_agree_with_one_long_run(step):
    end = 1.0
    results = []
    for h_comm in [end, step]:
        h = Host()
        try:
            f = h.initialize(QUIET)
            results.append(run(h, f, 0.0, end, h_comm, VOLUMES)[-1])
        finally:
            h.close()
    long_run, stepped = np.array(results[0]), np.array(results[1])
    # Inputs are constant and the drive is evaluated inside, so only integration error differs.
    assert np.allclose(stepped, long_run, rtol=1e-4, atol=1e-6), (step, stepped, long_run)


def test_eight_threads_give_the_sequential_results():
    from fmpy.fmi2 import FMU2Slave

    shared = Host()  # one extracted FMU: every instance runs in the same loaded library
    # fmpy loads the library with a process-wide chdir into the binaries folder and back, so
    # the wrappers are made on this thread; only the instances run concurrently.
    slaves = [FMU2Slave(guid=shared.md.guid, unzipDirectory=shared.dir, modelIdentifier="BreathingTorso",
                        instanceName=f"torso{i}") for i in range(16)]

    def job(i):
        f = slaves[i]
        f.instantiate(callbacks=shared.callbacks)
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        f.setReal([shared.vr["drive.ribs.amplitude"], shared.vr["drive.diaphragm.amplitude"]],
                  [0.05 + 0.05 * (i % 8), 0.3])
        f.exitInitializationMode()
        out = []
        for k in range(100):
            f.doStep(currentCommunicationPoint=k * 0.02, communicationStepSize=0.02)
            out.append(f.getReal([shared.vr["volume.lung"], shared.vr["volume.abdomen"]]))
        f.terminate()
        f.fmi2FreeInstance(f.component)
        return out

    cwd = os.getcwd()
    try:
        sequential = [job(i) for i in range(8)]
        with ThreadPoolExecutor(max_workers=8) as pool:
            parallel = list(pool.map(job, range(8, 16)))
        assert parallel == sequential
        assert sequential[0] != sequential[7]
        assert os.getcwd() == cwd
    finally:
        shutil.rmtree(shared.dir, ignore_errors=True)


def test_wrong_current_time_after_steps_fails():
    h = Host()
    try:
        f = h.initialize(QUIET)
        run(h, f, 0.0, 0.1, 0.02)
        with pytest.raises(FMICallException):
            f.doStep(currentCommunicationPoint=0.2, communicationStepSize=0.02)
        assert "currentCommunicationPoint" in h.last_error()
        run(h, f, 0.1, 0.2, 0.02)
    finally:
        h.close()


def _volume_ti_ttot(t, v, period, start):
    """Ti/Ttot of the lung volume over the breath that starts after `start`: time from its
    minimum to its maximum over the time to the next minimum."""
    m = (t >= start) & (t < start + period)
    t_min = t[m][np.argmin(v[m])]
    m = (t >= t_min) & (t < t_min + period)
    t_max = t[m][np.argmax(v[m])]
    m = (t > t_max) & (t < t_max + period)
    t_next = t[m][np.argmin(v[m])]
    return (t_max - t_min) / (t_next - t_min)


def test_inspiratory_fraction_parameter_shapes_the_breath():
    """drive.inspiratory_fraction (Ti/Ttot of the drive) reaches the model through fmpy: the
    lung volume's own Ti/Ttot follows it (measured 0.4975 at 0.5 and 0.4050 at 0.4 with
    `torso simulate --lod 0 --rate 200`: the volume lags the activation by 0-55 ms), the
    range is enforced, and 0.5 is the start value (the sine of eq. 2.4)."""
    period = 4.0  # quiet drive, 0.25 Hz
    fractions = {}
    for fraction in (0.5, 0.4):
        r = simulate_fmu(fmu_path(), stop_time=3 * period, output_interval=0.005,
                         start_values={"scene.level_of_detail": 0, "drive.inspiratory_fraction": fraction},
                         output=["volume.lung"])
        fractions[fraction] = _volume_ti_ttot(r["time"], r["volume.lung"], period, period + 0.5)
    assert abs(fractions[0.5] - 0.5) < 0.02, fractions
    assert abs(fractions[0.4] - 0.4) < 0.02, fractions
    with pytest.raises(Exception):
        simulate_fmu(fmu_path(), stop_time=1.0, start_values={"drive.inspiratory_fraction": 0.9})
    names = {v.name: v for v in read_model_description(fmu_path()).modelVariables}
    v = names["drive.inspiratory_fraction"]
    assert (float(v.start), float(v.min), float(v.max), v.variability) == (0.5, 0.2, 0.8, "tunable")
