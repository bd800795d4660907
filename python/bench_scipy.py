"""Work-precision side by side: scipy's `solve_ivp` integrating the model's own right-hand side
through the C ABI, scored against the same reference as `torso bench work-precision`.

The Rust bench writes, next to its CSV, the reference solution's frames
(`work_precision_<scenario>_reference.csv`: DOP853 at rtol 1e-12; first line the scene as
`key=value` FMI parameter names) and the fixed-step semi-implicit Euler runs
(`work_precision_<scenario>_fixed.csv`). This script

1. loads the crate's cdylib (`target/release/libbreathing_torso.so`) with ctypes, builds the same
   scene (`bt_config_default`, then every parameter of the reference header by `bt_config_set`,
   then `bt_create`) and reads its rest state (`bt_get_state`);
2. integrates it with `solve_ivp` (RK45, DOP853, LSODA, BDF, Radau) for every rtol (atol =
   rtol / 100, as the Rust bench), `t_eval` at the 56 Hz frames, calling `bt_rhs` (the inputs are
   zero; the built-in drive is applied at each t by the library). BDF, Radau and LSODA form
   their Jacobians by scipy's own finite differences, dense: the abdominal pressure couples
   every abdominal vertex to every other (P depends on the whole cavity volume), so
   `jac_sparsity` would not help (`--sparsity` measures the fill);
3. reads lung volume and the markers off each output frame (`bt_set_state`, `bt_read_by_name`,
   `bt_read_markers`) and takes the max over frames of |lung error| and of the marker distance
   to the reference;
4. writes `work_precision_<scenario>_scipy.csv`, a combined plot with the Rust runs
   (`work_precision_<scenario>_combined.png`, matplotlib) and a matched-error table on stdout.

Wall time is that of `solve_ivp` alone (median of `--repeats` runs; runs over 5 s are not
repeated); a run over `--cap` seconds is abandoned (an exception raised from the right-hand
side) and the tighter tolerances of that method are skipped. RHS evaluations are counted at
the C call, so they include the finite-difference Jacobian columns; scipy's own `nfev`,
`njev` and `nlu` are recorded too.

    cargo build --release
    target/release/torso bench work-precision --scenario quiet --duration 4 --out out/bench
    .venv/bin/python python/bench_scipy.py --dir out/bench --scenario quiet

The script may start as soon as the reference file exists (the Rust bench writes it before its
sweep); `--plot-only` redraws the combined plot and tables once both have finished.

`--formulation quasi-static` does the same for the quasi-static mode (`solver.method` 4), whose
state is the lung volume alone: the reference is the library's own run at rtol 1e-10
(`work_precision_<scenario>_quasi_static_reference.csv`, from `torso bench work-precision
--formulation quasi-static`), scipy integrates the reduced right-hand side `bt_quasi_rate`
(one static equilibrium of the chest wall per call; a call whose equilibrium fails returns NaN,
which makes every method shorten its step, as the library's own integrator does), and the
markers of a frame are read off `bt_quasi_set_volume`. Each run gets a fresh handle built with
that `solver.rtol`, so that the static solves are converged as tightly as in the library's own
run at the same tolerance and start from the same state (the static solver warm-starts from the
handle's history; build time excluded from the wall time). The plot and
the matched-error tables compare solve_ivp's wall time with the library's runs reading the lung
volume alone (`wall_lung_only_s` of the Rust CSV): reading the markers solves one equilibrium
per frame on either side (`frames_s`, recorded apart).

    target/release/torso bench work-precision --formulation quasi-static --lod 1 --out out/bench
    .venv/bin/python python/bench_scipy.py --formulation quasi-static --dir out/bench --rtols 1e-3,1e-4,1e-5,1e-6,1e-7,1e-8,1e-9
"""

import argparse
import csv
import ctypes
import math
import pathlib
import statistics
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

ROOT = pathlib.Path(__file__).resolve().parents[1]
LIB = ROOT / "target" / "release" / "libbreathing_torso.so"
METHODS = ["RK45", "DOP853", "LSODA", "BDF", "Radau"]
RTOLS = [10.0**-k for k in range(3, 9)]
DOUBLE_P = ctypes.POINTER(ctypes.c_double)


class Wave(ctypes.Structure):
    _fields_ = [("amplitude", ctypes.c_double), ("phase", ctypes.c_double)]


