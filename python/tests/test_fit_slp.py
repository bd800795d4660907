"""python/fit_slp.py drives BreathingTorso.fmu through fmpy and reaches the native fit's
optimum (`torso fit`, both with a rigid first-frame registration), and recovers the truth.

Needs fmu/BreathingTorso.fmu (scripts/test.sh builds it) and a torso with marker outputs;
skipped, with the reason printed, while either is missing.
"""

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FMU = ROOT / "fmu" / "BreathingTorso.fmu"
TORSO = ROOT / "target" / "release" / "torso"
sys.path.insert(0, str(ROOT / "python"))

# fit_slp reads recordings with the Python package (scripts/test.sh installs its wheel)
pytest.importorskip("breathing_torso", reason="the package is not installed: bash scripts/build-wheel.sh, then pip install target/wheels/*.whl")
import fit_slp  # noqa: E402


def _require_fmu_and_markers(tmp: Path) -> Path:
    if not FMU.is_file() or not TORSO.is_file():
        pytest.skip(f"{FMU} or {TORSO} missing: build them with `cargo build --release && target/release/torso fmu build`")
    rec = tmp / "rec.csv"
    run = subprocess.run(
        [str(TORSO), "synth", "--out", str(rec), "--truth", str(tmp / "truth.json"),
         "--lod", "0", "--rtol", "1e-4", "--duration", "8", "--seed", "5"],
        capture_output=True, text=True,
    )
    if run.returncode != 0 and "no skin model" in run.stderr:
        pytest.skip(f"the torso has no marker outputs in this build: {run.stderr.strip()}")
    assert run.returncode == 0, run.stderr
    return rec


def test_recording_reader_matches_the_format(tmp_path):
    text = "# grid: 2x2\n# units: mm\ntime," + ",".join(
        f"marker[{i}].{a}" for i in range(1, 5) for a in "xyz") + "\n"
    text += "0," + ",".join(["1"] * 12) + "\n0.5," + ",,," + ",".join(["2"] * 9) + "\n"
    p = tmp_path / "r.csv"
    p.write_text(text)
    grid, times, pts = fit_slp.read_recording(p)
    assert grid == (2, 2)
    assert list(times) == [0.0, 0.5]
    assert pts.shape == (2, 4, 3)
    assert pts[0, 0, 0] == pytest.approx(1e-3)
    assert all(v != v for v in pts[1, 0])  # untracked -> NaN
    p.write_text(text.replace("# units: mm", "# units: inch"))
    with pytest.raises(fit_slp.RecordingError, match=r"r.csv:2:\d+: unknown units `inch`"):
        fit_slp.read_recording(p)


def test_frequency_and_kabsch_helpers():
    import numpy as np

    rng = np.random.default_rng(3)
    times = np.arange(0, 18, 1 / 56)
    base = rng.normal(size=(60, 3)) * 0.1
    d = rng.normal(size=(60, 3)) * 0.004
    pts = base[None] + np.sin(2 * np.pi * 0.27 * times)[:, None, None] * d[None]
    f, _, _ = fit_slp.breathing_frequency(times, pts)
    assert abs(f - 0.27) < 0.01 * 0.27
    angle = 0.4
    r = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    moved = base @ r.T + np.array([0.1, -0.2, 0.3])
    rot, t = fit_slp.kabsch(base, moved)
    assert np.allclose(moved @ rot.T + t, base, atol=1e-12)


def test_fmpy_fit_reaches_the_native_optimum(tmp_path):
    rec = _require_fmu_and_markers(tmp_path)
    native = tmp_path / "native.json"
    run = subprocess.run(
        [str(TORSO), "fit", "--slp", str(rec), "--lod", "0", "--rtol", "1e-4", "--out", str(native)],
        capture_output=True, text=True,
    )
    assert run.returncode == 0, run.stderr
    out = tmp_path / "fmpy.json"
    assert fit_slp.main(["--fmu", str(FMU), "--slp", str(rec), "--lod", "0", "--rtol", "1e-4", "--out", str(out)]) == 0
    a = json.loads(native.read_text())
    b = json.loads(out.read_text())
    for key in ("cost_m", "initial_cost_m", "skin_fit_error_m", "evaluations", "wall_s", "delta_phase",
                "lung_volume_csv", "drive.frequency", "drive.ribs.amplitude", "drive.diaphragm.amplitude",
                "drive.ribs.phase", "drive.diaphragm.phase"):
        assert key in b, key
    assert b["evaluations"] <= 120
    assert abs(b["drive.frequency"] - a["drive.frequency"]) < 0.01 * a["drive.frequency"]
    for k in ("drive.ribs.amplitude", "drive.diaphragm.amplitude"):
        assert abs(b[k] - a[k]) <= 0.05 * a[k], (k, a[k], b[k])
    assert abs(fit_slp.wrap(b["delta_phase"] - a["delta_phase"])) < 0.1
    assert b["cost_m"] <= 1.05 * a["cost_m"]
    assert Path(b["lung_volume_csv"]).is_file()
    truth = json.loads((tmp_path / "truth.json").read_text())
    for k in ("drive.ribs.amplitude", "drive.diaphragm.amplitude"):
        assert abs(b[k] - truth[k]) <= 0.10 * truth[k], (k, b[k], truth[k])
    print(f"native {a['wall_s']:.2f} s, fmpy {b['wall_s']:.2f} s, ratio {b['wall_s'] / a['wall_s']:.2f}")


