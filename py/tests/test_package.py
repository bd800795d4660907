"""The installed package against the command-line tool built from the same source: every
function of breathing_torso, its errors, and the FMUs it ships (through fmpy).

The package is a binding of the library `torso` is built from, so where both do the same
thing the results must be identical, not close: the simulation's arrays equal the CSV `torso
simulate` writes (Rust prints the shortest decimal that reads back as the same double), a
recording written by the package is the file `torso convert` writes, a fit's drive and cost
are those `torso fit` writes, a validation's statistics those of `torso validate`, and the
shipped FMU run by fmpy gives the same volumes as `Torso.simulate`.
"""

import csv
import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import breathing_torso as bt
from conftest import run_cli

SOURCE_TREE = Path(os.environ.get("BT_SOURCE", "/nonexistent"))


def read_csv(path):
    """A numeric CSV as arrays by column (float() reads Rust's shortest round-trip text
    back to the same double)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    return {h: np.array([float(r[k]) for r in body]) for k, h in enumerate(header)}


def test_the_package_is_the_installed_one():
    """Imported from the venv's site-packages, not from the source tree."""
    here = Path(bt.__file__).resolve()
    assert "site-packages" in here.parts, here
    if SOURCE_TREE.exists():
        assert SOURCE_TREE.resolve() not in here.parents, here
    assert bt.__version__ == "0.1.0"


@pytest.mark.parametrize(
    "options, flags",
    [
        ({"lod": 0}, ["--lod", "0"]),
        (
            {"lod": 0, "posture": "supine", "subject": {"sex": "female", "stature": 1.62, "mass": 58},
             "solver": "rosenbrock", "scenario": "forced", "drive": {"frequency": 0.3}},
            ["--lod", "0", "--posture", "supine", "--sex", "female", "--stature", "1.62",
             "--mass", "58", "--solver", "rosenbrock", "--scenario", "forced", "--frequency", "0.3"],
        ),
        (
            {"lod": 0, "muscle_law": "hill"},
            ["--lod", "0", "--muscle-law", "hill"],
        ),
        (
            {"lod": 0, "posture": "supine", "gravity": 4.9, "gravity_loads": "acting"},
            ["--lod", "0", "--posture", "supine", "--gravity", "4.9", "--gravity-loads", "acting"],
        ),
        (
            {"lod": 0, "muscle_law": "hill", "postural_tone": False},
            ["--lod", "0", "--muscle-law", "hill", "--postural-tone", "off"],
        ),
    ],
    ids=["default", "female-supine-rosenbrock-forced", "hill-law", "gravity-acting", "hill-no-tone"],
)
def test_simulate_is_torso_simulate(torso_cli, tmp_path, options, flags):
    """Torso(...).simulate returns exactly the columns and values `torso simulate` writes."""
    out = tmp_path / "sim.csv"
    run_cli(torso_cli, "simulate", *flags, "--duration", "3", "--rate", "56", "--out", out)
    cli = read_csv(out)
    ours = bt.Torso(**options).simulate(3.0, as_frame=False)
    assert list(ours) == list(cli) == bt.Torso.outputs()
    for name in cli:
        assert np.array_equal(ours[name], cli[name]), name


def test_simulate_outputs_frames_and_continuation():
    """`outputs` selects columns (time always first), the frame count is round(d r) + 1, and
    a second call continues from the first's end (a 2 s run equals two 1 s runs)."""
    a = bt.Torso(lod=0)
    d = a.simulate(1.0, outputs=["volume.lung", "pressure.abdomen"], rate=10, as_frame=False)
    assert list(d) == ["time", "volume.lung", "pressure.abdomen"]
    assert len(d["time"]) == 11 and d["time"][0] == 0.0 and math.isclose(d["time"][-1], 1.0)
    assert a.time == pytest.approx(1.0)
    e = a.simulate(1.0, outputs=["volume.lung"], rate=10, as_frame=False)
    whole = bt.Torso(lod=0).simulate(2.0, outputs=["volume.lung"], rate=10, as_frame=False)
    assert np.array_equal(np.concatenate([d["volume.lung"], e["volume.lung"][1:]]), whole["volume.lung"])
    with pytest.raises(ValueError, match="unknown 'volume.lungs'"):
        a.simulate(1.0, outputs=["volume.lungs"])