class Drive(ctypes.Structure):
    _fields_ = [("frequency", ctypes.c_double), ("ribs", Wave), ("diaphragm", Wave), ("abdominals", Wave),
                ("enabled", ctypes.c_int), ("inspiratory_fraction", ctypes.c_double)]


class Subject(ctypes.Structure):
    _fields_ = [("sex", ctypes.c_int), ("age", ctypes.c_double), ("stature", ctypes.c_double),
                ("mass", ctypes.c_double), ("breast_size", ctypes.c_double), ("posture", ctypes.c_int)]


class Config(ctypes.Structure):
    """`BtConfig` of include/breathing_torso.h."""
    _fields_ = [("subject", Subject), ("level_of_detail", ctypes.c_int), ("grid_rows", ctypes.c_int),
                ("grid_cols", ctypes.c_int), ("slp_reference", ctypes.c_char_p), ("solver_method", ctypes.c_int),
                ("solver_rtol", ctypes.c_double), ("solver_atol", ctypes.c_double),
                ("solver_max_step", ctypes.c_double), ("drive", Drive), ("lung_ratio", ctypes.c_double),
                ("gain_left", ctypes.c_double), ("gain_right", ctypes.c_double),
                ("subject_mesh_dir", ctypes.c_char_p), ("group_gain_right", ctypes.c_double * 9),
                ("group_gain_left", ctypes.c_double * 9), ("muscle_law", ctypes.c_int),
                ("gravity", ctypes.c_double), ("gravity_loads", ctypes.c_int),
                ("postural_tone", ctypes.c_int)]


def load_library(path=LIB):
    """The cdylib with the signatures used here declared."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path} missing: build it with `cargo build --release`")
    lib = ctypes.CDLL(str(path))
    lib.bt_create.restype = ctypes.c_void_p
    lib.bt_create.argtypes = [ctypes.POINTER(Config)]
    lib.bt_destroy.argtypes = [ctypes.c_void_p]
    lib.bt_last_error.restype = ctypes.c_char_p
    lib.bt_last_error.argtypes = [ctypes.c_void_p]
    lib.bt_creation_error.restype = ctypes.c_char_p
    lib.bt_config_set.argtypes = [ctypes.POINTER(Config), ctypes.c_char_p, ctypes.c_double]
    lib.bt_state_dim.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_size_t)]
    lib.bt_get_state.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t]
    lib.bt_set_state.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_void_p, ctypes.c_size_t]
    lib.bt_rhs.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t]
    lib.bt_read_by_name.argtypes = [ctypes.c_void_p, ctypes.c_char_p, DOUBLE_P]
    lib.bt_read_markers.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t,
                                    ctypes.POINTER(ctypes.c_size_t)]
    lib.bt_advance_to.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_void_p]
    lib.bt_quasi_rate.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, DOUBLE_P]
    lib.bt_quasi_set_volume.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double]
    return lib


class OverCap(Exception):
    """Raised from the right-hand side when a run exceeds its wall-time cap."""


class Torso:
    """One model handle seen as y' = f(t, y) for scipy, plus reads of any state."""

    def __init__(self, lib, parameters):
        self.lib = lib
        c = Config()
        self._check(lib.bt_config_default(ctypes.byref(c)), None)
        for name, value in parameters.items():
            if lib.bt_config_set(ctypes.byref(c), name.encode(), float(value)) != 0:
                raise ValueError(lib.bt_creation_error().decode())
        self.config = c
        self.h = lib.bt_create(ctypes.byref(c))
        if not self.h:
            raise ValueError(lib.bt_creation_error().decode())
        n = ctypes.c_size_t()
        self._check(lib.bt_state_dim(self.h, ctypes.byref(n)))
        self.n = n.value
        self.markers_n = c.grid_rows * c.grid_cols
        self.y0 = self.state()  # the rest state (bt_set_state moves the model's own state later)
        self.calls = 0
        self.deadline = math.inf

    def _check(self, rc, h=-1):
        if rc != 0:
            msg = self.lib.bt_last_error(self.h if h == -1 else h).decode() if h is not None else ""
            raise RuntimeError(f"C ABI call failed ({rc}): {msg}")

    def close(self):
        if self.h:
            self.lib.bt_destroy(self.h)
            self.h = None

    def state(self):
        """The model's current state vector (the rest state after creation)."""
        y = np.empty(self.n)
        self._check(self.lib.bt_get_state(self.h, y.ctypes.data, self.n))
        return y

    def rhs(self, t, y):
        """f(t, y) through `bt_rhs` (a new array, as solve_ivp keeps references)."""
        if time.perf_counter() > self.deadline:
            raise OverCap()
        y = np.ascontiguousarray(y, dtype=np.float64)
        out = np.empty(self.n)
        rc = self.lib.bt_rhs(self.h, t, y.ctypes.data, out.ctypes.data, self.n)
        self.calls += 1
        if rc != 0:
            self._check(rc)
        return out

    def read_frame(self, t, y):
        """Lung volume [L] and markers [m] (m x 3) of state y at time t."""
        y = np.ascontiguousarray(y, dtype=np.float64)
        self._check(self.lib.bt_set_state(self.h, t, y.ctypes.data, self.n))
        v = ctypes.c_double()
        self._check(self.lib.bt_read_by_name(self.h, b"volume.lung", ctypes.byref(v)))
        xyz = np.empty(3 * self.markers_n)
        self._check(self.lib.bt_read_markers(self.h, xyz.ctypes.data, xyz.size, None))
        return v.value, xyz.reshape(-1, 3)


