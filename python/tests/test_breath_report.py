"""The per-breath report of `torso fit` checked by an independent implementation (numpy and
scipy): breath timing by scipy.signal.find_peaks on the fitted lung volume the fit writes,
tidal volume, IE50 from the numerical flow (numpy.gradient) at half the tidal volume, the
rib-cage share and the Lissajous phase angle recomputed from the written compartment
volumes; and python/fit_slp.py reading the same recordings as `torso fit` (grid CSV, C3D,
TRC, CSV of named markers) with the same progress lines.

Needs target/release/torso; skipped, with the reason printed, while it is missing. The fmpy
run needs fmu/BreathingTorso.fmu too.
"""

import io
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import find_peaks

ROOT = Path(__file__).resolve().parents[2]
TORSO = ROOT / "target" / "release" / "torso"
FMU = ROOT / "fmu" / "BreathingTorso.fmu"
sys.path.insert(0, str(ROOT / "python"))

import fit_slp  # noqa: E402


def _torso(*args):
    if not TORSO.is_file():
        pytest.skip(f"{TORSO} missing: build it with `cargo build --release`")
    run = subprocess.run([str(TORSO), *map(str, args)], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr
    return run


def _lissajous(rc, ab):
    """sin(phi) = m / s (Agostoni & Mognoni 1966), written afresh: m from the abdominal
    values where the rib cage crosses its mid-excursion (closed loop), s the abdominal
    excursion; beyond 90 deg when the two move in opposite directions; negative when the
    abdomen lags (clockwise loop with the rib cage on x)."""
    mid = 0.5 * (rc.min() + rc.max())
    a, b = rc - mid, np.roll(rc, -1) - mid
    ab_next = np.roll(ab, -1)
    w = np.where(a != b, a / np.where(a != b, a - b, 1.0), 0.0)
    at = ab + w * (ab_next - ab)
    up = at[(a < 0) & (b >= 0)][0]
    down = at[(a > 0) & (b <= 0)][0]
    phi = math.degrees(math.asin(min(1.0, abs(up - down) / (ab.max() - ab.min()))))
    if np.cov(rc, ab)[0, 1] < 0:
        phi = 180.0 - phi
    x, y = rc - rc.mean(), ab - ab.mean()
    area = float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
    return -phi if area > 0 else phi


def test_lissajous_reference_recovers_sine_phases():
    u = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    for phi in (0.0, 25.0, -70.0, 140.0):
        got = _lissajous(0.2 * np.sin(u), 0.5 * np.sin(u + math.radians(phi)) + 1.0)
        assert got == pytest.approx(phi, abs=0.2)


def test_breath_report_agrees_with_numpy_and_scipy(tmp_path):
    rec = tmp_path / "rec.csv"
    _torso("synth", "--lod", "0", "--rtol", "1e-4", "--duration", "20", "--seed", "11",
           "--out", rec, "--truth", tmp_path / "truth.json")
    out = tmp_path / "result.json"
    _torso("fit", "--slp", rec, "--lod", "0", "--rtol", "1e-4", "--max-evals", "24", "--threads", "1",
           "--out", out)
    result = json.loads(out.read_text())
    data = np.genfromtxt(tmp_path / "result_lung_volume.csv", delimiter=",", names=True)
    t, lung = data["time"], data["volumelung"]
    rc, ab = data["volumerib_cage_displaced"], data["volumeabdomen_displaced"]
    h = t[1] - t[0]
    span = lung.max() - lung.min()
    peaks, _ = find_peaks(lung, prominence=0.3 * span)
    troughs, _ = find_peaks(-lung, prominence=0.3 * span)
    breaths = result["breaths"]
    assert len(breaths) >= 3
    for b in breaths:
        i0 = int(round(b["onset_s"] / h))
        ip = int(round((b["onset_s"] + b["ti_s"]) / h))
        i1 = int(round((b["onset_s"] + b["ttot_s"]) / h))
        # scipy's extrema are the report's within one frame
        assert np.min(np.abs(troughs - i0)) <= 1, (b, troughs)
        assert np.min(np.abs(peaks - ip)) <= 1, (b, peaks)
        assert np.min(np.abs(troughs - i1)) <= 1, (b, troughs)
        seg = slice(i0, i1)
        # The CSV's lung volume is the fit's own run; the report's is a second run of the
        # same drive: the solver's tolerance (rtol 1e-4) and the CSV's 1 uL rounding.
        vt = lung[i0:i1].max() - lung[i0]
        assert vt == pytest.approx(b["tidal_volume_l"], abs=5e-4)
        # IE50 from numpy's central-difference flow at the half-volume crossings.
        flow = np.gradient(lung, t)
        half_in = lung[i0] + 0.5 * vt
        k = i0 + int(np.argmax(lung[i0:ip + 1] >= half_in))
        tif50 = np.interp(half_in, lung[k - 1:k + 1], flow[k - 1:k + 1])
        half_out = lung[ip] - 0.5 * (lung[ip] - lung[i1])
        k = ip + int(np.argmax(lung[ip:i1 + 1] <= half_out))
        tef50 = np.interp(-half_out, -lung[k - 1:k + 1], flow[k - 1:k + 1])
        assert tif50 / -tef50 == pytest.approx(b["ie50"], rel=0.02)
        swing = lambda x: x[seg].max() - x[seg].min()  # noqa: E731
        assert swing(rc) / (swing(rc) + swing(ab)) == pytest.approx(b["rib_cage_share"], abs=1e-3)
        assert _lissajous(rc[seg], ab[seg]) == pytest.approx(b["phase_angle_deg"], abs=0.3)
    summary = result["breaths_summary"]
    assert summary["count"] == len(breaths)
    for key in ("ti_s", "te_s", "tidal_volume_l", "phase_angle_deg"):
        values = [b[key] for b in breaths]
        assert summary["mean"][key] == pytest.approx(np.mean(values), abs=1e-12)
        assert summary["sd"][key] == pytest.approx(np.std(values, ddof=1), abs=1e-12)


def test_fit_slp_reads_every_format_torso_fit_reads(tmp_path):
    c3d_path = ROOT / "data" / "recordings" / "demo_quiet.c3d"
    _torso("convert", c3d_path, tmp_path / "rec.csv")
    _torso("convert", c3d_path, tmp_path / "rec.trc")
    grid, times, want = fit_slp.read_recording(tmp_path / "rec.csv")
    # A CSV of named markers, columns shuffled, `NAME X` headers, units in a # line.
    lines = (tmp_path / "rec.csv").read_text().splitlines()
    body = [line for line in lines if not line.startswith("#")]
    header = body[0].split(",")
    named = ["time"] + [c.replace("].x", "] X").replace("].y", "] Y").replace("].z", "] Z") for c in header[1:]]
    cols = [0]  # time, then the markers in reverse order
    for j in range(len(header) - 3, 0, -3):
        cols += [j, j + 1, j + 2]
    text = "# units: mm\n" + ",".join(named[c] for c in cols) + "\n"
    for row in body[1:]:
        cells = row.split(",")
        text += ",".join(cells[c] for c in cols) + "\n"
    (tmp_path / "named.csv").write_text(text)
    for name in ("rec.trc", "named.csv"):
        g, t, pts = fit_slp.read_recording(tmp_path / name)
        assert g == grid == (10, 6)
        assert np.allclose(t, times, atol=1e-9)
        assert np.nanmax(np.abs(pts - want)) < 1e-6
    with pytest.warns(UserWarning):  # the c3d package: no analog data in the file
        g, t, pts = fit_slp.read_recording(c3d_path)
    assert g == grid and np.allclose(t, times, atol=1e-6)
    # float32 millimetres in the C3D against the CSV's text
    assert np.nanmax(np.abs(pts - want)) < 1e-6
    (tmp_path / "bad.csv").write_text("# units: mm\ntime,A X,A Y,A Z\n0,1,2,3\n")
    with pytest.raises(fit_slp.RecordingError, match="bad.csv:0:0: 1 markers"):
        fit_slp.read_recording(tmp_path / "bad.csv")


def test_progress_lines_when_piped_end_at_100_percent():
    out = io.StringIO()
    p = fit_slp.Progress("fit_slp", 120, "evaluations", stream=out, interval=0.1, terminal=False)
    p.update(5, "best cost 0.900 mm")
    import time

    time.sleep(0.35)
    p.update(40, "best cost 0.800 mm")
    p.finish("cost 0.790 mm")
    lines = out.getvalue().splitlines()
    assert len(lines) >= 3, lines
    assert lines[0].startswith("fit_slp: 5/120 evaluations (4 %), best cost 0.900 mm, elapsed")
    assert lines[-1].startswith("fit_slp: 40/40 evaluations (100 %), cost 0.790 mm") and lines[-1].endswith("done")


def test_fit_slp_fits_a_c3d_recording_to_the_native_optimum_with_progress(tmp_path):
    """The same C3D file and a Ti/Ttot other than the sine's: fmpy reaches the native fit's
    optimum (the tolerances of test_fit_slp.py's grid-CSV comparison) and, piped, prints
    progress lines ending at 100 %."""
    if not FMU.is_file():
        pytest.skip(f"{FMU} missing: build it with `target/release/torso fmu build`")
    rec = tmp_path / "rec.c3d"
    _torso("synth", "--lod", "0", "--rtol", "1e-4", "--duration", "8", "--rate", "30", "--seed", "5",
           "--out", rec, "--truth", tmp_path / "truth.json")
    native = tmp_path / "native.json"
    _torso("fit", "--slp", rec, "--lod", "0", "--rtol", "1e-4", "--ti-ttot", "0.45", "--out", native)
    out = tmp_path / "fmpy.json"
    run = subprocess.run(
        [sys.executable, str(ROOT / "python" / "fit_slp.py"), "--fmu", str(FMU), "--slp", str(rec),
         "--lod", "0", "--rtol", "1e-4", "--ti-ttot", "0.45", "--out", str(out)],
        capture_output=True, text=True, cwd=ROOT,
    )
    assert run.returncode == 0, run.stderr
    lines = [line for line in run.stderr.splitlines() if line.startswith("fit_slp: ")]
    assert len(lines) >= 2, run.stderr
    assert "(100 %)" in lines[-1] and lines[-1].endswith("done"), lines[-1]
    a = json.loads(native.read_text())
    b = json.loads(out.read_text())
    assert a["drive.inspiratory_fraction"] == b["drive.inspiratory_fraction"] == 0.45
    assert b["evaluations"] <= 120
    assert abs(b["drive.frequency"] - a["drive.frequency"]) < 0.01 * a["drive.frequency"]
    for k in ("drive.ribs.amplitude", "drive.diaphragm.amplitude"):
        assert abs(b[k] - a[k]) <= 0.05 * a[k], (k, a[k], b[k])
    assert abs(fit_slp.wrap(b["delta_phase"] - a["delta_phase"])) < 0.1
    assert b["cost_m"] <= 1.05 * a["cost_m"]
    print(f"native: A_ribs {a['drive.ribs.amplitude']:.4f}, A_diaphragm {a['drive.diaphragm.amplitude']:.4f}, "
          f"dphi {a['delta_phase']:+.4f}, cost {a['cost_m'] * 1e3:.3f} mm; fmpy: A_ribs {b['drive.ribs.amplitude']:.4f}, "
          f"A_diaphragm {b['drive.diaphragm.amplitude']:.4f}, dphi {b['delta_phase']:+.4f}, "
          f"cost {b['cost_m'] * 1e3:.3f} mm")
