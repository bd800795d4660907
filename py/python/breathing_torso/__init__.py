"""The breathing torso model in Python.

A physically based breathing human torso (rib cage, sternum, spine, respiratory muscles, an
incompressible abdomen, a skin carrying surface markers): simulate it, read and write marker
recordings, fit the model to a Structured Light Plethysmography (SLP) recording, validate a
simulated lung volume against spirometry, and find the FMI 2.0 / 3.0 FMUs shipped with the
package. The computations are the Rust library's (the same code as the ``torso`` command-line
tool), called through the extension module ``breathing_torso._native``; this module turns its
results into numpy arrays and, when pandas is installed, pandas tables.

Simulation and fits release the GIL, so Python threads (and Dask's threaded workers) run them
in parallel; Ctrl-C interrupts a fit at its next cost evaluation. Errors of the library are
raised as ``ValueError`` (a bad parameter or a malformed file, the message naming the file, row,
column, parameter and the allowed range), ``OSError`` (a file that cannot be read or written)
or :class:`TorsoError` (a failed solve, a state outside the physiological bounds).

See docs/python.md in the source repository for the whole API.
"""

from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._native import TorsoError

__all__ = [
    "Torso",
    "Recording",
    "read_recording",
    "write_recording",
    "fit",
    "validate",
    "breathing_frequency",
    "register",
    "fmu_path",
    "TorsoError",
    "MUSCLE_GROUPS",
    "__version__",
]

__version__: str = _native.version()

#: The muscle groups, in the order of the ``activation.<group>`` outputs.
MUSCLE_GROUPS: Tuple[str, ...] = tuple(
    c[len("activation."):] for c in _native.Torso.columns() if c.startswith("activation.")
)

PathLike = Union[str, "os.PathLike[str]"]


def _pandas():
    """The pandas module, or None when it is not installed."""
    try:
        import pandas
    except ImportError:
        return None
    return pandas


def _table(columns: Dict[str, np.ndarray], as_frame: Optional[bool]):
    """``columns`` as a pandas DataFrame when ``as_frame`` is true, or is None and pandas
    is installed; otherwise the dict itself."""
    if as_frame is False:
        return columns
    pd = _pandas()
    if pd is None:
        if as_frame:
            raise ImportError("as_frame=True needs pandas (pip install pandas)")
        return columns
    return pd.DataFrame(columns)


def _f64(data: bytes) -> np.ndarray:
    """float64 little-endian bytes as a writable numpy array."""
    return np.frombuffer(data, dtype="<f8").astype(np.float64)


def _f64_bytes(values: Any, what: str) -> bytes:
    """A float64 array's bytes (little-endian, C order); a ValueError names ``what`` when
    the values are not numbers."""
    try:
        return np.ascontiguousarray(values, dtype="<f8").tobytes()
    except (TypeError, ValueError) as e:
        raise ValueError(f"{what}: not an array of numbers ({e})") from None



