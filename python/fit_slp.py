#!/usr/bin/env python3
"""Fit BreathingTorso.fmu to an SLP recording through fmpy (thesis 3.4 and 4.3).

The same loop as `torso fit`, driven through the FMI 2.0 co-simulation interface:

1. the recording is read by the library's own reader, `breathing_torso.read_recording`
   (the Python package; docs/python.md), so as `torso fit` reads it (docs/recordings.md):
   the grid CSV, a C3D file, a TRC file or a CSV of named markers (`--units`, `--rate` when
   the file does not say), the markers labelled `marker[1]`..`marker[R*C]`;
2. the first frame is registered rigidly to the FMU's rest markers by the library (`breathing_torso.register`, as `torso fit`); with
   `--slp-reference` a first fit gives the rest-pose grid the recording implies, written as
   `<out stem>_reference.csv`, and the FMU registers its grid and fits its skin to it
   (`slp.reference`, as `torso fit --skin-fit`; its `marker[i].x|y|z` outputs are then in the
   recording's frame) before a polish;
3. the breathing frequency comes from the recording's principal displacement (PCA of the
   detrended marker trajectories, Hann-windowed DFT with two-bin interpolation), estimated
   by the library (`breathing_torso.breathing_frequency`), as `torso fit` estimates it;
4. a linearised start (two basis runs, rib cage alone and diaphragm alone, time-shifted,
   non-negative least squares) then scipy's bounded Nelder-Mead over
   (drive.ribs.amplitude, drive.diaphragm.amplitude, drive.ribs.phase, drive.diaphragm.phase);
   cost = mean marker-to-grid distance over frames and tracked points (eq. 3.1) after one
   rigid pose correction fitted over all frames (Kabsch), as in the native fit;
5. one FMU instance is reused: `fmi2Reset` before each run (the FMU keeps its built model and
   restores its fresh state), drive parameters as start values, one period of settling, then
   the recording window at the recording's frame times, one fmi2GetReal per frame.

The drive's inspiratory fraction (`drive.inspiratory_fraction`, Ti/Ttot of its waves) is
held at `--ti-ttot` (default 0.5, the sine of thesis eq. 2.4, as `torso fit`); `--ti-ttot auto`
takes the median Ti/Ttot of the recording's breaths, read off its principal displacement as
`torso fit --ti-ttot auto` reads it.

Progress goes to stderr: a bar on a terminal, else a line at least every 5 s and a last one
at 100 % (evaluations done over the budget, best cost, elapsed time, time left), as
`torso fit`.

Writes result.json with the FMI parameter names, `cost_m`, `initial_cost_m`,
`skin_fit_error_m`, `evaluations`, `wall_s`, `delta_phase` and the fitted lung-volume CSV.

Usage: python fit_slp.py --fmu fmu/BreathingTorso.fmu --slp rec.csv --out result.json
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
import threading
import time
from pathlib import Path

import numpy as np

import breathing_torso

POSTURES = {"standing": 0, "sitting": 1, "supine": 2}
SEXES = {"male": 0, "female": 1}
AMPLITUDE_RANGE = (0.0, 1.0)
BASIS_AMPLITUDE = 0.3
SHIFTS = 24


class RecordingError(ValueError):
    """A malformed recording: the message names file, line and column."""


UNIT_SCALES = {"m": 1.0, "cm": 1e-2, "mm": 1e-3}
LABEL = re.compile(r"^marker\[(\d+)\]$")


def _grid_points(path: Path, labels: list, coords: np.ndarray, grid) -> tuple:
    """Orders named markers [frames, len(labels), 3] as the grid `marker[1]`..`marker[R*C]`
    (grid from the provenance, else 60 markers -> 10x6)."""
    n = len(labels)
    if grid is None:
        if n != 60:
            raise RecordingError(f"{path}:0:0: {n} markers and no `grid` provenance entry: "
                                 "the grid is known only for 60 markers (10x6)")
        grid = (10, 6)
    want = grid[0] * grid[1]
    index = {}
    unknown = []
    for j, label in enumerate(labels):
        m = LABEL.match(label.strip())
        k = int(m.group(1)) if m else 0
        if not 1 <= k <= want or k in index:
            unknown.append(label)
        else:
            index[k] = j
    missing = [f"marker[{k}]" for k in range(1, want + 1) if k not in index]
    if unknown or missing:
        raise RecordingError(
            f"{path}:0:0: labels not of the {grid[0]}x{grid[1]} grid: unknown {unknown[:5]}, "
            f"missing {missing[:5]} (expected marker[1]..marker[{want}])")
    order = [index[k] for k in range(1, want + 1)]
    return grid, coords[:, order, :]


def _parse_grid(value: str):
    r, c = value.lower().split("x")
    return int(r), int(c)


def read_recording(path: Path, units=None, rate=None):
    """Reads a recording in any of the formats `torso fit` reads (see the module doc) with
    the library's own reader (`breathing_torso.read_recording`). Returns (grid, times [s],
    points [frames, R*C, 3] in metres with NaN for untracked points), the points in the
    grid's order; a malformed file is a RecordingError naming file, line and column."""
    try:
        rec = breathing_torso.read_recording(path, units=units, rate=rate)
    except ValueError as e:
        raise RecordingError(str(e)) from e
    grid = _parse_grid(rec.provenance["grid"]) if "grid" in rec.provenance else None
    grid, pts = _grid_points(Path(path), rec.labels, rec.positions, grid)
    return grid, rec.time, pts