def test_simulate_returns_a_dataframe_with_pandas():
    pd = pytest.importorskip("pandas")
    df = bt.Torso(lod=0).simulate(0.5, outputs=["volume.lung"])
    assert isinstance(df, pd.DataFrame)
    assert list(df.columns) == ["time", "volume.lung"] and len(df) == 29


def test_activations_add_to_the_drive():
    """An input is added to the drive and clamped to [0, 1] (applied = clamp(input + drive)):
    held values and one value per output interval, against a run without inputs."""
    n = 20
    plain = bt.Torso(lod=0).simulate(1.0, rate=n, as_frame=False)
    ramp = np.linspace(0.0, 0.3, n)
    driven = bt.Torso(lod=0).simulate(
        1.0, rate=n, activations={"scalenes": 0.25, "rectus_abdominis": ramp}, as_frame=False
    )
    assert np.allclose(driven["activation.scalenes"], np.clip(plain["activation.scalenes"] + 0.25, 0, 1), rtol=0, atol=1e-15)
    # frame k > 0 ends interval k - 1, over which ramp[k - 1] was applied; frame 0 shows ramp[0]
    held = np.concatenate([[ramp[0]], ramp])
    expect = np.clip(plain["activation.rectus_abdominis"] + held, 0, 1)
    assert np.allclose(driven["activation.rectus_abdominis"], expect, rtol=0, atol=1e-15)
    # the inputs move the model: the lung volume differs from the plain run's
    assert np.max(np.abs(driven["volume.lung"] - plain["volume.lung"])) > 1e-3
    with pytest.raises(ValueError, match="unknown muscle group `diafragm`"):
        bt.Torso(lod=0).simulate(1.0, activations={"diafragm": 0.1})
    with pytest.raises(ValueError, match="3 values; give one, or one per output interval"):
        bt.Torso(lod=0).simulate(1.0, rate=n, activations={"scalenes": [0.1, 0.2, 0.3]})
    with pytest.raises(ValueError, match=r"1\.5.*\[0, 1\]"):
        bt.Torso(lod=0).simulate(1.0, activations={"scalenes": 1.5})


def test_state_and_set_state():
    """state() has state_dim values; set_state puts a model in another's state and time, so
    that what it reads and how it continues are that model's (its integrator restarts, so
    the continuation agrees within the solver's tolerance rather than bit for bit)."""
    a = bt.Torso(lod=0)
    a.simulate(1.3, as_frame=False)
    y = a.state()
    assert y.shape == (a._native.state_dim(),) and np.all(np.isfinite(y))
    b = bt.Torso(lod=0)
    b.set_state(y, time=a.time)
    assert b.time == a.time and np.array_equal(b.state(), y)
    ra = a.simulate(1.0, outputs=["volume.lung"], as_frame=False)
    rb = b.simulate(1.0, outputs=["volume.lung"], as_frame=False)
    assert np.array_equal(ra["time"], rb["time"])
    assert ra["volume.lung"][0] == rb["volume.lung"][0]
    # rtol 1e-6 per step, about 50 steps a second: within 1e-4 of the volume (0.4 mL of 4 L)
    assert np.allclose(ra["volume.lung"], rb["volume.lung"], rtol=1e-4, atol=0)
    with pytest.raises(ValueError, match="state"):
        b.set_state(y[:-1])
    with pytest.raises(ValueError):
        b.set_state(np.full_like(y, np.nan))