def test_reset_restores_the_fresh_model_and_rebuilds_on_a_new_fixed_parameter(tmp_path):
    """fmi2Reset keeps the built model and restores its fresh state: a run after a reset gives
    the markers of a run on a new instance, bit for bit; a changed fixed parameter (stature)
    after a reset builds a different model, and changing it back gives the first one again."""
    import numpy as np

    if not FMU.is_file():
        pytest.skip(f"{FMU} missing: build it with `target/release/torso fmu build`")
    params = {"grid.rows": 10, "grid.cols": 6, "scene.level_of_detail": 0, "solver.rtol": 1e-4}
    drive = fit_slp.drive_dict(0.25, [0.3, 0.35, 0.4, 0.7])
    times = np.array([0.0, 0.25, 0.5])
    a = fit_slp.FmuModel(FMU, dict(params), {})
    b = fit_slp.FmuModel(FMU, dict(params), {})
    try:
        first, _ = a.run(drive, times)
        again, _ = a.run(drive, times)
        other, _ = a.run(fit_slp.drive_dict(0.25, [0.0, 0.0, 0.0, 0.0]), times)
        fresh, _ = b.run(drive, times)
        assert np.array_equal(first, again)
        assert np.array_equal(first, fresh)
        assert np.abs(other[-1] - first[-1]).max() > 1e-5  # the drive does change the markers
        a.params["subject.stature"] = 1.6
        short, _ = a.run(drive, times[:1])
        assert np.abs(short[0] - first[0]).max() > 1e-3
        a.params["subject.stature"] = 1.75
        back, _ = a.run(drive, times)
        assert np.array_equal(back, first)
    finally:
        a.close()
        b.close()


def test_reference_writer_round_trips(tmp_path):
    import numpy as np

    pts = np.arange(12, dtype=float).reshape(4, 3) * 1e-3
    pts[2] = np.nan
    p = tmp_path / "ref.csv"
    fit_slp.write_reference(p, (2, 2), pts)
    grid, times, frames = fit_slp.read_recording(p)
    assert grid == (2, 2) and len(times) == 2
    assert np.allclose(frames[0][[0, 1, 3]], pts[[0, 1, 3]], rtol=0, atol=1e-15)
    assert np.isnan(frames[1][2]).all()


def test_periodic_runs_match_stepping_through_every_frame():
    """Reading an 18 s run off its periodic breath gives the frames of a run stepped through
    every frame, within 0.2 um and 20 nL, from the third breath on (the first that repeats
    itself within the periodicity tolerance; before it, the stepped run still carries the
    transient from rest, about 0.3 um)."""
    import numpy as np

    if not FMU.is_file():
        pytest.skip(f"{FMU} missing: build it with `target/release/torso fmu build`")
    params = {"grid.rows": 10, "grid.cols": 6, "scene.level_of_detail": 0}
    drive = fit_slp.drive_dict(0.25, [0.2, 0.25, -1.6, -1.5])
    times = 4.0 + np.arange(1009) / 56.0
    m = fit_slp.FmuModel(FMU, dict(params), {})
    try:
        a, va = m.run(drive, times, volumes=True)
        b, vb = m.run(drive, times, volumes=True, periodic=False)
    finally:
        m.close()
    settled = times >= 8.0
    dm = np.linalg.norm(a[settled] - b[settled], axis=2).max()
    dv = np.abs(va[settled] - vb[settled]).max()
    print(f"periodic vs stepped from 8 s: markers {dm:.2e} m, lung {dv:.2e} L")
    assert dm < 2e-7 and dv < 2e-5
    assert np.array_equal(a[300], a[300 + 224])  # later breaths are the periodic one