BT_ERR_NUMERICAL = -3


class QuasiTorso(Torso):
    """A quasi-static handle (`solver.method` 4) seen as V_L' = f(t, V_L) for scipy: the state is
    the lung volume [L] alone (`bt_quasi_rate`), and a frame is read off `bt_quasi_set_volume`."""

    def __init__(self, lib, parameters):
        super().__init__(lib, {**parameters, "solver.method": 4})
        self.n = 1
        self.failures = 0

    def state(self):
        """The model's current lung volume [L], as a 1-vector."""
        v = ctypes.c_double()
        self._check(self.lib.bt_read_by_name(self.h, b"volume.lung", ctypes.byref(v)))
        return np.array([v.value])

    def rhs(self, t, y):
        """dV_L/dt through `bt_quasi_rate`; NaN (a rejected step) when the equilibrium fails or a
        stage's volume is not a volume (after a NaN stage, or an excursion below zero)."""
        if time.perf_counter() > self.deadline:
            raise OverCap()
        if not (math.isfinite(y[0]) and y[0] > 0.0):
            self.failures += 1
            return np.array([math.nan])
        rate = ctypes.c_double()
        rc = self.lib.bt_quasi_rate(self.h, float(t), float(y[0]), ctypes.byref(rate))
        self.calls += 1
        if rc == BT_ERR_NUMERICAL:
            self.failures += 1
            return np.array([math.nan])
        if rc != 0:
            self._check(rc)
        return np.array([rate.value])

    def read_frame(self, t, y):
        """Lung volume [L] and markers [m] (m x 3) of lung volume y[0] at time t."""
        self._check(self.lib.bt_quasi_set_volume(self.h, float(t), float(y[0])))
        v = ctypes.c_double()
        self._check(self.lib.bt_read_by_name(self.h, b"volume.lung", ctypes.byref(v)))
        xyz = np.empty(3 * self.markers_n)
        self._check(self.lib.bt_read_markers(self.h, xyz.ctypes.data, xyz.size, None))
        return v.value, xyz.reshape(-1, 3)


def load_reference(path):
    """(scene dict, frame times, lung volumes, markers[frame, marker, 3]) of a reference CSV."""
    with open(path) as f:
        head = f.readline()
        if not head.startswith("#"):
            raise ValueError(f"{path}:1: expected the `# key=value ...` scene line")
        scene = dict(kv.split("=", 1) for kv in head[1:].split())
        data = np.loadtxt(f, delimiter=",", skiprows=1, ndmin=2)
    return scene, data[:, 0], data[:, 1], data[:, 2:].reshape(data.shape[0], -1, 3)


def scene_parameters(scene):
    """The FMI parameters of the scene line (names with a dot)."""
    return {k: float(v) for k, v in scene.items() if "." in k}


SETTLED = 0.5  # [s]: the errors are also reported from here on (as the Rust quasi-static sweep does)