def test_constructor_errors_name_the_parameter_and_range():
    with pytest.raises(ValueError, match=r"-1 for `stature`: allowed range is \[1\.4, 2\.1\]"):
        bt.Torso(subject={"stature": -1})
    with pytest.raises(ValueError, match="posture.*standing, sitting or supine"):
        bt.Torso(posture="hanging")
    with pytest.raises(ValueError, match="unknown key `height`"):
        bt.Torso(subject={"height": 1.8})
    with pytest.raises(ValueError, match="solver"):
        bt.Torso(solver="euler")
    with pytest.raises(ValueError, match="lod|level_of_detail"):
        bt.Torso(lod=7)
    with pytest.raises(ValueError, match="hil for `muscle_law`: allowed range is thesis or hill"):
        bt.Torso(muscle_law="hil")
    with pytest.raises(ValueError, match=r"40 for `gravity`: allowed range is \[0, 29\.43\]"):
        bt.Torso(gravity=40)
    with pytest.raises(ValueError, match="gravity_loads.*preloaded or acting"):
        bt.Torso(gravity_loads="floating")
    # a string is not read by its truth value ("off" would otherwise switch the tone on)
    with pytest.raises(ValueError, match="'off' for `postural_tone`: allowed range is True or False"):
        bt.Torso(postural_tone="off")


def inspect_missing(torso_cli, path):
    """Missing samples per marker as `torso inspect` prints them."""
    out = run_cli(torso_cli, "inspect", path).stdout.splitlines()
    start = out.index("marker\tmissing") + 1
    rows = [l.split("\t") for l in out[start:] if "\t" in l]
    return {k: int(v) for k, v in rows}


def test_read_recording_every_format(torso_cli, data_dir, synth_recording, tmp_path):
    """C3D, TRC, the grid CSV and a CSV of named markers: labels, frames and missing samples
    as `torso inspect` reports them; positions in metres, NaN where a sample is missing."""
    c3d = data_dir / "recordings" / "chest30_lab.c3d"
    trc = tmp_path / "chest.trc"
    named = tmp_path / "chest.csv"
    run_cli(torso_cli, "convert", c3d, trc)
    run_cli(torso_cli, "convert", c3d, named)
    recordings = {p: bt.read_recording(p) for p in (c3d, trc, named, synth_recording)}
    assert [r.format for r in recordings.values()] == ["c3d", "trc", "marker-csv", "grid-csv"]
    for path, r in recordings.items():
        missing = inspect_missing(torso_cli, path)
        assert r.labels == list(missing)
        assert r.positions.shape == (len(r.time), len(r.labels), 3)
        assert [int(n) for n in np.isnan(r.positions[:, :, 0]).sum(axis=0)] == list(missing.values())
    base = recordings[c3d]
    assert base.units == "mm" and base.provenance["made_by"].startswith("torso synth")
    assert base.rate == pytest.approx(30.0)
    # the same markers through every text format, in metres (the text holds 1e-6 mm digits)
    for other in (trc, named):
        assert np.allclose(recordings[other].positions, base.positions, rtol=0, atol=1e-8)
    grid = recordings[synth_recording]
    assert grid.labels[0] == "marker[1]" and grid.provenance["grid"] == "10x6"
    assert np.isnan(grid.positions).any(), "1 % dropout leaves gaps"
    # the torso's markers are metres from the camera: within 5 m
    assert np.nanmax(np.abs(grid.positions)) < 5.0


def test_read_recording_units_rate_and_errors(tmp_path):
    """A CSV of named markers without units or times takes them from the keywords; errors
    name the file and line."""
    p = tmp_path / "bare.csv"
    p.write_text("A.x,A.y,A.z\n1,2,3\n4,5,6\n")
    r = bt.read_recording(p, units="mm", rate=50)
    assert np.array_equal(r.time, [0.0, 0.02]) and np.allclose(r.positions[1, 0], [0.004, 0.005, 0.006])
    with pytest.raises(ValueError, match="units"):
        bt.read_recording(p, units="inch")
    bad = tmp_path / "bad.csv"
    bad.write_text("time,A.x,A.y,A.z\n0,1,2,3\n0.1,1,oops,3\n")
    with pytest.raises(ValueError, match=r"bad\.csv:3:\d+: column 3 `A\.y`: `oops` is not a number"):
        bt.read_recording(bad, units="m")
    with pytest.raises(OSError, match="missing.c3d"):
        bt.read_recording(tmp_path / "missing.c3d")
    with pytest.raises(ValueError, match=r"\.xyz"):
        bt.read_recording(tmp_path / "file.xyz")


