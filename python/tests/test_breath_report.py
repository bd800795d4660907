"""The per-breath report of `torso fit` checked against numpy and scipy: breath timing by
scipy.signal.find_peaks on the fitted lung volume the fit writes, tidal volume, IE50 from
the numerical flow (numpy.gradient) at half the tidal volume, and the rib-cage share
recomputed from the written compartment volumes; the phase angle by two routes: a Python
port of the report's own Lissajous rule (`_lissajous`, the same algorithm, which checks the
Rust arithmetic and sign convention, not the method), and an independent one, the phase
difference of the fundamentals (least-squares sine fits at the breathing frequency) of the
rib-cage and abdominal volumes; and python/fit_slp.py reading the same recordings as
`torso fit` (grid CSV, C3D, TRC, CSV of named markers) with the same progress lines.

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
    """sin(phi) = m / s (Agostoni & Mognoni 1966), a Python port of the report's rule
    (src/stats/thoracoabdominal.rs, not an independent derivation): m from the abdominal
    values where the rib cage crosses its mid-excursion (closed loop), s the abdominal
    excursion; beyond 90 deg when the two move in opposite directions (negative
    covariance); negative when the abdomen lags, i.e. when the loop, rib cage on x and
    abdomen on y, runs counter-clockwise (positive shoelace area)."""
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


def fundamental(t, x, f):
    """Least-squares fit of x = c + a sin(2 pi f t + theta): (theta [rad], a, largest
    absolute residual). The residual is what the signal holds beyond its fundamental
    (harmonics, drift)."""
    w = 2.0 * np.pi * f * np.asarray(t)
    design = np.column_stack([np.ones_like(w), np.sin(w), np.cos(w)])
    coef, *_ = np.linalg.lstsq(design, x, rcond=None)
    residual = x - design @ coef
    return math.atan2(coef[2], coef[1]), math.hypot(coef[1], coef[2]), float(np.max(np.abs(residual)))


def fundamental_phase_deg(t, rc, ab, f):
    """Phase of the abdominal volume's fundamental minus the rib cage's [deg], wrapped to
    (-180, 180] (positive: abdomen leads, the report's sign), and the bound [deg] within
    which the Lissajous angle of the same signals must lie around it.

    For two pure sinusoids the Lissajous angle equals this phase difference exactly. Beyond
    the fundamental, a residual of at most e_x (rib cage) and e_y (abdomen) times the
    fundamental's amplitude moves the mid-excursion crossings by at most e_x rad of phase,
    hence the abdominal values there by (e_x + e_y) times its amplitude (m by twice that),
    and the abdominal excursion s by 2 e_y; so sin(phi) moves by at most
    e_x + e_y (1 + |sin phi|), and phi by that over cos(phi) (first order; radians)."""
    th_rc, a_rc, r_rc = fundamental(t, rc, f)
    th_ab, a_ab, r_ab = fundamental(t, ab, f)
    d = math.degrees(th_ab - th_rc)
    d = (d + 180.0) % 360.0 - 180.0
    d = 180.0 if d == -180.0 else d
    ex, ey = r_rc / a_rc, r_ab / a_ab
    phi = math.radians(d)
    cos = abs(math.cos(phi))
    bound = math.degrees((ex + ey * (1.0 + abs(math.sin(phi)))) / cos) if cos > 0.1 else math.inf
    return d, bound


def circular_mean_deg(values):
    """Circular mean direction [deg] (Fisher 1993; Mardia & Jupp 2000)."""
    r = np.radians(values)
    return math.degrees(math.atan2(np.mean(np.sin(r)), np.mean(np.cos(r))))


def circular_sd_deg(values):
    """Circular standard deviation sqrt(-2 ln R) [deg], R the mean resultant length."""
    r = np.radians(values)
    return math.degrees(math.sqrt(-2.0 * math.log(math.hypot(np.mean(np.sin(r)), np.mean(np.cos(r))))))


def test_lissajous_reference_recovers_sine_phases():
    u = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    for phi in (0.0, 25.0, -70.0, 140.0):
        got = _lissajous(0.2 * np.sin(u), 0.5 * np.sin(u + math.radians(phi)) + 1.0)
        assert got == pytest.approx(phi, abs=0.2)


def test_fundamental_phase_recovers_sine_phases_and_bounds_harmonics():
    t = np.linspace(0.0, 12.0, 600, endpoint=False)
    f = 0.25
    u = 2 * np.pi * f * t
    for phi in (0.0, 25.0, -70.0, 140.0):
        d, bound = fundamental_phase_deg(t, 0.2 * np.sin(u) + 3.0, 0.5 * np.sin(u + math.radians(phi)), f)
        assert d == pytest.approx(phi, abs=1e-9)
        assert bound < 1e-9
    # A second harmonic of 5 % on the rib cage: the Lissajous angle of one breath moves,
    # within the stated bound.
    rc = 0.2 * (np.sin(u) + 0.05 * np.sin(2 * u + 0.7))
    ab = 0.5 * np.sin(u + math.radians(20.0))
    d, bound = fundamental_phase_deg(t, rc, ab, f)
    one = slice(0, 200)
    assert abs(_lissajous(rc[one], ab[one]) - d) <= bound


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
    # find_peaks never reports a sample at either end, nor one next to it (its prominence
    # is cut off by the end); a trough on or beside the first or last frame (the recording
    # starts at end-expiration) is the lowest sample of the quarter breath at that end,
    # when that sample is not the quarter's inner boundary (a slope running out of it).
    quarter = int(round(0.25 / result["drive.frequency"] / h))
    n = len(lung)
    for lo in (0, n - 1 - quarter):
        k = lo + int(np.argmin(lung[lo:lo + quarter + 1]))
        inner = lo + quarter if lo == 0 else lo
        if k != inner:
            troughs = np.union1d(troughs, [k])
    # The truth's breaths: a synthetic recording starts at end-expiration and, without
    # variability, its troughs follow every 1/f, so it holds floor(duration f) whole breaths.
    truth = json.loads((tmp_path / "truth.json").read_text())
    assert truth["variability"] == 0
    expected = math.floor(truth["duration_s"] * truth["drive.frequency"] + 1e-9)
    breaths = result["breaths"]
    assert len(breaths) == expected == 5
    checked = 0
    for b in breaths:
        i0 = int(round(b["onset_s"] / h))
        ip = int(round((b["onset_s"] + b["ti_s"]) / h))
        i1 = int(round((b["onset_s"] + b["ttot_s"]) / h))
        # A trough up to one frame outside the recording counts as on its end (the
        # report's rule); such a breath has a sample the CSV does not hold.
        assert -1 <= i0 and i1 <= len(t), b
        if i0 < 0 or i1 >= len(t):
            continue
        checked += 1
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
    assert checked >= len(breaths) - 2
    summary = result["breaths_summary"]
    assert summary["count"] == len(breaths)
    for key in ("ti_s", "te_s", "tidal_volume_l"):
        values = [b[key] for b in breaths]
        assert summary["mean"][key] == pytest.approx(np.mean(values), abs=1e-12)
        assert summary["sd"][key] == pytest.approx(np.std(values, ddof=1), abs=1e-12)
    phases = [b["phase_angle_deg"] for b in breaths]
    assert summary["mean"]["phase_angle_deg"] == pytest.approx(circular_mean_deg(phases), abs=1e-9)
    assert summary["sd"]["phase_angle_deg"] == pytest.approx(circular_sd_deg(phases), abs=1e-9)

    # Independently of the Lissajous rule: the phase difference of the fundamentals over
    # the whole breaths, within the bound the signals' departure from a sinusoid sets
    # (fundamental_phase_deg).
    i0 = max(0, int(round(breaths[0]["onset_s"] / h)))
    i1 = min(len(t), int(round((breaths[-1]["onset_s"] + breaths[-1]["ttot_s"]) / h)))
    whole = slice(i0, i1)
    d, bound = fundamental_phase_deg(t[whole], rc[whole], ab[whole], result["drive.frequency"])
    print(f"phase: report {summary['mean']['phase_angle_deg']:+.2f} deg, fundamentals {d:+.2f} deg, "
          f"bound {bound:.2f} deg")
    assert abs(summary["mean"]["phase_angle_deg"] - d) <= bound


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
    # read by the breathing_torso package (the library's C3D reader), not the c3d package
    g, t, pts = fit_slp.read_recording(c3d_path)
    assert g == grid and np.allclose(t, times, atol=1e-6)
    # float32 millimetres in the C3D against the CSV's text
    assert np.nanmax(np.abs(pts - want)) < 1e-6
    (tmp_path / "bad.csv").write_text("# units: mm\ntime,A X,A Y,A Z\n0,1,2,3\n")
    # the library's message: file, row and column, and what is wrong
    with pytest.raises(fit_slp.RecordingError, match=r"bad\.csv:4:1: 1 frame\(s\): a recording needs at least two"):
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
    """The same C3D file, breathed with Ti/Ttot 0.42, both fits reading Ti/Ttot off the
    recording (`--ti-ttot auto`): fmpy takes the native fit's inspiratory fraction, reaches its
    optimum (the tolerances of test_fit_slp.py's grid-CSV comparison) and, piped, prints
    progress lines ending at 100 %."""
    if not FMU.is_file():
        pytest.skip(f"{FMU} missing: build it with `target/release/torso fmu build`")
    rec = tmp_path / "rec.c3d"
    _torso("synth", "--lod", "0", "--rtol", "1e-4", "--duration", "8", "--rate", "30", "--seed", "5",
           "--ti-ttot", "0.42", "--out", rec, "--truth", tmp_path / "truth.json")
    native = tmp_path / "native.json"
    _torso("fit", "--slp", rec, "--lod", "0", "--rtol", "1e-4", "--ti-ttot", "auto", "--out", native)
    out = tmp_path / "fmpy.json"
    run = subprocess.run(
        [sys.executable, str(ROOT / "python" / "fit_slp.py"), "--fmu", str(FMU), "--slp", str(rec),
         "--lod", "0", "--rtol", "1e-4", "--ti-ttot", "auto", "--out", str(out)],
        capture_output=True, text=True, cwd=ROOT,
    )
    assert run.returncode == 0, run.stderr
    lines = [line for line in run.stderr.splitlines() if line.startswith("fit_slp: ")]
    assert len(lines) >= 2, run.stderr
    assert "(100 %)" in lines[-1] and lines[-1].endswith("done"), lines[-1]
    a = json.loads(native.read_text())
    b = json.loads(out.read_text())
    # The same breaths read the same way; against the drive's 0.42, within the SLP limit of
    # agreement for Ti (+-0.22 s, Motamedi-Fakhr et al. 2017) over the 4 s quiet breath: 0.055.
    assert abs(b["drive.inspiratory_fraction"] - a["drive.inspiratory_fraction"]) < 1e-6, (a, b)
    assert abs(a["drive.inspiratory_fraction"] - 0.42) < 0.05, a["drive.inspiratory_fraction"]
    assert b["evaluations"] <= 120
    assert abs(b["drive.frequency"] - a["drive.frequency"]) < 0.01 * a["drive.frequency"]
    for k in ("drive.ribs.amplitude", "drive.diaphragm.amplitude"):
        assert abs(b[k] - a[k]) <= 0.05 * a[k], (k, a[k], b[k])
    assert abs(fit_slp.wrap(b["delta_phase"] - a["delta_phase"])) < 0.1
    assert b["cost_m"] <= 1.05 * a["cost_m"]
    print(f"Ti/Ttot native {a['drive.inspiratory_fraction']:.4f}, fmpy {b['drive.inspiratory_fraction']:.4f}")
    print(f"native: A_ribs {a['drive.ribs.amplitude']:.4f}, A_diaphragm {a['drive.diaphragm.amplitude']:.4f}, "
          f"dphi {a['delta_phase']:+.4f}, cost {a['cost_m'] * 1e3:.3f} mm; fmpy: A_ribs {b['drive.ribs.amplitude']:.4f}, "
          f"A_diaphragm {b['drive.diaphragm.amplitude']:.4f}, dphi {b['delta_phase']:+.4f}, "
          f"cost {b['cost_m'] * 1e3:.3f} mm")


def test_breath_timing_reads_the_inspiratory_fraction_of_a_noisy_asymmetric_wave():
    """fit_slp's breath reader (`--ti-ttot auto`) on a wave of known timing: half-cosine
    rise over Ti = 0.4 Ttot, half-cosine fall over the rest, 4 s breaths at 30 Hz, noise 2 %
    of the swing. Every whole breath is found, each Ti and Te within the breath-by-breath limits
    of agreement of SLP against pneumotachography (Motamedi-Fakhr et al. 2017: +-0.22 s Ti,
    +-0.29 s Te), and the median Ti/Ttot within 0.02."""
    rng = np.random.default_rng(3)
    fs, period, frac = 30.0, 4.0, 0.4
    t = np.arange(0.0, 30.0, 1.0 / fs)
    phase = np.mod(t + 1.3, period) / period
    rise = 0.5 * (1 - np.cos(np.pi * phase / frac))
    fall = 0.5 * (1 + np.cos(np.pi * (phase - frac) / (1 - frac)))
    v = np.where(phase < frac, rise, fall) + 0.02 * rng.standard_normal(len(t))
    breaths = fit_slp.breath_timing(t, v, 1.0 / period)
    assert len(breaths) == 6, breaths
    for ti, te in breaths:
        assert abs(ti - frac * period) <= 0.22 and abs(te - (1 - frac) * period) <= 0.29, (ti, te)
    loadings = np.array([[1.0, 0.0, 0.0]])
    assert abs(fit_slp.recording_ti_ttot(t, v, loadings, 1.0 / period) - frac) < 0.02
    # A recording whose principal axis points dorsally is read with its sign turned.
    assert abs(fit_slp.recording_ti_ttot(t, -v, -loadings, 1.0 / period) - frac) < 0.02