def detrend(x: np.ndarray) -> np.ndarray:
    """Removes the least-squares line along axis 0."""
    n = x.shape[0]
    t = np.arange(n) - (n - 1) / 2.0
    mean = x.mean(axis=0)
    slope = (t[:, None] * (x - mean)).sum(axis=0) / (t**2).sum()
    return x - mean - slope * t[:, None]


def breathing_frequency(times: np.ndarray, pts: np.ndarray):
    """The breathing frequency, the principal displacement and each point's loading on its
    axis, as `torso fit` estimates them (`breathing_torso.breathing_frequency`: gap-filled,
    detrended trajectories, first principal axis, Hann-windowed DFT with two-bin
    interpolation and the autocorrelation cross-check)."""
    est = breathing_torso.breathing_frequency(times, pts)
    return est["frequency_hz"], est["signal"], est["loadings"]


def _moving_average(v: np.ndarray, half: int) -> np.ndarray:
    """Centred moving average over `half` samples each side, shrinking at the ends."""
    prefix = np.concatenate([[0.0], np.cumsum(v)])
    i = np.arange(len(v))
    a, b = np.maximum(i - half, 0), np.minimum(i + half + 1, len(v))
    return (prefix[b] - prefix[a]) / (b - a)


def _extrema(v: np.ndarray, h: float) -> list:
    """Hysteresis extrema: a peak once the signal falls `h` below the running maximum, a
    trough once it rises `h` above the running minimum. Items (index, +1 peak / -1 trough)."""
    out, state, hi, lo = [], 0, 0, 0
    for i in range(1, len(v)):
        if state >= 0 and v[i] > v[hi]:
            hi = i
        if state <= 0 and v[i] < v[lo]:
            lo = i
        if state <= 0 and v[i] >= v[lo] + h:
            out.append((lo, -1))
            state, hi = 1, i
        elif state >= 0 and v[i] <= v[hi] - h:
            out.append((hi, 1))
            state, lo = -1, i
    return out


def breath_timing(times: np.ndarray, signal: np.ndarray, f: float) -> list:
    """(Ti, Te) of each whole breath (trough, peak, trough) of `signal` (inspiration
    positive), as `torso fit` reads the recording's breaths (src/stats/breaths.rs with
    src/fit/breathing.rs's settings): extrema located on a centred moving average over 0.05
    breathing periods, hysteresis 0.3 of the 5-95 % range of the detrended curve, extrema
    closer than 0.1 periods merged (the more extreme kept), an extremum on the first sample
    dropped."""
    period = 1.0 / f
    n = len(times)
    if n < 4:
        return []
    dt = (times[-1] - times[0]) / (n - 1)
    half = int(round(0.5 * 0.05 * period / dt)) if dt > 0 else 0
    v = _moving_average(np.asarray(signal, dtype=float), half)
    d = detrend(v[:, None])[:, 0]
    h = 0.3 * (np.percentile(d, 95) - np.percentile(d, 5))
    if h <= 0:
        return []
    ext = _extrema(v, h)
    if ext and ext[0][0] == 0:
        ext.pop(0)
    i = 0
    while i + 1 < len(ext):
        if times[ext[i + 1][0]] - times[ext[i][0]] < 0.1 * period:
            if i > 0 and i + 2 < len(ext):
                a, b = ext[i - 1], ext[i + 1]
                keep_b = v[b[0]] > v[a[0]] if a[1] > 0 else v[b[0]] < v[a[0]]
                ext[i - 1] = b if keep_b else a
                del ext[i:i + 2]
                i -= 1
            elif i == 0:
                ext.pop(0)
            else:
                del ext[i + 1:]
        else:
            i += 1
    return [(times[p] - times[s], times[e] - times[p])
            for (s, ks), (p, kp), (e, ke) in zip(ext, ext[1:], ext[2:]) if (ks, kp, ke) == (-1, 1, -1)]