@pytest.mark.parametrize("ext", ["c3d", "trc", "csv"])
def test_write_recording_is_torso_convert(torso_cli, data_dir, tmp_path, ext):
    """write_recording of what read_recording read writes the file `torso convert` writes."""
    c3d = data_dir / "recordings" / "chest30_lab.c3d"
    (tmp_path / "cli").mkdir()
    (tmp_path / "py").mkdir()
    run_cli(torso_cli, "convert", c3d, tmp_path / "cli" / f"rec.{ext}")
    bt.write_recording(tmp_path / "py" / f"rec.{ext}", bt.read_recording(c3d))
    assert (tmp_path / "py" / f"rec.{ext}").read_bytes() == (tmp_path / "cli" / f"rec.{ext}").read_bytes()


def test_write_recording_gaps_and_shape(tmp_path):
    """NaN positions are written as missing samples and read back as NaN."""
    t = np.arange(4) / 10.0
    pos = np.random.default_rng(1).normal(size=(4, 2, 3))
    pos[2, 1] = np.nan
    rec = bt.Recording(time=t, labels=["a", "b"], positions=pos, units="m", provenance={"note": "x"})
    bt.write_recording(tmp_path / "r.csv", rec)
    back = bt.read_recording(tmp_path / "r.csv")
    assert back.labels == ["a", "b"] and back.provenance.get("note") == "x"
    assert np.array_equal(np.isnan(back.positions), np.isnan(pos))
    assert np.allclose(back.positions[~np.isnan(pos)], pos[~np.isnan(pos)], rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="expected .frames, markers, 3."):
        bt.write_recording(tmp_path / "r.csv", bt.Recording(time=t, labels=["a"], positions=pos))


FIT_OPTIONS = ["--lod", "0", "--max-evals", "20", "--threads", "1", "--stature", "1.75", "--mass", "75"]
FIT_KEYWORDS = dict(lod=0, max_evals=20, threads=1, subject={"stature": 1.75, "mass": 75})
DRIVE_KEYS = [
    "drive.frequency", "drive.inspiratory_fraction", "drive.ribs.amplitude", "drive.ribs.phase",
    "drive.diaphragm.amplitude", "drive.diaphragm.phase", "drive.abdominals.amplitude",
    "drive.abdominals.phase", "cost_m", "evaluations", "registration",
]


def test_fit_is_torso_fit(torso_cli, synth_recording, tmp_path):
    """fit() writes and returns what `torso fit` writes: the same drive, cost, registration
    and breaths; the per-breath table and the lung volume as tables; the progress callback
    sees every reported evaluation."""
    (tmp_path / "cli").mkdir()
    run_cli(torso_cli, "fit", "--slp", synth_recording, "--out", tmp_path / "cli" / "result.json", *FIT_OPTIONS)
    cli = json.loads((tmp_path / "cli" / "result.json").read_text())
    seen = []
    ours = bt.fit(synth_recording, tmp_path / "py" / "result.json", progress=lambda n, c: seen.append((n, c)),
                  as_frame=False, **FIT_KEYWORDS)
    for key in DRIVE_KEYS:
        assert ours[key] == cli[key], key
    assert ours["cost_basis"] == cli["cost_basis"]
    written = json.loads((tmp_path / "py" / "result.json").read_text())
    assert written["breaths"] == cli["breaths"]
    breaths = ours["breaths"]
    assert np.array_equal(breaths["tidal_volume_l"], [b["tidal_volume_l"] for b in cli["breaths"]])
    lung = read_csv(tmp_path / "cli" / "result_lung_volume.csv")
    assert list(ours["lung_volume"]) == list(lung)
    for k in lung:
        assert np.array_equal(ours["lung_volume"][k], lung[k]), k
    assert seen, "the progress callback was never called"
    counts = [n for n, _ in seen]
    assert counts == sorted(counts) and counts[-1] <= 20
    assert all(np.isfinite(c) and c > 0 for _, c in seen)


