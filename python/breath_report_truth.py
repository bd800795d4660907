#!/usr/bin/env python3
"""The per-breath report of a fit of a synthetic recording against the truth that made it.

`torso simulate` runs the true drive (from the recording's `.truth.json`) at the recording's
level of detail; its breaths after two settling breaths are measured with scipy
(scipy.signal.find_peaks for the extrema) and their means set against the `breaths_summary`
of the fit's result JSON. The phase angle is the Lissajous angle of the report's rule (a
Python port of it, `_lissajous` in python/tests/test_breath_report.py, so the same
algorithm, not an independent one; circular mean) and, independently, the phase
difference of the fundamentals of the rib-cage and abdominal volumes
(`fundamental_phase_deg`, least-squares sine fits at the breathing frequency) of the truth
and of the fit's written volumes (`<stem>_lung_volume.csv` beside the result JSON).

Usage: python breath_report_truth.py --truth rec.truth.json --fit result.json [--lod 0]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy.signal import find_peaks

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python" / "tests"))

from test_breath_report import _lissajous, circular_mean_deg, fundamental_phase_deg  # noqa: E402


def truth_breaths(torso: str, truth: dict, lod: int, rtol: float) -> dict:
    """Means of Ti, Te, VT, rib-cage share and phase angle of the true drive's breaths."""
    f = truth["drive.frequency"]
    args = [torso, "simulate", "--lod", str(lod), "--rtol", str(rtol), "--frequency", str(f),
            "--ti-ttot", str(truth.get("drive.inspiratory_fraction", 0.5)), "--rate", "56",
            "--duration", str(6.0 / f)]
    for fam in ("ribs", "diaphragm", "abdominals"):
        args += [f"--{fam}-amplitude", str(truth[f"drive.{fam}.amplitude"]),
                 f"--{fam}-phase", str(truth[f"drive.{fam}.phase"])]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "truth.csv"
        subprocess.run(args + ["--out", str(out)], check=True, capture_output=True)
        d = np.genfromtxt(out, delimiter=",", names=True)
    t, lung = d["time"], d["volumelung"]
    rc, ab = d["volumerib_cage_displaced"], d["volumeabdomen_displaced"]
    settled = t >= 2.0 / f
    span = lung[settled].max() - lung[settled].min()
    troughs, _ = find_peaks(-lung, prominence=0.3 * span)
    peaks, _ = find_peaks(lung, prominence=0.3 * span)
    troughs = troughs[t[troughs] >= 2.0 / f]
    rows = []
    for a, b in zip(troughs[:-1], troughs[1:]):
        p = peaks[(peaks > a) & (peaks < b)][0]
        seg = slice(a, b)
        swing = lambda x: x[seg].max() - x[seg].min()  # noqa: E731
        rows.append({"ti_s": t[p] - t[a], "te_s": t[b] - t[p], "tidal_volume_l": lung[p] - lung[a],
                     "rib_cage_share": swing(rc) / (swing(rc) + swing(ab)),
                     "phase_angle_deg": _lissajous(rc[seg], ab[seg])})
    means = {k: float(np.mean([r[k] for r in rows])) for k in rows[0]}
    means["phase_angle_deg"] = circular_mean_deg([r["phase_angle_deg"] for r in rows])
    whole = slice(troughs[0], troughs[-1])
    means["phase_fundamental_deg"] = fundamental_phase_deg(t[whole], rc[whole], ab[whole], f)[0]
    return means | {"breaths": len(rows)}


def fit_fundamental_phase(fit_json: Path, fit: dict) -> float:
    """Phase difference of the fundamentals of the fit's written compartment volumes over
    its whole breaths [deg]."""
    csv = fit_json.with_name(fit_json.stem + "_lung_volume.csv")
    d = np.genfromtxt(csv, delimiter=",", names=True)
    t = d["time"]
    breaths = fit["breaths"]
    h = t[1] - t[0]
    i0 = max(0, int(round(breaths[0]["onset_s"] / h)))
    i1 = min(len(t), int(round((breaths[-1]["onset_s"] + breaths[-1]["ttot_s"]) / h)))
    whole = slice(i0, i1)
    return fundamental_phase_deg(t[whole], d["volumerib_cage_displaced"][whole],
                                 d["volumeabdomen_displaced"][whole], fit["drive.frequency"])[0]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--truth", required=True)
    p.add_argument("--fit", required=True)
    p.add_argument("--lod", type=int, default=0)
    p.add_argument("--rtol", type=float, default=1e-4)
    p.add_argument("--torso", default=str(ROOT / "target" / "release" / "torso"))
    args = p.parse_args(argv)
    truth = truth_breaths(args.torso, json.loads(Path(args.truth).read_text()), args.lod, args.rtol)
    fit = json.loads(Path(args.fit).read_text())
    mean = fit["breaths_summary"]["mean"]
    print(f"{'index':<21} {'truth':>9} {'fit':>9} {'error':>9}   ({truth['breaths']} true breaths, "
          f"{fit['breaths_summary']['count']} fitted, {fit['evaluations']} evaluations)")
    fitted = dict(mean)
    fitted["phase_fundamental_deg"] = fit_fundamental_phase(Path(args.fit), fit)
    for k in ("ti_s", "te_s", "tidal_volume_l", "rib_cage_share", "phase_angle_deg", "phase_fundamental_deg"):
        print(f"{k:<21} {truth[k]:>9.4f} {fitted[k]:>9.4f} {fitted[k] - truth[k]:>+9.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