def recording_ti_ttot(times: np.ndarray, signal: np.ndarray, loadings: np.ndarray, f: float) -> float:
    """Median Ti/Ttot of the recording's breaths (`torso fit --ti-ttot auto`): the principal
    displacement signed so that inspiration moves the markers ventrally (+x of the model's
    frame, where the registered recording lies), clamped to the drive's 0.2-0.8; NaN without
    a whole breath."""
    sign = -1.0 if loadings[:, 0].sum() < 0 else 1.0
    fractions = [ti / (ti + te) for ti, te in breath_timing(times, sign * signal, f)]
    if not fractions:
        return math.nan
    return float(np.clip(np.median(fractions), 0.2, 0.8))


def kabsch(model: np.ndarray, rec: np.ndarray):
    """Rigid transform (R, t) minimising sum |R rec + t - model|^2, the registration of
    `torso fit` (`breathing_torso.register`, Umeyama 1991)."""
    reg = breathing_torso.register(model, rec)
    return reg["rotation"], reg["translation"]


def wrap(a: float) -> float:
    """Wraps an angle to (-pi, pi]."""
    w = (a + math.pi) % (2 * math.pi) - math.pi
    return w + 2 * math.pi if w <= -math.pi else w



def format_secs(secs: float) -> str:
    """`12.3 s`, `4 min 05 s` or `1 h 02 min`, as `torso`'s progress."""
    if not math.isfinite(secs):
        return "?"
    s = max(secs, 0.0)
    if s < 60:
        return f"{s:.1f} s"
    if s < 3600:
        return f"{int(s // 60)} min {int(s % 60):02d} s"
    return f"{int(s // 3600)} h {int(s % 3600 // 60):02d} min"


class Progress:
    """Progress on `stream` (stderr): a bar redrawn in place on a terminal; otherwise a line
    at the first update, then at least every `interval` seconds (a timer thread writes one
    even when no update comes), and a last line at 100 %; the same text as `torso fit`."""

    def __init__(self, label: str, total: int, unit: str, stream=None, interval: float = 5.0,
                 terminal: bool | None = None):
        self.label, self.total, self.unit = label, total, unit
        self.stream = stream if stream is not None else sys.stderr
        self.terminal = self.stream.isatty() if terminal is None else terminal
        self.interval = interval
        self.start = time.monotonic()
        self.done, self.detail = 0, ""
        self.last_line = None
        self.last_draw = 0.0
        self.lock = threading.Lock()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._tick, daemon=True)
        self.thread.start()

    def _text(self, end: bool = False) -> str:
        elapsed = time.monotonic() - self.start
        pct = 100.0 if self.total == 0 else min(100.0, 100.0 * self.done / self.total)
        if self.done >= self.total:
            eta = "0 s"
        elif self.done == 0:
            eta = "?"
        else:
            eta = format_secs(elapsed * (self.total - self.done) / self.done)
        detail = f", {self.detail}" if self.detail else ""
        if self.terminal:
            filled = min(30, int(pct / 100 * 30))
            return (f"\r{self.label} [{'#' * filled}{'.' * (30 - filled)}] {pct:3.0f} % {self.done}/{self.total} "
                    f"{self.unit}{detail}, {format_secs(elapsed)} elapsed, ETA {eta}\x1b[K")
        tail = "done" if end else f"ETA {eta}"
        return (f"{self.label}: {self.done}/{self.total} {self.unit} ({pct:.0f} %){detail}, "
                f"elapsed {format_secs(elapsed)}, {tail}\n")

    def _write(self, text: str):
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):
            pass  # progress is advisory

    def _emit(self, force: bool):
        with self.lock:
            now = time.monotonic()
            if self.terminal:
                due = now - self.last_draw >= 0.1
                if force or due:
                    self.last_draw = now
                    self._write(self._text())
            else:
                due = self.last_line is None or now - self.last_line >= self.interval
                if force or due:
                    self.last_line = now
                    self._write(self._text())

    def _tick(self):
        step = 0.5 if self.terminal else max(0.01, self.interval / 10)
        while not self.stop.wait(step):
            since = self.last_line if self.last_line is not None else self.start
            if self.terminal or time.monotonic() - since >= self.interval:
                self._emit(True)

    def update(self, done: int, detail: str = ""):
        with self.lock:
            self.done, self.detail = done, detail
        self._emit(False)

    def finish(self, detail: str = ""):
        """The count becomes the total (a search that stops early has done all it will do)
        and the last line, or the full bar, is written."""
        self.stop.set()
        self.thread.join()
        with self.lock:
            if self.done < self.total:
                self.total = self.done
            self.detail = detail
            self._write(self._text(end=True) + ("\n" if self.terminal else ""))