def errors(torso, t_eval, ys, ref_lung, ref_markers):
    """Max over frames of |lung - reference| [L] and of the marker distance [m]; the same from
    SETTLED s on are kept in `errors.settled`."""
    lung_err = marker_err = late_lung = late_marker = 0.0
    for i, t in enumerate(t_eval):
        lung, markers = torso.read_frame(t, ys[:, i])
        dl = abs(lung - ref_lung[i])
        dm = float(np.max(np.linalg.norm(markers - ref_markers[i], axis=1)))
        lung_err, marker_err = max(lung_err, dl), max(marker_err, dm)
        if t >= SETTLED - 1e-9:
            late_lung, late_marker = max(late_lung, dl), max(late_marker, dm)
    errors.settled = (late_lung, late_marker)
    return lung_err, marker_err


def run_scipy(torso, method, rtol, t_eval, cap):
    """One solve_ivp run from the rest state: (wall, rhs calls, solution) or raises OverCap."""
    y0 = torso.y0.copy()
    torso.calls = 0
    start, cpu = time.perf_counter(), time.process_time()
    torso.deadline = start + cap
    try:
        sol = solve_ivp(torso.rhs, (0.0, t_eval[-1]), y0, method=method, t_eval=t_eval,
                        rtol=rtol, atol=rtol * 1e-2)
    finally:
        torso.deadline = math.inf
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    run_scipy.cpu = cpu
    return wall, torso.calls, sol


NATIVE = {"dopri5": 0, "bs3": 1, "high-order": 2, "quasi-static": 4}


def run_native(lib, parameters, method, rtol, t_eval, cap):
    """The library's own integrator through the C ABI in this process (`bt_advance_to` frame by
    frame, reading lung volume and markers every frame, as the Rust bench does): a row dict."""
    torso = Torso(lib, {**parameters, "solver.method": NATIVE[method], "solver.rtol": rtol,
                        "solver.atol": rtol * 1e-2})
    lung, markers, v = [], [], ctypes.c_double()
    xyz = np.empty(3 * torso.markers_n)
    try:
        # the marker model (skin and weights) is built on the first marker read, once per compiled
        # model; the Rust bench builds it before its clock starts too
        torso._check(lib.bt_read_markers(torso.h, xyz.ctypes.data, xyz.size, None))
        start, cpu = time.perf_counter(), time.process_time()
        for t in t_eval:
            if t > 0:
                torso._check(torso.lib.bt_advance_to(torso.h, t, None))
            torso._check(lib.bt_read_by_name(torso.h, b"volume.lung", ctypes.byref(v)))
            torso._check(lib.bt_read_markers(torso.h, xyz.ctypes.data, xyz.size, None))
            lung.append(v.value)
            markers.append(xyz.reshape(-1, 3).copy())
            if time.perf_counter() - start > cap:
                raise OverCap()
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
        torso._check(lib.bt_read_by_name(torso.h, b"solver.rhs_evaluations", ctypes.byref(v)))
        return wall, cpu, int(v.value), np.array(lung), np.array(markers)
    finally:
        torso.close()


def measure_native(lib, parameters, method, rtol, t_eval, ref_lung, ref_markers, repeats, cap):
    """A CSV row (dict) for the library's own method `method` at `rtol`, run from Python."""
    row = {"method": f"native-{method}", "rtol": rtol, "atol": rtol * 1e-2}
    walls, cpus = [], []
    for k in range(repeats):
        try:
            wall, cpu, calls, lung, markers = run_native(lib, parameters, method, rtol, t_eval, cap)
        except OverCap:
            row["status"] = f"skipped: over the {cap:g} s time cap"
            return row
        walls.append(wall)
        cpus.append(cpu)
        if wall > 5.0:
            break
    lung_err = float(np.max(np.abs(lung - ref_lung)))
    marker_err = float(np.max(np.linalg.norm(markers - ref_markers, axis=2)))
    row.update(status="ok", wall_s=statistics.median(walls), cpu_s=statistics.median(cpus), runs=len(walls),
               rhs_evaluations=calls, nfev=calls, njev=0, nlu=0, lung_error_l=lung_err,
               marker_error_m=marker_err)
    return row