def test_fit_of_a_recording_object_with_pandas(synth_recording):
    pd = pytest.importorskip("pandas")
    rec = bt.read_recording(synth_recording)
    result = bt.fit(rec, **{**FIT_KEYWORDS, "max_evals": 10})
    assert isinstance(result["breaths"], pd.DataFrame) and len(result["breaths"]) >= 2
    assert {"tidal_volume_l", "ti_ttot", "rib_cage_share"} <= set(result["breaths"].columns)
    assert isinstance(result["lung_volume"], pd.DataFrame)
    assert len(result["lung_volume"]) == len(rec.time)


def test_fit_errors(synth_recording, tmp_path):
    """A bad option names itself; an exception in the progress callback ends the fit and is
    raised again as itself."""
    with pytest.raises(ValueError, match="threads.*1 or 2"):
        bt.fit(synth_recording, threads=3, lod=0)
    with pytest.raises(ValueError, match="method"):
        bt.fit(synth_recording, method="simplex", lod=0)
    with pytest.raises(ValueError, match="postural_tone"):
        bt.fit(synth_recording, postural_tone=0, lod=0)
    with pytest.raises(bt.TorsoError, match="10x6 grid .60 points.*grid is 8x6"):
        bt.fit(synth_recording, grid="8x6", **FIT_KEYWORDS)

    class Stop(Exception):
        pass

    def stop(n, cost):
        if n >= 3:
            raise Stop(n)

    with pytest.raises(Stop):
        bt.fit(synth_recording, progress=stop, **FIT_KEYWORDS)


def test_ctrl_c_interrupts_a_fit(synth_recording):
    """SIGINT during a fit (the GIL released) raises KeyboardInterrupt at the next evaluation:
    a fit allowed 400 evaluations stops within 5 s of the signal."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals reach the main thread only")
    started = threading.Event()
    timer = threading.Thread(
        target=lambda: started.wait(30) and (time.sleep(0.5), os.kill(os.getpid(), signal.SIGINT)),
        daemon=True,
    )
    timer.start()
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        bt.fit(synth_recording, progress=lambda n, c: started.set(), **{**FIT_KEYWORDS, "max_evals": 400})
    timer.join()
    assert time.perf_counter() - t0 < 5.5


def test_ctrl_c_interrupts_a_simulation():
    """SIGINT during a long simulation (a day at 1 Hz, minutes of work) raises
    KeyboardInterrupt within 5 s; the model stays at the last frame it reached, whole."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals reach the main thread only")
    t = bt.Torso(lod=0)
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        t.simulate(86400.0, rate=1.0)
    timer.join()
    assert time.perf_counter() - t0 < 5.5
    assert 0.0 < t.time < 86400.0 and t.time == round(t.time)
    again = t.simulate(2.0, rate=1.0, as_frame=False)
    assert again["time"][0] == t.time - 2.0 and np.all(np.isfinite(again["volume.lung"]))