class FmuModel:
    """One BreathingTorso FMU instance, reset before each run."""

    def __init__(self, fmu_path: Path, params: dict, strings: dict):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        self.md = read_model_description(str(fmu_path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.kind = {v.name: v.type for v in self.md.modelVariables}
        self.unzip = extract(str(fmu_path))
        self.fmu = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=self.unzip,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName="fit_slp",
        )
        self.fmu.instantiate()
        self.params, self.strings = params, strings
        self.rows, self.cols = int(params["grid.rows"]), int(params["grid.cols"])
        n = self.rows * self.cols
        self.marker_vrs = [self.vr[f"marker[{i + 1}].{a}"] for i in range(n) for a in "xyz"]
        self.volume_vr = self.vr["volume.lung"]
        self.runs = 0
        self.fresh = True

    def _set(self, values: dict):
        """Sets values grouped by type: one fmi2Set* call per type."""
        groups = {}
        for name, value in values.items():
            groups.setdefault(self.kind[name], []).append((self.vr[name], value))
        for kind, pairs in groups.items():
            vrs = [vr for vr, _ in pairs]
            if kind == "Real":
                self.fmu.setReal(vrs, [float(v) for _, v in pairs])
            elif kind in ("Integer", "Enumeration"):
                self.fmu.setInteger(vrs, [int(v) for _, v in pairs])
            elif kind == "Boolean":
                self.fmu.setBoolean(vrs, [bool(v) for _, v in pairs])
            else:
                self.fmu.setString(vrs, [str(v) for _, v in pairs])

    def run(self, drive: dict, times: np.ndarray, volumes: bool = False, periodic: bool = True):
        """Markers [len(times), P, 3] (and lung volumes) at model times `times`.

        `fmi2Reset` keeps the built model aside and the next initialisation restores its fresh
        state, so a run costs the integration alone. Per output: one fmi2DoStep and one
        fmi2GetReal of every marker coordinate straight into the output array (ctypes, a
        precomputed value-reference array), no Python-level conversion.

        With `periodic` (as the native fit, `TorsoMarkers::run_periodic`): the frames are read
        off the periodic response. The first breath from rest is the transient; each following
        breath is stepped through the phases of every frame and checked (its end against its
        start: markers within 0.1 um, lung volume within 10 nL); the first periodic breath
        gives every frame at its phase. Frames are read as they come too, so a response that
        is not periodic before the last two breaths is simply simulated over every frame.
        """
        import ctypes

        from fmpy.fmi2 import fmi2True

        if not self.fresh:
            self.fmu.reset()
        self.fresh = False
        self.runs += 1
        self._set(self.params)
        self._set(self.strings)
        self._set(drive)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        n = self.rows * self.cols
        out = np.empty((len(times), n, 3))
        vol = np.empty(len(times))
        vrs = (ctypes.c_uint32 * (3 * n))(*self.marker_vrs)
        vvr = (ctypes.c_uint32 * 1)(self.volume_vr)
        dbl = ctypes.POINTER(ctypes.c_double)
        comp, do_step, get_real = self.fmu.component, self.fmu.fmi2DoStep, self.fmu.fmi2GetReal
        t = 0.0

        def sample(targets, markers, volumes_out):
            nonlocal t
            for k, target in enumerate(targets):
                if target > t:
                    do_step(comp, t, target - t, fmi2True)
                    t = target
                get_real(comp, vrs, 3 * n, markers[k].ctypes.data_as(dbl))
                if volumes:
                    get_real(comp, vvr, 1, volumes_out[k:].ctypes.data_as(dbl))

        f = float(drive["drive.frequency"])
        period = 1.0 / f
        settle = period
        nxt = 0
        if periodic and len(times) and times[0] >= 0.0 and times[-1] > 3.0 * period:
            begin, start = settle, None
            while times[-1] > begin + 2.0 * period:
                end = begin + period
                direct = int(np.searchsorted(times, end, side="right"))
                phases = np.minimum(begin + np.mod(times - settle, period), end)
                extra = ([begin] if start is None else []) + [end]
                targets = np.concatenate([times[nxt:direct], phases, extra])
                order = np.argsort(targets, kind="stable")
                got = np.empty((len(targets), n, 3))
                got_vol = np.empty(len(targets))
                sorted_m = np.empty_like(got)
                sorted_v = np.empty_like(got_vol)
                sample(targets[order], sorted_m, sorted_v)
                got[order], got_vol[order] = sorted_m, sorted_v
                nd = direct - nxt
                out[nxt:direct], vol[nxt:direct] = got[:nd], got_vol[:nd]
                if start is None:
                    start = (got[-2].copy(), got_vol[-2])
                end_m, end_v = got[-1], got_vol[-1]
                mismatch_m = float(np.max(np.linalg.norm(end_m - start[0], axis=1)))
                ok = mismatch_m <= 1e-7 and (not volumes or abs(end_v - start[1]) <= 1e-5)
                nxt = direct
                if ok:
                    out[:] = got[nd:nd + len(times)]
                    vol[:] = got_vol[nd:nd + len(times)]
                    return out, vol
                start = (end_m.copy(), end_v)
                begin = end
        sample(times[nxt:], out[nxt:], vol[nxt:])
        return out, vol

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def drive_dict(f: float, x) -> dict:
    return {
        "drive.frequency": f,
        "drive.ribs.amplitude": x[0],
        "drive.diaphragm.amplitude": x[1],
        "drive.ribs.phase": x[2],
        "drive.diaphragm.phase": x[3],
        "drive.abdominals.amplitude": 0.0,
        "drive.abdominals.phase": 0.0,
    }


def aligned_cost(model_pts: np.ndarray, rec: np.ndarray, tracked: np.ndarray) -> float:
    m, r = model_pts[tracked], rec[tracked]
    rot, t = kabsch(m, r)
    return float(np.linalg.norm(r @ rot.T + t - m, axis=1).mean())


def linearised_start(model, rest, rec, tracked, times, f, psi, rate):
    """Two basis runs (three breaths each, the third read as periodic) and the best
    time-shifted non-negative least-squares combination."""
    period = 1.0 / f
    h = 1.0 / rate
    # one breath of each basis response after two of settling, read as periodic (as native)
    n = int(math.ceil(period / h)) + 2
    grid = 2.0 * period + h * np.arange(n)
    bases = []
    for fam in range(2):
        x = [BASIS_AMPLITUDE if fam == 0 else 0.0, BASIS_AMPLITUDE if fam == 1 else 0.0, psi, psi]
        pts, _ = model.run(drive_dict(f, x), grid)
        bases.append(pts - rest)
    stride = max(1, len(times) // 300)
    idx = np.arange(0, len(times), stride)
    r = np.where(tracked[idx][..., None], rec[idx], np.nan)
    r = r - np.nanmean(r, axis=0)
    mask = ~np.isnan(r[..., 0])
    r = np.nan_to_num(r)

    def sample(b, s):
        tt = np.mod(times[idx] + s * period / SHIFTS, period)
        x = np.clip(tt / h, 0, n - 1)
        j = np.minimum(np.floor(x).astype(int), n - 2)
        w = (x - j)[:, None, None]
        d = b[j] * (1 - w) + b[j + 1] * w
        return (d - d.mean(axis=0)) * mask[..., None]

    dr = [sample(bases[0], s) for s in range(SHIFTS)]
    dd = [sample(bases[1], s) for s in range(SHIFTS)]
    best = (math.inf, None)
    rr = float((r * r).sum())
    for sr, a in enumerate(dr):
        aa, ar = float((a * a).sum()), float((a * r).sum())
        for sd, b in enumerate(dd):
            bb, ab, br = float((b * b).sum()), float((a * b).sum()), float((b * r).sum())
            cands = [(max(ar / aa, 0.0) if aa > 0 else 0.0, 0.0), (0.0, max(br / bb, 0.0) if bb > 0 else 0.0)]
            det = aa * bb - ab * ab
            if det > 1e-12 * aa * bb:
                cr, cd = (ar * bb - br * ab) / det, (br * aa - ar * ab) / det
                if cr >= 0 and cd >= 0:
                    cands.append((cr, cd))
            for cr, cd in cands:
                res = rr - 2 * (cr * ar + cd * br) + cr * cr * aa + 2 * cr * cd * ab + cd * cd * bb
                if res < best[0]:
                    ph = lambda s: psi + wrap(2 * math.pi * s / SHIFTS)
                    best = (res, [float(np.clip(cr * BASIS_AMPLITUDE, *AMPLITUDE_RANGE)),
                                  float(np.clip(cd * BASIS_AMPLITUDE, *AMPLITUDE_RANGE)), ph(sr), ph(sd)])
    return best[1]


SKIN_POLISH_EVALS = 40


def write_reference(path: Path, grid, points: np.ndarray):
    """A still recording (two identical frames, metres) of `points` [P, 3] (NaN: untracked)."""
    n = grid[0] * grid[1]
    head = "time," + ",".join(f"marker[{i + 1}].{a}" for i in range(n) for a in "xyz")
    cells = ["" if np.isnan(v) else repr(float(v)) for v in points.reshape(-1)]
    path.parent.mkdir(parents=True, exist_ok=True)
    row = ",".join(cells)
    path.write_text(f"# grid: {grid[0]}x{grid[1]}\n# units: m\n{head}\n0.0,{row}\n{1 / 56},{row}\n")


def search(model, rec, tracked, times, f, x0, budget, step, history, progress=None):
    """Bounded Nelder-Mead (scipy, adaptive) from x0 in the unit box of the bounds (each
    phase within pi of its start), as the native search: initial simplex of `step` times each
    range, stop when the simplex spans less than 0.004 of each range and its costs agree
    within 0.4 um. Returns x."""
    from scipy.optimize import minimize

    lo = np.array([AMPLITUDE_RANGE[0]] * 2 + [x0[2] - math.pi, x0[3] - math.pi])
    hi = np.array([AMPLITUDE_RANGE[1]] * 2 + [x0[2] + math.pi, x0[3] + math.pi])
    span = hi - lo
    model_times = 1.0 / f + times

    def cost(u):
        x = lo + np.clip(u, 0.0, 1.0) * span
        pts, _ = model.run(drive_dict(f, x), model_times)
        value = aligned_cost(pts, rec, tracked)
        history.append(value)
        if progress is not None:
            progress.update(len(history) + 2, f"best cost {min(history) * 1e3:.3f} mm")
        return value

    u0 = np.clip((np.array(x0, dtype=float) - lo) / span, 0.0, 1.0)
    simplex = [u0]
    for i in range(4):
        v = u0.copy()
        v[i] = v[i] + step if v[i] + step <= 1.0 else v[i] - step
        simplex.append(v)
    res = minimize(
        cost,
        u0,
        method="Nelder-Mead",
        bounds=[(0.0, 1.0)] * 4,
        options={"maxfev": budget, "initial_simplex": np.array(simplex), "xatol": 4e-3, "fatol": 4e-7,
                 "adaptive": True},
    )
    return lo + np.clip(res.x, 0.0, 1.0) * span


def fit(args) -> dict:
    start = time.perf_counter()
    (rows, cols), times_abs, raw = read_recording(Path(args.slp), args.units, args.rate)
    times = times_abs - times_abs[0]
    tracked = ~np.isnan(raw[..., 0])
    params = {
        "subject.sex": SEXES[args.sex],
        "subject.age": args.age,
        "subject.stature": args.stature,
        "subject.mass": args.mass,
        "subject.breast_size": args.breast_size,
        "posture": POSTURES[args.posture],
        "scene.level_of_detail": args.lod,
        "grid.rows": rows,
        "grid.cols": cols,
        "solver.rtol": args.rtol,
        "solver.atol": args.rtol / 100,  # as the native fit (FIT_ATOL_PER_RTOL)
    }
    out = Path(args.out)
    auto = args.ti_ttot == "auto"
    if not auto:
        try:
            ti_ttot = float(args.ti_ttot)
        except ValueError:
            ti_ttot = math.nan
        if not 0.2 <= ti_ttot <= 0.8:
            raise RecordingError(f"--ti-ttot {args.ti_ttot}: expected `auto` or a number in [0.2, 0.8]")
        params["drive.inspiratory_fraction"] = ti_ttot
    model = FmuModel(Path(args.fmu), params, {})
    history = []
    progress = Progress("fit_slp", args.max_evals, "evaluations")
    skin = None
    try:
        n_model = model.rows * model.cols
        if n_model != rows * cols:
            raise RecordingError(f"recording grid {rows}x{cols} does not match the model's {model.rows}x{model.cols}")
        rest, _ = model.run(drive_dict(0.25, [0, 0, 0, 0]), np.array([0.0]))
        rest = rest[0]
        first = tracked[0]
        # Rigid registration of the first frame to the rest markers (as `torso fit`); the
        # cost's pose correction over all frames refines it.
        rot0, t0 = kabsch(rest[first], raw[0][first])
        rec = raw @ rot0.T + t0
        registration_err = float(np.linalg.norm(rec[0][first] - rest[first], axis=1).mean())
        rate = (len(times) - 1) / times[-1]
        f, signal, loadings = breathing_frequency(times, rec)
        if auto:
            # Ti/Ttot read off the recording's breaths; the FMU takes it at every reset.
            ti_ttot = recording_ti_ttot(times, signal, loadings, f)
            if not math.isfinite(ti_ttot):
                raise RecordingError(f"{args.slp}: --ti-ttot auto needs at least one whole breath "
                                     "(minimum, maximum, minimum) in the recording; give a number")
            model.params["drive.inspiratory_fraction"] = ti_ttot
        # Phase of the breath's fundamental: the basis runs' phase (the shift scan covers
        # the whole period, so the principal axis's sign does not matter).
        c = np.stack([np.ones_like(times), np.sin(2 * np.pi * f * times), np.cos(2 * np.pi * f * times)], 1)
        coef = np.linalg.lstsq(c, signal, rcond=None)[0]
        psi = math.atan2(coef[2], coef[1])
        model_times = 1.0 / f + times
        budget = args.max_evals - 2 - (SKIN_POLISH_EVALS if args.slp_reference else 0)
        x0 = linearised_start(model, rest, rec, tracked, times, f, psi, rate)
        x0[2], x0[3] = wrap(x0[2]), wrap(x0[3])
        x = search(model, rec, tracked, times, f, x0, budget, 0.03, history, progress)
        if args.slp_reference:
            # The rest-pose grid the first fit implies (each frame minus the fitted model's
            # displacement from rest, averaged over frames; as `torso fit --skin-fit`), in the
            # recording's frame, becomes the FMU's slp.reference: the FMU fits its skin to
            # it and outputs markers in the recording's frame; then a polish.
            pts, _ = model.run(drive_dict(f, x), model_times)
            m, r = pts[tracked], rec[tracked]
            rot, t = kabsch(m, r)
            corrected = rec @ rot.T + t
            implied = np.where(tracked[..., None], corrected - (pts - rest[None]), 0.0)
            count = tracked.sum(axis=0)
            ref_model = implied.sum(axis=0) / np.maximum(count, 1)[:, None]
            # model frame -> recording frame: x_raw = rot0^T (rot^T (x - t) - t0)
            ref = ((ref_model - t) @ rot - t0) @ rot0
            ref[count == 0] = np.nan
            reference = out.with_name(out.stem + "_reference.csv")
            write_reference(reference, (rows, cols), ref)
            model.strings = {"slp.reference": str(reference.resolve())}
            rest_fitted, _ = model.run(drive_dict(0.25, [0, 0, 0, 0]), np.array([0.0]))
            ok = count > 0
            skin = {"before": float(np.linalg.norm(ref_model[ok] - rest[ok], axis=1).mean()),
                    "after": float(np.linalg.norm(rest_fitted[0][ok] - ref[ok], axis=1).mean()),
                    "skin_fitted": True, "reference": str(reference)}
            rec = raw  # the FMU's markers are now in the recording's frame
            budget = args.max_evals - len(history) - 3
            x = search(model, rec, tracked, times, f, [x[0], x[1], wrap(x[2]), wrap(x[3])], budget, 0.01,
                       history, progress)
        best = int(np.argmin(history))
        pts, vol = model.run(drive_dict(f, x), model_times, volumes=True)
        final_cost = aligned_cost(pts, rec, tracked)
        evaluations = len(history) + 2
        progress.update(evaluations, f"best cost {min(history) * 1e3:.3f} mm")
        progress.finish(f"cost {final_cost * 1e3:.3f} mm")
    finally:
        progress.stop.set()
        model.close()
    out.parent.mkdir(parents=True, exist_ok=True)
    csv = out.with_name(out.stem + "_lung_volume.csv")
    with csv.open("w") as fh:
        fh.write("time,volume.lung\n")
        for t, v in zip(times, vol):
            fh.write(f"{t:.6f},{v:.6f}\n")
    result = drive_dict(f, [x[0], x[1], wrap(x[2]), wrap(x[3])])
    result["drive.inspiratory_fraction"] = ti_ttot
    result.update(
        {
            "cost_m": final_cost,
            "initial_cost_m": history[0],
            "best_history_index": best,
            # Rigid registration: the mean distance between the registered first frame and the
            # rest markers. With slp.reference: the skin fitting's mean error before and after
            # against the rest-pose reference grid.
            "skin_fit_error_m": skin or {"before": registration_err, "after": registration_err,
                                         "skin_fitted": False},
            "evaluations": evaluations,
            "evaluations_ahead_unused": 0,
            "wall_s": time.perf_counter() - start,
            "delta_phase": wrap(x[3] - x[2]),
            "lung_volume_csv": str(csv),
            "method": "scipy-nelder-mead",
            "recording": str(args.slp),
        }
    )
    out.write_text(json.dumps(result, indent=2) + "\n")
    return result


def bench(args) -> int:
    """Native `torso fit` against this script's fit on the same recording and settings,
    alternating, `args.bench` times each: median wall and CPU time of each and their ratio.
    The native wall time is the fit's own (`wall_s`, excluding the process start); the CPU
    time of a native run is its child-process CPU time."""
    import resource
    import statistics
    import subprocess
    import tempfile

    rows = {"native": [], "fmpy": []}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.bench):
            out = Path(tmp) / f"native{i}.json"
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            cmd = [args.torso, "fit", "--slp", str(args.slp), "--out", str(out), "--sex", args.sex,
                   "--age", str(args.age), "--stature", str(args.stature), "--mass", str(args.mass),
                   "--breast-size", str(args.breast_size), "--posture", args.posture, "--lod", str(args.lod),
                   "--rtol", str(args.rtol), "--max-evals", str(args.max_evals), "--ti-ttot", str(args.ti_ttot)]
            run = subprocess.run(cmd, capture_output=True, text=True)
            if run.returncode != 0:
                print(run.stderr, file=sys.stderr)
                return 1
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            r = json.loads(out.read_text())
            rows["native"].append((r["wall_s"], after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime,
                                   r["evaluations"], r["cost_m"]))
            a = argparse.Namespace(**vars(args))
            a.out = str(Path(tmp) / f"fmpy{i}.json")
            c0 = time.process_time()
            r = fit(a)
            rows["fmpy"].append((r["wall_s"], time.process_time() - c0, r["evaluations"], r["cost_m"]))
            print(f"run {i + 1}: native {rows['native'][-1][0]:.2f} s wall, {rows['native'][-1][1]:.2f} s CPU, "
                  f"{rows['native'][-1][2]} evaluations; fmpy {rows['fmpy'][-1][0]:.2f} s wall, "
                  f"{rows['fmpy'][-1][1]:.2f} s CPU, {rows['fmpy'][-1][2]} evaluations", flush=True)
    med = {k: [statistics.median(x[j] for x in v) for j in range(4)] for k, v in rows.items()}
    for k, (w, c, e, cost) in med.items():
        print(f"{k:>6}: median wall {w:.2f} s, CPU {c:.2f} s, evaluations {e:.0f}, cost {cost * 1e3:.3f} mm, "
              f"CPU per evaluation {c / e:.3f} s")
    print(f"fmpy / native: wall {med['fmpy'][0] / med['native'][0]:.2f}x, CPU {med['fmpy'][1] / med['native'][1]:.2f}x, "
          f"CPU per evaluation {(med['fmpy'][1] / med['fmpy'][2]) / (med['native'][1] / med['native'][2]):.2f}x")
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fmu", default="fmu/BreathingTorso.fmu")
    p.add_argument("--slp", required=True)
    p.add_argument("--out", default="out/fit_fmpy/result.json")
    p.add_argument("--sex", default="male", choices=sorted(SEXES))
    p.add_argument("--age", type=float, default=30.0)
    p.add_argument("--stature", type=float, default=1.75)
    p.add_argument("--mass", type=float, default=75.0)
    p.add_argument("--breast-size", type=float, default=0.0)
    p.add_argument("--posture", default="standing", choices=sorted(POSTURES))
    p.add_argument("--lod", type=int, default=1)
    p.add_argument("--max-evals", type=int, default=120)
    p.add_argument("--rtol", type=float, default=1e-6,
                   help="solver.rtol of the FMU (the native fit's default: as accurate for fitting as tighter ones)")
    p.add_argument("--ti-ttot", default="0.5",
                   help="drive.inspiratory_fraction held by the search: a number in 0.2-0.8, or `auto`, the "
                        "median Ti/Ttot of the recording's breaths (as `torso fit --ti-ttot`)")
    p.add_argument("--units", choices=sorted(UNIT_SCALES),
                   help="length unit of a CSV of named markers that does not state it")
    p.add_argument("--rate", type=float, help="frame rate [Hz] of a CSV of named markers without a time column")
    p.add_argument("--slp-reference", action="store_true",
                   help="fit the FMU's skin to the rest-pose grid a first fit implies (slp.reference), "
                        "then polish, as `torso fit --skin-fit`")
    p.add_argument("--bench", type=int, default=0, metavar="N",
                   help="time N native fits (`--torso`) and N fmpy fits of the recording, alternating; print medians")
    p.add_argument("--torso", default="target/release/torso", help="the torso executable for --bench")
    args = p.parse_args(argv)
    if args.bench > 0:
        return bench(args)
    try:
        r = fit(args)
    except RecordingError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    print(json.dumps({k: r[k] for k in ("drive.frequency", "drive.ribs.amplitude", "drive.diaphragm.amplitude",
                                         "delta_phase", "cost_m", "evaluations", "wall_s")}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