def measure(torso, method, rtol, t_eval, ref_lung, ref_markers, repeats, cap):
    """A CSV row (dict) for one method and tolerance."""
    row = {"method": f"scipy-{method}", "rtol": rtol, "atol": rtol * 1e-2}
    walls, cpus = [], []
    for k in range(repeats):
        try:
            wall, calls, sol = run_scipy(torso, method, rtol, t_eval, cap)
        except OverCap:
            row["status"] = f"skipped: over the {cap:g} s time cap"
            return row
        except RuntimeError as e:  # a C ABI error (e.g. a NaN time after a failed first equilibrium)
            row["status"] = f"failed: {e}"
            return row
        if sol.status != 0:
            row["status"] = f"failed: {sol.message}"
            return row
        walls.append(wall)
        cpus.append(run_scipy.cpu)
        if wall > 5.0:
            break
    start = time.perf_counter()
    lung_err, marker_err = errors(torso, t_eval, sol.y, ref_lung, ref_markers)
    row["frames_s"] = time.perf_counter() - start
    row["lung_error_settled_l"], row["marker_error_settled_m"] = errors.settled
    row.update(status="ok", wall_s=statistics.median(walls), cpu_s=statistics.median(cpus), runs=len(walls),
               rhs_evaluations=calls,
               nfev=sol.nfev, njev=sol.njev, nlu=sol.nlu, lung_error_l=lung_err,
               marker_error_m=marker_err)
    return row


def measure_quasi(lib, parameters, method, rtol, t_eval, ref_lung, ref_markers, repeats, cap):
    """A CSV row (dict) for scipy's `method` on the reduced right-hand side at `rtol`: every repeat
    on a fresh handle built with that `solver.rtol` (the static solver's warm start is the
    handle's history, so a second run on the same handle would start from the first's end), the
    errors read off the last."""
    row = {"method": f"scipy-{method}", "rtol": rtol, "atol": rtol * 1e-2}
    walls, cpus, failures = [], [], 0
    for k in range(repeats):
        handle = QuasiTorso(lib, {**parameters, "solver.rtol": rtol, "solver.atol": rtol * 1e-2})
        try:
            try:
                wall, calls, sol = run_scipy(handle, method, rtol, t_eval, cap)
            except OverCap:
                row["status"] = f"skipped: over the {cap:g} s time cap"
                return row
            except (RuntimeError, ValueError) as e:  # a C ABI error; NaN in a Jacobian (BDF, Radau)
                row["status"] = f"failed: {e}"
                return row
            if sol.status != 0:
                row["status"] = f"failed: {sol.message}"
                return row
            if not np.all(np.isfinite(sol.y)):
                row["status"] = f"failed: non-finite lung volume ({handle.failures} failed right-hand sides)"
                return row
            walls.append(wall)
            cpus.append(run_scipy.cpu)
            failures = handle.failures
            if k == repeats - 1 or wall > 5.0:
                start = time.perf_counter()
                lung_err, marker_err = errors(handle, t_eval, sol.y, ref_lung, ref_markers)
                row["frames_s"] = time.perf_counter() - start
                row["lung_error_settled_l"], row["marker_error_settled_m"] = errors.settled
                break
        finally:
            handle.close()
    row.update(status="ok", wall_s=statistics.median(walls), cpu_s=statistics.median(cpus), runs=len(walls),
               rhs_evaluations=calls, nfev=sol.nfev, njev=sol.njev, nlu=sol.nlu, lung_error_l=lung_err,
               marker_error_m=marker_err, failed_rhs=failures)
    return row


def read_rows(path):
    """Rows of a CSV (comment lines dropped), or [] when the file is missing."""
    path = pathlib.Path(path)
    if not path.is_file():
        return []
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def series(rows, label_key="method"):
    """{label: [(wall, rhs, lung error, marker error, setting)]} of the rows that ran."""
    out = {}
    for r in rows:
        if r.get("status") != "ok":
            continue
        setting = r.get("rtol") or r.get("step_s")
        # the quasi-static bench's own runs: the wall time reading the lung volume alone, as
        # solve_ivp's is measured (the markers are read outside its clock)
        out.setdefault(r[label_key], []).append(
            (float(r.get("wall_lung_only_s") or r["wall_s"]), float(r["rhs_evaluations"]), float(r["lung_error_l"]),
             float(r["marker_error_m"]), setting, float(r.get("cpu_s") or "nan")))
    return out


def matched(all_series, target):
    """Per series, the fastest run (by CPU time where measured, else wall time) and the one with
    the fewest RHS evaluations among those whose lung error is at most `target` (None when none
    reaches it)."""
    table = {}
    for name, pts in all_series.items():
        ok = [p for p in pts if p[2] <= target]
        table[name] = (min(ok, key=lambda p: p[0] if math.isnan(p[5]) else p[5]) if ok else None,
                       min(ok, key=lambda p: p[1]) if ok else None,
                       min(p[2] for p in pts))
    return table


