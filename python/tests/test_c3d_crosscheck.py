"""The C3D files `torso` writes, read by another implementation (the `c3d` package from PyPI):
labels, rate, units, coordinates, missing points (residual -1) and the BREATHING_TORSO
provenance group agree with what `torso convert` writes as text.

Needs target/release/torso; skipped, with the reason printed, while it is missing.
"""

import subprocess
from pathlib import Path

import c3d
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
TORSO = ROOT / "target" / "release" / "torso"


def _torso(*args):
    if not TORSO.is_file():
        pytest.skip(f"{TORSO} missing: build it with `cargo build --release`")
    run = subprocess.run([str(TORSO), *map(str, args)], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr
    return run.stdout


def _grid_csv(path: Path):
    """(provenance dict, times, points [frames, 60, 3] in mm with NaN when missing)."""
    lines = path.read_text().splitlines()
    meta = {}
    while lines[0].startswith("#"):
        key, value = lines.pop(0)[1:].split(":", 1)
        meta[key.strip()] = value.strip()
    assert meta["units"] == "mm"
    rows = [[float(c) if c else np.nan for c in line.split(",")] for line in lines[1:]]
    data = np.array(rows)
    return meta, data[:, 0], data[:, 1:].reshape(len(rows), -1, 3)


@pytest.mark.parametrize("dropout", [0.0, 0.05])
def test_c3d_package_reads_what_torso_writes(tmp_path, dropout):
    rec = tmp_path / "rec.c3d"
    _torso("synth", "--lod", "0", "--duration", "2", "--rate", "25", "--dropout", dropout,
           "--out", rec, "--truth", tmp_path / "truth.json")
    _torso("convert", rec, tmp_path / "rec.csv")
    meta, times, want = _grid_csv(tmp_path / "rec.csv")

    with open(rec, "rb") as handle:
        reader = c3d.Reader(handle)
        labels = [label.strip() for label in reader.point_labels]
        assert labels == [f"marker[{k}]" for k in range(1, 61)]
        assert reader.point_rate == pytest.approx(25.0)
        assert reader.get("POINT:UNITS").string_value.strip() == "mm"
        keys = [k.strip() for k in reader.get("BREATHING_TORSO:KEYS").string_array]
        values = [v.strip() for v in reader.get("BREATHING_TORSO:VALUES").string_array]
        frames = [points for _, points, _ in reader.read_frames()]

    provenance = dict(zip(keys, values))
    assert provenance["scene.level_of_detail"] == "0"
    assert provenance["dropout"] == meta["dropout"]
    for key in keys:
        assert provenance[key] == meta[key], key
    assert len(frames) == len(times) == 51
    got = np.array([f[:, :3] for f in frames])
    residual = np.array([f[:, 3] for f in frames])
    missing = np.isnan(want[:, :, 0])
    assert np.array_equal(residual < 0, missing)
    assert (missing.sum() > 0) == (dropout > 0)
    # float32 millimetres against the text's 0.1 um
    assert np.max(np.abs(got[~missing] - want[~missing])) < 1e-4


def test_bundled_c3d_reads_in_the_c3d_package():
    with open(ROOT / "data" / "recordings" / "demo_quiet.c3d", "rb") as handle:
        reader = c3d.Reader(handle)
        assert reader.point_used == 60
        assert reader.point_rate == pytest.approx(30.0)
        frames = [points for _, points, _ in reader.read_frames()]
    assert len(frames) == 181
    assert all(np.all(f[:, 3] >= 0) for f in frames)