def test_validate_is_torso_validate(torso_cli, tmp_path):
    """validate() from the files, and from the arrays simulate returns, gives the statistics
    `torso validate` writes."""
    sim, spiro = tmp_path / "sim.csv", tmp_path / "spiro.csv"
    run_cli(torso_cli, "simulate", "--lod", "0", "--duration", "40", "--out", sim)
    run_cli(torso_cli, "synth-spirometry", "--from", sim, "--out", spiro, "--noise", "0.02", "--seed", "2")
    opts = ["--bootstrap", "19", "--bars-iterations", "400"]
    run_cli(torso_cli, "validate", "--sim", sim, "--spiro", spiro, "--out", tmp_path / "cli", *opts)
    cli = json.loads((tmp_path / "cli" / "validation.json").read_text())
    from_files = bt.validate(sim, spiro, tmp_path / "py", bootstrap=19, bars_iterations=400)
    assert from_files == cli
    assert json.loads((tmp_path / "py" / "validation.json").read_text()) == cli
    simulated = bt.Torso(lod=0).simulate(40.0, as_frame=False)
    s = read_csv(spiro)
    from_arrays = bt.validate(simulated, (s["time"], s["volume"]), bootstrap=19, bars_iterations=400)
    # simulate's arrays are the CSV's values, so every statistic is the same
    assert from_arrays == cli
    with pytest.raises(ValueError, match="bars.iterations"):
        bt.validate(sim, spiro, bars_iterations=100)
    with pytest.raises(ValueError, match="volume.*flow"):
        bt.validate(sim, sim)


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_bundled_fmu_through_fmpy_is_simulate(fmi_version):
    """The FMU shipped in the wheel, run by fmpy, gives the lung volume Torso.simulate gives
    at the same output times (the same library behind both)."""
    fmpy = pytest.importorskip("fmpy")
    path = bt.fmu_path(fmi_version)
    assert Path(path).is_file() and Path(path).parent.parent == Path(bt.__file__).parent
    r = fmpy.simulate_fmu(
        path, stop_time=2.0, output_interval=0.25, start_values={"scene.level_of_detail": 0},
        output=["volume.lung", "pressure.abdomen"],
    )
    d = bt.Torso(lod=0).simulate(2.0, rate=4, as_frame=False)
    assert np.array_equal(r["time"], d["time"])
    assert np.array_equal(r["volume.lung"], d["volume.lung"])
    assert np.array_equal(r["pressure.abdomen"], d["pressure.abdomen"])
    with pytest.raises(ValueError, match="allowed 2 or 3"):
        bt.fmu_path(1)


def test_exceptions_carry_the_library_message():
    """A run that leaves the physiological bounds is a TorsoError with the library's message
    (the variable, its value and the bounds), the model left at its last good time."""
    assert bt.TorsoError.__module__ == "breathing_torso" and issubclass(bt.TorsoError, Exception)
    t = bt.Torso(lod=0)
    with pytest.raises(ValueError, match=r"duration.*\(0, 86400\]"):
        t.simulate(-1.0)
    t.set_state(t.state() * 3.0)
    with pytest.raises(bt.TorsoError, match=r"volume\.\w+ = .* outside the physiological bounds"):
        t.simulate(1.0)
    assert t.time == 0.0


def test_breathing_frequency_of_a_recording(synth_recording):
    """The recording's frequency as `torso fit` finds it (`breathing frequency` in its JSON's
    `frequency`), from the package's arrays; the principal displacement's loadings are a unit
    vector over the points' coordinates."""
    rec = bt.read_recording(synth_recording)
    est = bt.breathing_frequency(rec.time, rec.positions)
    # torso synth's default drive: 0.25 Hz; the fit's acceptance (docs/results.md): within 1 %
    assert abs(est["frequency_hz"] - 0.25) <= 0.01 * 0.25
    assert est["signal"].shape == rec.time.shape
    assert est["loadings"].shape == (60, 3)
    assert np.isclose(np.sum(est["loadings"] ** 2), 1.0, rtol=0, atol=1e-12)
    assert 0.0 < est["explained"] <= 1.0
    with pytest.raises(ValueError, match="expected .frames, points, 3."):
        bt.breathing_frequency(rec.time[:-1], rec.positions)


def test_register_recovers_a_known_pose():
    """Points moved by a known rotation, translation (and scale) are registered back exactly,
    untracked points skipped; fewer than three tracked points is an error."""
    rng = np.random.default_rng(7)
    model = rng.normal(size=(12, 3)) * 0.1
    a = 0.7
    rot = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    recorded = (model @ rot.T) * 1.3 + [0.5, -0.2, 1.0]
    recorded[3] = np.nan
    rigid = bt.register(model, recorded / 1.3)
    assert rigid["scale"] == 1.0
    back = (recorded / 1.3) @ rigid["rotation"].T + rigid["translation"]
    ok = ~np.isnan(recorded[:, 0])
    assert np.allclose(back[ok], model[ok], rtol=0, atol=1e-12) and rigid["rms_m"] < 1e-12
    similar = bt.register(model, recorded, with_scale=True)
    assert similar["scale"] == pytest.approx(1 / 1.3, rel=1e-12)
    recorded[:10] = np.nan
    with pytest.raises(ValueError):
        bt.register(model, recorded)