def _flag(name: str, value) -> bool:
    """A switch given as a Python bool (numpy's bool too); anything else, a string such as
    "off" included, is refused by name rather than read by its truth value."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise ValueError(f"{value!r} for `{name}`: allowed range is True or False")

class Torso:
    """A breathing torso model, built for one subject, posture and level of detail.

    Args:
        subject: the subject's ``sex`` ("male" or "female"), ``age`` [years], ``stature``
            [m], ``mass`` [kg] and ``breast_size`` (0-1); missing keys take the defaults of
            ``torso simulate`` (male, 30 y, 1.75 m, 75 kg, 0).
        posture: "standing", "sitting" or "supine".
        lod: level of detail 0, 1 or 2 (None: 1).
        solver: the ODE solver: "dopri5", "bs3", "high-order", "rosenbrock" or
            "quasi-static".
        rtol: the solver's relative tolerance.
        scenario: the built-in breathing drive: "quiet", "forced" or "rest".
        drive: overrides of the drive: ``frequency`` [Hz], ``ti_ttot``,
            ``ribs_amplitude``, ``ribs_phase``, ``diaphragm_amplitude``,
            ``diaphragm_phase``, ``abdominals_amplitude``, ``abdominals_phase``.
        muscle_law: "thesis" (the seed thesis's shortening spring) or "hill" (passive and
            active parts, its passive wall fitted to the adult chest wall's compliance); the
            scenario's amplitudes are the ones calibrated for that law (``--muscle-law``).
        gravity: the gravitational acceleration [m/s^2], 0 to 3 x 9.81 (``--gravity``).
        gravity_loads: "preloaded" (each posture's generated anatomy is its rest, constant
            preloads cancelling gravity there; the default) or "acting" (the abdominal
            contents' hydrostatic pressure acts and each posture rests where the loads
            balance; ``--gravity-loads``, docs/dynamics.md).
        postural_tone: True (the default) applies the posture's tonic muscle activity:
            standing under the "hill" law the abdominal wall's tone, 0.017 of the maximal
            force (Cholewicki et al. 1997); False, none: a relaxed subject, as in a
            relaxation manoeuvre (``--postural-tone``).

    The same values give the model ``torso simulate`` builds from the same options, and
    :meth:`simulate` returns what it writes. Raises ValueError naming a bad value and its
    allowed range.
    """

    def __init__(
        self,
        subject: Optional[Mapping[str, Any]] = None,
        posture: str = "standing",
        lod: Optional[int] = None,
        solver: str = "dopri5",
        rtol: float = 1e-6,
        scenario: str = "quiet",
        drive: Optional[Mapping[str, float]] = None,
        muscle_law: str = "thesis",
        gravity: float = 9.81,
        gravity_loads: str = "preloaded",
        postural_tone: bool = True,
    ) -> None:
        self._native = _native.Torso(
            dict(subject) if subject is not None else None,
            posture,
            lod,
            solver,
            rtol,
            scenario,
            dict(drive) if drive is not None else None,
            muscle_law,
            float(gravity),
            gravity_loads,
            _flag("postural_tone", postural_tone),
        )

    @property
    def time(self) -> float:
        """The simulated time [s]."""
        return self._native.time

    @staticmethod
    def outputs() -> List[str]:
        """The names of every output :meth:`simulate` can return, in its column order."""
        return list(_native.Torso.columns())

    def simulate(
        self,
        duration: float,
        outputs: Optional[Sequence[str]] = None,
        activations: Optional[Mapping[str, Any]] = None,
        rate: float = 56.0,
        as_frame: Optional[bool] = None,
    ):
        """Runs the model for ``duration`` seconds from its current time.

        Args:
            duration: simulated time [s], in (0, 86400].
            outputs: the outputs to return (see :meth:`outputs`; ``time`` is always
                returned); None for all of them.
            activations: activation inputs per muscle group (see ``MUSCLE_GROUPS``), added
                to the drive: one value in [0, 1] held throughout, or one value per output
                interval (``round(duration * rate)`` values, each held over its interval).
                Inputs given to the first run of a new model start it at their equilibrium.
            rate: output rate [Hz] (SLP cameras: 56 Hz).
            as_frame: return a pandas DataFrame (None: when pandas is installed).

        Returns:
            ``round(duration * rate) + 1`` frames (the first at the current time): a dict of
            float64 arrays by output name, or a DataFrame with those columns. Volumes in
            litres, pressure in Pa, displacements in m. Ctrl-C raises KeyboardInterrupt
            within 64 frames, the model left at the last frame it reached.
        """
        names = self.outputs()
        if outputs is not None:
            unknown = [o for o in outputs if o not in names]
            if unknown:
                raise ValueError(
                    f"outputs: unknown {', '.join(map(repr, unknown))} (known: {', '.join(names)})"
                )
        inputs = None
        if activations is not None:
            inputs = []
            for name, values in activations.items():
                v = np.atleast_1d(np.asarray(values, dtype=np.float64)).ravel()
                inputs.append((str(name), v.tolist()))
        data = _f64(self._native.simulate(float(duration), float(rate), inputs))
        table = data.reshape(-1, len(names))
        keep = names if outputs is None else ["time"] + [o for o in outputs if o != "time"]
        columns = {n: table[:, names.index(n)].copy() for n in keep}
        return _table(columns, as_frame)

    def state(self) -> np.ndarray:
        """The state vector at the current time (positions, then velocities, then the
        lung-volume states; a copy)."""
        return _f64(self._native.state())

    def set_state(self, state: Any, time: Optional[float] = None) -> None:
        """Sets the state vector (``len(torso.state())`` finite values) and, when given, the
        time [s] (else the current time is kept); a later :meth:`simulate` continues from
        it. Raises ValueError when the length or a value is wrong; nothing changes then."""
        t = self.time if time is None else float(time)
        self._native.set_state(t, _f64_bytes(np.ravel(state), "state"))


@dataclass
class Recording:
    """A marker recording: named markers over time.

    Attributes:
        time: frame times [s], shape (frames,).
        labels: marker labels, one per column of ``positions``.
        positions: marker positions [m], shape (frames, markers, 3), NaN for a missing
            sample.
        units: the length unit of the file it was read from ("m", "cm" or "mm"), used again
            when it is written.
        format: "c3d", "trc", "grid-csv" or "marker-csv" (None for a new recording).
        provenance: how the recording was made, key by key, in file order.
    """

    time: np.ndarray
    labels: List[str]
    positions: np.ndarray
    units: str = "m"
    format: Optional[str] = None
    provenance: Dict[str, str] = field(default_factory=dict)

    @property
    def rate(self) -> float:
        """The mean frame rate [Hz]."""
        if len(self.time) < 2:
            return float("nan")
        return (len(self.time) - 1) / float(self.time[-1] - self.time[0])


def read_recording(
    path: PathLike, units: Optional[str] = None, rate: Optional[float] = None
) -> Recording:
    """Reads a marker recording: ``.c3d``, ``.trc`` (OpenSim), the SLP grid CSV or a CSV of
    named markers (every format ``torso inspect`` reads).

    Args:
        path: the file; its extension names the format.
        units: length unit of a CSV of named markers without a ``# units:`` line: "mm",
            "cm" or "m".
        rate: frame rate [Hz] of a CSV of named markers without a time column.

    Returns:
        a :class:`Recording`, positions in metres. Raises ValueError (naming the file, row
        and column) for a malformed file, OSError when it cannot be read.
    """
    times, labels, positions, file_units, fmt, provenance = _native.read_recording(
        os.fspath(path), units, rate
    )
    t = _f64(times)
    return Recording(
        time=t,
        labels=list(labels),
        positions=_f64(positions).reshape(len(t), len(labels), 3),
        units=file_units,
        format=fmt,
        provenance=dict(provenance),
    )


def write_recording(path: PathLike, recording: Recording) -> None:
    """Writes ``recording`` in the format the extension of ``path`` names (``.c3d``,
    ``.trc`` or ``.csv``: the grid CSV when the labels are a grid's, named markers
    otherwise), in ``recording.units``; NaN positions are written as missing samples."""
    time = np.asarray(recording.time, dtype=np.float64)
    positions = np.asarray(recording.positions, dtype=np.float64)
    labels = [str(label) for label in recording.labels]
    if positions.shape != (len(time), len(labels), 3):
        raise ValueError(
            f"positions: shape {positions.shape}, expected (frames, markers, 3) = "
            f"({len(time)}, {len(labels)}, 3)"
        )
    _native.write_recording(
        os.fspath(path),
        _f64_bytes(time, "time"),
        labels,
        _f64_bytes(positions, "positions"),
        recording.units,
        [(str(k), str(v)) for k, v in recording.provenance.items()],
    )


def _read_csv_columns(path: Path) -> Dict[str, np.ndarray]:
    """A numeric CSV with one header line as arrays by column name."""
    with open(path, encoding="utf-8") as f:
        header = f.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {name: data[:, k].copy() for k, name in enumerate(header)}


def fit(
    recording: Union[PathLike, Recording],
    out: Optional[PathLike] = None,
    *,
    subject: Optional[Mapping[str, Any]] = None,
    posture: str = "standing",
    lod: Optional[int] = None,
    solver: str = "dopri5",
    rtol: float = 1e-6,
    grid: str = "10x6",
    units: Optional[str] = None,
    rate: Optional[float] = None,
    method: str = "nelder-mead",
    max_evals: int = 120,
    seed: int = 1,
    threads: Optional[int] = None,
    skin_fit: bool = False,
    marker_offsets: bool = False,
    fit_size: Optional[bool] = None,
    drift: bool = True,
    sway: bool = True,
    reference: Sequence[str] = (),
    marker_radius: float = 0.0,
    anterior: Sequence[str] = (),
    ti_ttot: Optional[float] = 0.5,
    progress: Optional[Callable[[int, float], Any]] = None,
    as_frame: Optional[bool] = None,
    muscle_law: str = "thesis",
    gravity: float = 9.81,
    gravity_loads: str = "preloaded",
    postural_tone: bool = True,
) -> Dict[str, Any]:
    """Fits the model to a marker recording, as ``torso fit`` does (registration, frequency,
    the drive's amplitudes and phases; docs/fit_report.md).

    Args:
        recording: a recording file (any format :func:`read_recording` reads) or a
            :class:`Recording`.
        out: the result JSON to write (its folder is created), with ``<stem>_lung_volume.csv`` and the report
            figure beside it; None writes them to a temporary folder removed afterwards.
        subject, posture, lod, solver, rtol, muscle_law, gravity, gravity_loads,
            postural_tone: the model, as for :class:`Torso`; with no
            ``stature`` or ``mass`` in ``subject`` the size is estimated from the recording
            (``torso fit``'s rule).
        grid: the model's marker grid "ROWSxCOLS".
        units, rate: as for :func:`read_recording`.
        method: "nelder-mead", "multistart" or "cmaes".
        max_evals: the largest number of cost evaluations.
        seed: seed of the randomised methods.
        threads: 1 or 2 threads for the Nelder-Mead search (None: 2 on a machine with two
            cores or more).
        skin_fit, marker_offsets, anterior: as ``--skin-fit``, ``--marker-offsets``,
            ``--anterior``.
        fit_size: True estimates the subject's size, False never does, None follows
            ``torso fit``'s rule.
        drift: remove each marker's slow drift when markers are compared about their means
            (False: ``--no-drift``).
        sway: remove the trunk's sway, estimated from the markers over the back, from a
            named set (False: ``--no-sway``); ``reference`` names the markers to take it
            from instead (``--reference``).
        marker_radius: the markers' distance from the skin [mm] (``--marker-radius``).
        ti_ttot: the drive's inspiratory fraction held by the search, or None for the
            recording's median (``--ti-ttot auto``).
        progress: called as ``progress(evaluations, best_cost_m)`` at every evaluation the
            search reports; an exception it raises ends the fit and is raised again.
        as_frame: per-breath tables and the lung volume as DataFrames (None: when pandas is
            installed).

    Returns:
        the result JSON ``torso fit`` writes, as a dict, with ``breaths`` (the fitted model's
        breaths, one row each) as a table, and ``lung_volume``: the fitted lung volume and
        the displaced volumes over the recording's frames (the CSV beside the JSON). A
        KeyboardInterrupt (Ctrl-C) stops the fit at its next evaluation.
    """
    with tempfile.TemporaryDirectory(prefix="breathing_torso_fit_") as tmp:
        if isinstance(recording, Recording):
            path = Path(tmp) / "recording.csv"
            write_recording(path, recording)
        else:
            path = Path(os.fspath(recording))
        json_path = Path(os.fspath(out)) if out is not None else Path(tmp) / "fit" / "result.json"
        json_path.parent.mkdir(parents=True, exist_ok=True)
        written = _native.fit(
            os.fspath(path),
            os.fspath(json_path),
            dict(subject) if subject is not None else None,
            posture,
            lod,
            solver,
            rtol,
            grid,
            units,
            rate,
            method,
            int(max_evals),
            int(seed),
            threads,
            bool(skin_fit),
            bool(marker_offsets),
            fit_size,
            bool(drift),
            bool(sway),
            [str(r) for r in reference],
            float(marker_radius),
            [str(a) for a in anterior],
            ti_ttot,
            progress,
            muscle_law,
            float(gravity),
            gravity_loads,
            _flag("postural_tone", postural_tone),
        )
        with open(written, encoding="utf-8") as f:
            result: Dict[str, Any] = json.load(f)
        csv = json_path.with_name(json_path.stem + "_lung_volume.csv")
        result["lung_volume"] = _table(_read_csv_columns(csv), as_frame)
    breaths = result.get("breaths") or []
    columns = sorted({k for b in breaths for k in b})
    result["breaths"] = _table(
        {c: np.array([b.get(c, np.nan) for b in breaths], dtype=np.float64) for c in columns},
        as_frame,
    )
    return result


def validate(
    sim: Any,
    spiro: Any,
    out: Optional[PathLike] = None,
    *,
    sim_column: Optional[str] = None,
    spiro_kind: str = "volume",
    lung_ratio: Optional[float] = None,
    max_lag: int = 100,
    harmonics: int = 4,
    bootstrap: int = 399,
    max_ar_order: int = 8,
    seed: int = 1,
    bars_iterations: int = 2200,
    detrend: bool = False,
) -> Dict[str, Any]:
    """Compares a simulated lung volume with a spirogram, as ``torso validate`` does
    (alignment, agreement, cosinor, BARS; docs/validation.md).

    Args:
        sim: a simulation CSV path (``time`` and ``volume.lung``, or ``sim_column``), the
            dict or DataFrame :meth:`Torso.simulate` returns, or a ``(time, volume)`` pair
            [s, L].
        spiro: a spirometry CSV path (``time`` and ``volume`` [L] or ``flow`` [L/s]), or a
            ``(time, values)`` pair of the kind ``spiro_kind`` ("volume" or "flow").
        out: a folder to write every output into (``validation.json``, the aligned CSV,
            plots, summary), or None.
        the rest: the options of ``torso validate`` of the same names.

    Returns:
        the statistics ``torso validate`` writes to ``validation.json``, as a dict.
    """
    sim_path = spiro_path = None
    sim_arrays = spiro_arrays = None
    if isinstance(sim, (str, os.PathLike)):
        sim_path = os.fspath(sim)
    else:
        if isinstance(sim, tuple):
            t, v = sim
        else:
            t, v = sim["time"], sim[sim_column or "volume.lung"]
        sim_arrays = (_f64_bytes(t, "sim time"), _f64_bytes(v, "sim values"))
    if isinstance(spiro, (str, os.PathLike)):
        spiro_path = os.fspath(spiro)
    else:
        t, v = spiro
        spiro_arrays = (_f64_bytes(t, "spiro time"), _f64_bytes(v, "spiro values"), spiro_kind)
    text = _native.validate(
        sim_path,
        sim_arrays,
        spiro_path,
        spiro_arrays,
        None if out is None else os.fspath(out),
        sim_column,
        lung_ratio,
        int(max_lag),
        int(harmonics),
        int(bootstrap),
        int(max_ar_order),
        int(seed),
        int(bars_iterations),
        bool(detrend),
    )
    return json.loads(text)


def breathing_frequency(time: Any, positions: Any) -> Dict[str, Any]:
    """The breathing frequency of a marker recording as ``torso fit`` estimates it.

    The principal displacement is the projection of the gap-filled (linear in time), linearly
    detrended trajectories on their first principal axis; its frequency comes from a
    Hann-windowed DFT with two-bin interpolation, cross-checked by the autocorrelation.

    Args:
        time: frame times [s], shape (frames,).
        positions: marker positions [m], shape (frames, points, 3), NaN where missing.

    Returns:
        ``frequency_hz``; ``signal`` (frames,), the principal displacement [m];
        ``loadings`` (points, 3), each point's share of the principal axis; ``explained``,
        the fraction of the detrended variance on the axis.
    """
    t = np.asarray(time, dtype=np.float64)
    p = np.asarray(positions, dtype=np.float64)
    if p.ndim != 3 or p.shape[0] != len(t) or p.shape[2] != 3:
        raise ValueError(f"positions: shape {p.shape}, expected (frames, points, 3) with {len(t)} frames")
    f, signal, loadings, explained = _native.breathing_frequency(
        _f64_bytes(t, "time"), _f64_bytes(p, "positions"), p.shape[1]
    )
    return {
        "frequency_hz": f,
        "signal": _f64(signal),
        "loadings": _f64(loadings).reshape(-1, 3),
        "explained": explained,
    }


def register(model: Any, recorded: Any, with_scale: bool = False) -> Dict[str, Any]:
    """The least-squares rigid transform (with ``with_scale``, similarity) that maps the
    ``recorded`` points onto the ``model`` points (Umeyama 1991), as ``torso fit`` registers
    a frame to the model's grid.

    Args:
        model: points (n, 3) [m].
        recorded: the same points as recorded (n, 3), NaN rows for untracked points (at
            least three tracked).

    Returns:
        ``rotation`` (3, 3), ``translation`` (3,), ``scale`` and ``rms_m``, the
        root-mean-square residual: ``model ~ scale * recorded @ rotation.T + translation``.
    """
    m = np.asarray(model, dtype=np.float64)
    r = np.asarray(recorded, dtype=np.float64)
    if m.ndim != 2 or m.shape[1] != 3 or r.shape != m.shape:
        raise ValueError(f"model and recorded: shapes {m.shape} and {r.shape}, expected the same (n, 3)")
    rotation, translation, scale, rms = _native.register(
        _f64_bytes(m, "model"), _f64_bytes(r, "recorded"), bool(with_scale)
    )
    return {
        "rotation": _f64(rotation).reshape(3, 3),
        "translation": np.array(translation, dtype=np.float64),
        "scale": scale,
        "rms_m": rms,
    }


def fmu_path(fmi_version: int = 2) -> str:
    """The path of the FMU shipped inside the package: the FMI 2.0 co-simulation FMU
    (``fmi_version=2``) or the FMI 3.0 one (``3``), with linux64 and, where the wheel was
    built with the win64 toolchain, win64 binaries. ``fmpy.simulate_fmu(fmu_path(), ...)``
    runs it. Raises ValueError for another version, FileNotFoundError when this
    installation carries no FMU (a build without ``scripts/build-wheel.sh``)."""
    names = {2: "BreathingTorso.fmu", 3: "BreathingTorso3.fmu"}
    if fmi_version not in names:
        raise ValueError(f"fmi_version: {fmi_version!r}, allowed 2 or 3")
    path = Path(__file__).resolve().parent / "fmu" / names[fmi_version]
    if not path.is_file():
        raise FileNotFoundError(
            f"{path}: this installation carries no FMU (build the wheel with scripts/build-wheel.sh)"
        )
    return str(path)