def plot(all_series, path, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(17, 5.5))
    for name, pts in sorted(all_series.items()):
        style = "--" if name.startswith("scipy") else ("-." if "euler" in name else "-")
        wall, rhs, lung, mark = (np.array([p[k] for p in pts]) for k in range(4))
        for ax, x, y in ((axes[0], wall, lung), (axes[1], rhs, lung), (axes[2], wall, mark)):
            ax.loglog(x, y, style, marker="o", ms=4, label=name)
    labels = [("wall time [s]", "max |lung volume error| [L]"),
              ("RHS evaluations", "max |lung volume error| [L]"),
              ("wall time [s]", "max marker error [m]")]
    for ax, (xl, yl) in zip(axes, labels):
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def jacobian_fill(torso, y, t=0.0):
    """Fraction of non-zero entries of the finite-difference Jacobian at (t, y)."""
    f0 = torso.rhs(t, y)
    nz = 0
    for j in range(torso.n):
        yp = y.copy()
        d = 1e-7 * max(1.0, abs(y[j]))
        yp[j] += d
        nz += int(np.count_nonzero(torso.rhs(t, yp) != f0))
    return nz / torso.n**2


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dir", default="out/bench", help="folder of the Rust bench's CSVs; outputs go here too")
    ap.add_argument("--scenario", default="quiet")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--native", default="dopri5",
                    help="the library's own methods to run from this process too, interleaved (empty: none)")
    ap.add_argument("--rtols", default=",".join(f"{r:g}" for r in RTOLS))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cap", type=float, default=60.0, help="wall-time cap of one run [s]")
    ap.add_argument("--lib", default=str(LIB))
    ap.add_argument("--targets", default="1e-5,1e-6", help="lung errors [L] of the matched-error table")
    ap.add_argument("--sparsity", action="store_true", help="measure the Jacobian's fill at the rest state")
    ap.add_argument("--plot-only", action="store_true",
                    help="run nothing: redraw the plot and tables from the CSVs already in --dir")
    ap.add_argument("--formulation", default="inertial", choices=["inertial", "quasi-static"],
                    help="quasi-static: scipy on the reduced right-hand side bt_quasi_rate, against the "
                         "quasi-static reference (--native defaults to none; quasi-static runs it from here)")
    args = ap.parse_args(argv)
    quasi = args.formulation == "quasi-static"
    if quasi and args.native == "dopri5":
        # the Rust bench's rows are the library's own runs, timed reading the lung volume alone
        args.native = ""
    suffix = "_quasi_static" if quasi else ""
    if args.plot_only:
        name = f"work_precision_{args.scenario}{suffix}"
        out = pathlib.Path(args.dir)
        with open(out / f"{name}_reference.csv") as f:
            scene = dict(kv.split("=", 1) for kv in f.readline()[1:].split())
        return report(out, name, args, scene, read_rows(out / f"{name}_scipy.csv"))

    out = pathlib.Path(args.dir)
    name = f"work_precision_{args.scenario}{suffix}"
    scene, t_eval, ref_lung, ref_markers = load_reference(out / f"{name}_reference.csv")
    lib = load_library(args.lib)
    torso = (QuasiTorso if quasi else Torso)(lib, scene_parameters(scene))
    print(f"{args.scenario} breathing, {scene['duration']} s, level of detail "
          f"{scene['scene.level_of_detail']}, state length {torso.n}, {len(t_eval)} frames; "
          f"reference {scene['method']} rtol {scene['rtol']} from {out / (name + '_reference.csv')}")
    if args.sparsity:
        print(f"finite-difference Jacobian fill at the rest state: {jacobian_fill(torso, torso.y0):.3f}")

    rows = []
    print(f"{'method':<13} {'rtol':>6} {'wall [s]':>9} {'cpu [s]':>8} {'RHS':>8} {'nfev':>8} {'njev':>5} {'nlu':>5} "
          f"{'lung [L]':>10} {'marker [m]':>10}")
    jobs = [("native", m) for m in args.native.split(",") if m] + [("scipy", m) for m in args.methods.split(",")]
    for kind, method in jobs:
        skip = None
        for rtol in (float(r) for r in args.rtols.split(",")):
            if skip:
                row = {"method": f"{kind}-{method}", "rtol": rtol, "atol": rtol * 1e-2, "status": skip}
            elif kind == "native":
                row = measure_native(lib, scene_parameters(scene), method, rtol, t_eval, ref_lung, ref_markers,
                                     args.repeats, args.cap)
            elif quasi:
                row = measure_quasi(lib, scene_parameters(scene), method, rtol, t_eval, ref_lung, ref_markers,
                                    args.repeats, args.cap)
                # a failure at one tolerance (the start's equilibrium at rtol 1e-3) says nothing of
                # the tighter ones; a run over the cap does
                if row["status"].startswith("skipped"):
                    skip = "skipped: a looser tolerance did not finish"
            else:
                row = measure(torso, method, rtol, t_eval, ref_lung, ref_markers, args.repeats, args.cap)
                if row["status"] != "ok":
                    skip = "skipped: a looser tolerance did not finish"
            rows.append(row)
            if row["status"] == "ok":
                print(f"{row['method']:<13} {rtol:>6.0e} {row['wall_s']:>9.3f} {row['cpu_s']:>8.3f} "
                      f"{row['rhs_evaluations']:>8} "
                      f"{row['nfev']:>8} {row['njev']:>5} {row['nlu']:>5} {row['lung_error_l']:>10.3e} "
                      f"{row['marker_error_m']:>10.3e}", flush=True)
            else:
                print(f"{row['method']:<13} {rtol:>6.0e} {row['status']}", flush=True)
    torso.close()

    return report(out, name, args, scene, rows)


