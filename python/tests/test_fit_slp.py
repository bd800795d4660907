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
    with pytest.raises(fit_slp.RecordingError, match="r.csv:2:1: unknown units"):
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