def report(out, name, args, scene, rows):
    """Writes the scipy CSV, the combined plot and prints the matched-error tables."""
    fields = ["method", "rtol", "atol", "status", "wall_s", "cpu_s", "runs", "rhs_evaluations", "nfev", "njev", "nlu",
              "lung_error_l", "marker_error_m", "lung_error_settled_l", "marker_error_settled_m", "failed_rhs",
              "frames_s"]
    csv_path = out / f"{name}_scipy.csv"
    with open(csv_path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in fields})

    all_series = series(read_rows(out / f"{name}.csv"))
    all_series.update(series(read_rows(out / f"{name}_fixed.csv")))
    all_series.update(series([{**r, "rtol": f"{float(r['rtol']):g}"} for r in rows]))
    png = out / f"{name}_combined.png"
    if args.formulation == "quasi-static":
        title = (f"Work-precision, {args.scenario} breathing, quasi-static, level of detail "
                 f"{scene['scene.level_of_detail']}: our Dormand-Prince 5(4), scipy solve_ivp on the same "
                 f"reduced RHS (bt_quasi_rate)")
    else:
        title = (f"Work-precision, {args.scenario} breathing, level of detail "
                 f"{scene['scene.level_of_detail']}: our solvers, scipy solve_ivp on the same RHS "
                 f"(C ABI), semi-implicit Euler")
    plot(all_series, png, title)
    print(f"wrote {csv_path} and {png}")

    for target in (float(x) for x in args.targets.split(",")):
        table = matched(all_series, target)
        print(f"\nmatched error: lung-volume error <= {target:g} L")
        print(f"{'series':<20} {'fastest: setting':>17} {'wall [s]':>9} {'cpu [s]':>8} {'RHS':>9}   "
              f"{'fewest RHS: setting':>20} {'RHS':>9} {'wall [s]':>9}")
        for s_name, (fast, few, best) in sorted(table.items()):
            if fast is None:
                print(f"{s_name:<20} not reached (smallest error {best:.2e} L)")
                continue
            print(f"{s_name:<20} {fast[4]:>17} {fast[0]:>9.3f} {fast[5]:>8.3f} {fast[1]:>9.0f}   "
                  f"{few[4]:>20} {few[1]:>9.0f} "
                  f"{few[0]:>9.3f}")
        for base in ("dopri5", "native-dopri5", "quasi-static", "native-quasi-static"):
            ours = table.get(base, (None, None, None))
            if ours[0] is None:
                continue
            for ref in ("scipy-RK45", "scipy-DOP853", "scipy-LSODA", "scipy-BDF", "scipy-Radau"):
                other = table.get(ref, (None, None, None))
                if other[0] is not None:
                    cpu = other[0][5] / ours[0][5]
                    print(f"  {ref} / {base}: wall {other[0][0] / ours[0][0]:.1f}x"
                          + ("" if math.isnan(cpu) else f", cpu {cpu:.1f}x")
                          + f", RHS {other[1][1] / ours[1][1]:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
