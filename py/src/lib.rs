//! `breathing_torso._native`: the Python extension module, a thin binding over the crate
//! `breathing-torso`. It owns only the conversion between Python values and the crate's
//! types: the model ([`Torso`]), the recording readers and writers, the fit and the
//! spirometry validation are the crate's, called as the command-line tool calls them, so the
//! package returns what `torso simulate`, `torso fit` and `torso validate` write. The pure
//! Python layer (`python/breathing_torso/__init__.py`) turns the flat buffers returned here
//! into numpy arrays and pandas tables.
//!
//! Arrays cross the boundary as `bytes` of little-endian f64 (numpy reads them without a
//! copy), so the binding needs no numpy headers. Errors become Python exceptions carrying the
//! crate's message ([`to_py`]). Simulation and fits run with the GIL released; a fit checks
//! for Ctrl-C (and calls the user's progress callback) at every cost evaluation it reports, a
//! simulation every 64 output frames.

use breathing_torso::cli::common::{DriveArgs, SolverArgs, SubjectArgs};
use breathing_torso::cli::fit::{FitFlags, ModelArgs, default_threads};
use breathing_torso::fit::{FitOptions, Method, PoseOptions};
use breathing_torso::model::run::{Frame, frame};
use breathing_torso::model::{AdvanceOptions, Drive};
use breathing_torso::recording::{Format, Markers, ReadOptions, Units};
use breathing_torso::stats::io::Series;
use breathing_torso::stats::prepare::SpiroKind;
use breathing_torso::{Error, anatomy::MuscleGroup};
use nalgebra::Point3;
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::path::PathBuf;

create_exception!(
    breathing_torso,
    TorsoError,
    PyException,
    "An error of the breathing torso library (a failed solve, a state outside the physiological bounds, a file that cannot be read); its message is the library's."
);

/// The crate's error as a Python exception: a bad parameter or a malformed file is a
/// `ValueError`, a file that cannot be read or written an `OSError`, anything else a
/// [`TorsoError`]; the message is the crate's (file, row, column, variable, allowed range).
fn to_py(e: Error) -> PyErr {
    let message = python_names(&e.to_string());
    match e {
        Error::InvalidParameter { .. } | Error::Parse { .. } => PyValueError::new_err(message),
        Error::Io { .. } => PyOSError::new_err(message),
        _ => TorsoError::new_err(message),
    }
}

/// `text` with the command-line flags the shared option parsers name (`--stature`,
/// `--breast-size`) written as the Python keywords that set them (`stature`, `breast_size`).
fn python_names(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = rest.find("--") {
        let (before, flag) = rest.split_at(at);
        out.push_str(before);
        let name_len = flag[2..]
            .find(|c: char| !(c.is_ascii_lowercase() || c == '-'))
            .unwrap_or(flag.len() - 2);
        if name_len == 0 {
            out.push_str("--");
        } else {
            out.push_str(&flag[2..2 + name_len].replace('-', "_"));
        }
        rest = &flag[2 + name_len..];
    }
    out.push_str(rest);
    out
}

/// `values` as little-endian f64 bytes.
fn f64_bytes<'py>(py: Python<'py>, values: &[f64]) -> Bound<'py, PyBytes> {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    PyBytes::new(py, &bytes)
}

/// Little-endian f64 bytes as values; an error naming `what` when the length is not a
/// multiple of 8.
fn from_f64_bytes(bytes: &[u8], what: &str) -> PyResult<Vec<f64>> {
    if !bytes.len().is_multiple_of(8) {
        return Err(PyValueError::new_err(format!(
            "{what}: {} bytes is not a whole number of float64 values",
            bytes.len()
        )));
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect())
}

/// The subject, posture, level of detail, solver and drive of a model, parsed by the
/// command-line tool's own option types so that a model built here is the one `torso
/// simulate` and `torso fit` build from the same values.
#[derive(Clone, Debug)]
struct Scene {
    subject: SubjectArgs,
    solver: SolverArgs,
    drive: DriveArgs,
}

/// Reads the keys of `dict` into `set`, each key once; an unknown key is a `ValueError`
/// listing the known ones.
fn dict_items(
    dict: Option<&Bound<'_, PyDict>>,
    what: &str,
    known: &[&str],
    mut set: impl FnMut(&str, &Bound<'_, PyAny>) -> PyResult<()>,
) -> PyResult<()> {
    let Some(dict) = dict else { return Ok(()) };
    for (k, v) in dict.iter() {
        let key: String = k.extract()?;
        if !known.contains(&key.as_str()) {
            return Err(PyValueError::new_err(format!(
                "{what}: unknown key `{key}` (known: {})",
                known.join(", ")
            )));
        }
        set(&key, &v)?;
    }
    Ok(())
}

const SUBJECT_KEYS: [&str; 5] = ["sex", "age", "stature", "mass", "breast_size"];
const DRIVE_KEYS: [&str; 8] = [
    "frequency",
    "ti_ttot",
    "ribs_amplitude",
    "ribs_phase",
    "diaphragm_amplitude",
    "diaphragm_phase",
    "abdominals_amplitude",
    "abdominals_phase",
];

/// The model's laws as the keywords name them: the muscle law, the gravitational
/// acceleration [m/s^2], how gravity loads the model and whether the posture's tone is
/// applied (`--muscle-law`, `--gravity`, `--gravity-loads`, `--postural-tone`).
struct Laws<'a> {
    muscle_law: &'a str,
    gravity: f64,
    gravity_loads: &'a str,
    postural_tone: bool,
}

impl Scene {
    #[allow(clippy::too_many_arguments)]
    fn new(
        subject: Option<&Bound<'_, PyDict>>,
        posture: &str,
        lod: Option<u32>,
        solver: &str,
        rtol: f64,
        scenario: &str,
        drive: Option<&Bound<'_, PyDict>>,
        laws: &Laws<'_>,
    ) -> PyResult<Scene> {
        let mut s = SubjectArgs {
            sex: "male".into(),
            age: 30.0,
            stature: None,
            mass: None,
            breast_size: 0.0,
            posture: posture.into(),
            lod,
            muscle_law: laws.muscle_law.into(),
            gravity: laws.gravity,
            gravity_loads: laws.gravity_loads.into(),
            postural_tone: if laws.postural_tone { "on" } else { "off" }.into(),
        };
        dict_items(subject, "subject", &SUBJECT_KEYS, |k, v| {
            match k {
                "sex" => s.sex = v.extract()?,
                "age" => s.age = v.extract()?,
                "stature" => s.stature = Some(v.extract()?),
                "mass" => s.mass = Some(v.extract()?),
                _ => s.breast_size = v.extract()?,
            }
            Ok(())
        })?;
        let mut d = DriveArgs {
            scenario: scenario.into(),
            frequency: None,
            ti_ttot: None,
            ribs_amplitude: None,
            ribs_phase: None,
            diaphragm_amplitude: None,
            diaphragm_phase: None,
            abdominals_amplitude: None,
            abdominals_phase: None,
        };
        dict_items(drive, "drive", &DRIVE_KEYS, |k, v| {
            let x: f64 = v.extract()?;
            *match k {
                "frequency" => &mut d.frequency,
                "ti_ttot" => &mut d.ti_ttot,
                "ribs_amplitude" => &mut d.ribs_amplitude,
                "ribs_phase" => &mut d.ribs_phase,
                "diaphragm_amplitude" => &mut d.diaphragm_amplitude,
                "diaphragm_phase" => &mut d.diaphragm_phase,
                "abdominals_amplitude" => &mut d.abdominals_amplitude,
                _ => &mut d.abdominals_phase,
            } = Some(x);
            Ok(())
        })?;
        Ok(Scene {
            subject: s,
            solver: SolverArgs {
                solver: solver.into(),
                rtol,
            },
            drive: d,
        })
    }

    fn config(&self) -> PyResult<breathing_torso::Config> {
        let law = self.subject.law().map_err(to_py)?;
        let drive: Drive = self.drive.drive(law).map_err(to_py)?;
        self.subject.config(&self.solver, drive).map_err(to_py)
    }
}

/// The columns of a simulation, as `torso simulate` writes them.
fn frame_columns() -> Vec<String> {
    breathing_torso::cli::simulate::frame_columns()
}

/// One frame's values in [`frame_columns`] order.
fn frame_row(f: &Frame, row: &mut Vec<f64>) {
    breathing_torso::cli::simulate::frame_values(f, row);
}

/// The muscle group named `name` (`diaphragm`, `external_intercostals`, ...).
fn group(name: &str) -> PyResult<MuscleGroup> {
    MuscleGroup::ALL
        .into_iter()
        .find(|g| g.name() == name)
        .ok_or_else(|| {
            PyValueError::new_err(format!(
                "activations: unknown muscle group `{name}` (known: {})",
                MuscleGroup::ALL.map(|g| g.name()).join(", ")
            ))
        })
}

/// Why a simulation stopped early: the library's error, or a Python exception (Ctrl-C).
enum Stop {
    Library(Error),
    Python(PyErr),
}

impl From<Error> for Stop {
    fn from(e: Error) -> Stop {
        Stop::Library(e)
    }
}

/// The breathing torso model (see the Python class `breathing_torso.Torso`).
#[pyclass(module = "breathing_torso._native")]
struct Torso {
    torso: breathing_torso::Torso,
    /// Not advanced or set since it was built: inputs given to the first `simulate` then
    /// move the start to their equilibrium, as the FMU's initialisation does.
    fresh: bool,
}

#[pymethods]
impl Torso {
    #[new]
    #[pyo3(signature = (subject=None, posture="standing", lod=None, solver="dopri5", rtol=1e-6, scenario="quiet", drive=None, muscle_law="thesis", gravity=9.81, gravity_loads="preloaded", postural_tone=true))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        subject: Option<&Bound<'_, PyDict>>,
        posture: &str,
        lod: Option<u32>,
        solver: &str,
        rtol: f64,
        scenario: &str,
        drive: Option<&Bound<'_, PyDict>>,
        muscle_law: &str,
        gravity: f64,
        gravity_loads: &str,
        postural_tone: bool,
    ) -> PyResult<Torso> {
        let laws = Laws {
            muscle_law,
            gravity,
            gravity_loads,
            postural_tone,
        };
        let config =
            Scene::new(subject, posture, lod, solver, rtol, scenario, drive, &laws)?.config()?;
        let torso = py
            .detach(|| breathing_torso::Torso::new(config))
            .map_err(to_py)?;
        Ok(Torso { torso, fresh: true })
    }

    /// Simulated time [s].
    #[getter]
    fn time(&self) -> f64 {
        self.torso.time()
    }

    /// The names of the columns `simulate` returns, in order.
    #[staticmethod]
    fn columns() -> Vec<String> {
        frame_columns()
    }

    /// Runs `duration` seconds, a frame every 1/`rate` s (the first at the current time).
    /// `activations`: (group, values) pairs, each one value held throughout or one per
    /// output interval. Returns the frames as row-major f64 bytes in `columns()` order.
    #[pyo3(signature = (duration, rate=56.0, activations=None))]
    fn simulate<'py>(
        &mut self,
        py: Python<'py>,
        duration: f64,
        rate: f64,
        activations: Option<Vec<(String, Vec<f64>)>>,
    ) -> PyResult<Bound<'py, PyBytes>> {
        if !(duration > 0.0 && duration <= 86_400.0) {
            return Err(to_py(Error::invalid("duration", duration, "(0, 86400] s")));
        }
        if !(rate > 0.0 && rate <= 10_000.0) {
            return Err(to_py(Error::invalid("rate", rate, "(0, 10000] Hz")));
        }
        let n = (duration * rate).round() as usize;
        let mut inputs = Vec::new();
        for (name, values) in activations.unwrap_or_default() {
            let g = group(&name)?;
            if values.len() != 1 && values.len() != n {
                return Err(PyValueError::new_err(format!(
                    "activations[{name:?}]: {} values; give one, or one per output interval ({n} for {duration} s at {rate} Hz)",
                    values.len()
                )));
            }
            if let Some(bad) = values.iter().find(|v| !(0.0..=1.0).contains(*v)) {
                return Err(to_py(Error::invalid(
                    format!("activations[{name:?}]"),
                    bad,
                    "[0, 1]",
                )));
            }
            inputs.push((g, values));
        }
        let fresh = self.fresh;
        let torso = &mut self.torso;
        // The frame loop of `model::run::run` (what `torso simulate` runs), with the inputs
        // set before each interval and a check for Ctrl-C every 64 frames.
        let rows = py.detach(move || -> Result<Vec<f64>, Stop> {
            let mut rows = Vec::with_capacity((n + 1) * 20);
            let set = |torso: &mut breathing_torso::Torso, i: usize| {
                for (g, v) in &inputs {
                    torso.set_activation(*g, v[i.min(v.len() - 1)])?;
                }
                Ok::<(), Error>(())
            };
            if !inputs.is_empty() {
                set(torso, 0)?;
                if fresh {
                    torso.start_at_equilibrium();
                }
            }
            let t0 = torso.time();
            let options = AdvanceOptions {
                check_physiology: true,
            };
            frame_row(&frame(torso)?, &mut rows);
            for i in 1..=n {
                set(torso, i - 1)?;
                torso.advance_to_with(t0 + i as f64 / rate, options)?;
                frame_row(&frame(torso)?, &mut rows);
                if i % 64 == 0 {
                    Python::attach(|py| py.check_signals()).map_err(Stop::Python)?;
                }
            }
            Ok(rows)
        });
        self.fresh = false;
        match rows {
            Ok(rows) => Ok(f64_bytes(py, &rows)),
            Err(Stop::Library(e)) => Err(to_py(e)),
            Err(Stop::Python(e)) => Err(e),
        }
    }

    /// The state vector at the current time, as f64 bytes.
    fn state<'py>(&mut self, py: Python<'py>) -> Bound<'py, PyBytes> {
        f64_bytes(py, self.torso.current_state())
    }

    /// Sets the time and the state vector (f64 bytes of `state_dim` values).
    fn set_state(&mut self, time: f64, state: &[u8]) -> PyResult<()> {
        let y = from_f64_bytes(state, "state")?;
        self.torso.set_state(time, &y).map_err(to_py)?;
        self.fresh = false;
        Ok(())
    }

    /// Length of the state vector.
    fn state_dim(&self) -> usize {
        self.torso.state_dim()
    }
}

/// The reader's options from the Python keywords.
fn read_options(units: Option<&str>, rate: Option<f64>) -> PyResult<ReadOptions> {
    let units = units
        .map(|u| Units::parse(u).ok_or_else(|| to_py(Error::invalid("units", u, "mm, cm or m"))))
        .transpose()?;
    if let Some(r) = rate
        && !(r.is_finite() && r > 0.0)
    {
        return Err(to_py(Error::invalid("rate", r, "a frame rate in Hz > 0")));
    }
    Ok(ReadOptions { units, rate })
}

/// What `read_recording` returns: times, labels, positions (frames x markers x 3, NaN for a
/// missing sample, metres), the file's unit, its format and the provenance pairs.
type RecordingParts<'py> = (
    Bound<'py, PyBytes>,
    Vec<String>,
    Bound<'py, PyBytes>,
    &'static str,
    &'static str,
    Vec<(String, String)>,
);

/// Reads a marker recording (.c3d, .trc, the grid CSV or a CSV of named markers).
#[pyfunction]
#[pyo3(signature = (path, units=None, rate=None))]
fn read_recording<'py>(
    py: Python<'py>,
    path: PathBuf,
    units: Option<&str>,
    rate: Option<f64>,
) -> PyResult<RecordingParts<'py>> {
    let options = read_options(units, rate)?;
    let m = py
        .detach(|| Markers::read(&path, &options))
        .map_err(to_py)?;
    let mut positions = Vec::with_capacity(m.times.len() * m.markers() * 3);
    for frame in &m.frames {
        for p in frame {
            match p {
                Some(p) => positions.extend([p.x, p.y, p.z]),
                None => positions.extend([f64::NAN; 3]),
            }
        }
    }
    let format = match m.format {
        Format::C3d => "c3d",
        Format::Trc => "trc",
        Format::MarkerCsv => "marker-csv",
        Format::GridCsv => "grid-csv",
    };
    Ok((
        f64_bytes(py, &m.times),
        m.labels,
        f64_bytes(py, &positions),
        m.units.name(),
        format,
        m.provenance,
    ))
}

/// Writes a marker recording in the format the extension of `path` names.
#[pyfunction]
#[pyo3(signature = (path, times, labels, positions, units="m", provenance=Vec::new()))]
fn write_recording(
    py: Python<'_>,
    path: PathBuf,
    times: &[u8],
    labels: Vec<String>,
    positions: &[u8],
    units: &str,
    provenance: Vec<(String, String)>,
) -> PyResult<()> {
    let times = from_f64_bytes(times, "time")?;
    let positions = from_f64_bytes(positions, "positions")?;
    let per_frame = labels.len() * 3;
    if positions.len() != times.len() * per_frame {
        return Err(PyValueError::new_err(format!(
            "positions: {} values, expected frames x markers x 3 = {} x {} x 3",
            positions.len(),
            times.len(),
            labels.len()
        )));
    }
    let units =
        Units::parse(units).ok_or_else(|| to_py(Error::invalid("units", units, "mm, cm or m")))?;
    let format = Format::from_path(&path).map_err(to_py)?;
    let frames = if per_frame == 0 {
        vec![Vec::new(); times.len()]
    } else {
        frames_of(&positions, labels.len())
    };
    let m = Markers {
        labels,
        times,
        frames,
        units,
        format,
        provenance,
    };
    py.detach(|| m.write(&path)).map_err(to_py)
}

/// Per frame, per point: the positions of f64 bytes (frames x points x 3), `None` where a
/// coordinate is not finite (a missing sample).
fn frames_of(values: &[f64], points: usize) -> Vec<Vec<Option<Point3<f64>>>> {
    if points == 0 {
        return Vec::new();
    }
    values
        .chunks_exact(points * 3)
        .map(|f| {
            f.chunks_exact(3)
                .map(|p| {
                    p.iter()
                        .all(|v| v.is_finite())
                        .then(|| Point3::new(p[0], p[1], p[2]))
                })
                .collect()
        })
        .collect()
}

/// The breathing frequency of a grid recording as `torso fit` reads it: the principal
/// displacement (first principal axis of the gap-filled, detrended trajectories) and its
/// frequency (Hann-windowed DFT with two-bin interpolation, autocorrelation cross-check).
/// Returns (frequency [Hz], signal bytes (frames), loadings bytes (points x 3), explained
/// variance fraction).
#[pyfunction]
fn breathing_frequency<'py>(
    py: Python<'py>,
    times: &[u8],
    positions: &[u8],
    points: usize,
) -> PyResult<(f64, Bound<'py, PyBytes>, Bound<'py, PyBytes>, f64)> {
    let times = from_f64_bytes(times, "time")?;
    let values = from_f64_bytes(positions, "positions")?;
    if points == 0 || values.len() != times.len() * points * 3 {
        return Err(PyValueError::new_err(format!(
            "positions: {} values, expected frames x points x 3 = {} x {points} x 3",
            values.len(),
            times.len()
        )));
    }
    let recording = breathing_torso::recording::Recording {
        grid: (1, points),
        frames: frames_of(&values, points),
        times,
        units: Units::Metres,
        provenance: Vec::new(),
    };
    let (pd, f) = py
        .detach(|| -> breathing_torso::Result<_> {
            let pd = breathing_torso::fit::principal::principal_displacement(&recording)?;
            let f = breathing_torso::stats::frequency::estimate_frequency(
                &pd.signal,
                recording.rate(),
            )?;
            Ok((pd, f))
        })
        .map_err(to_py)?;
    let loadings: Vec<f64> = pd.loadings.iter().flat_map(|l| [l.x, l.y, l.z]).collect();
    Ok((
        f.frequency_hz,
        f64_bytes(py, &pd.signal),
        f64_bytes(py, &loadings),
        pd.explained,
    ))
}

/// What `register` returns: rotation (3 x 3 row-major bytes), translation, scale, rms [m].
type Transform<'py> = (Bound<'py, PyBytes>, (f64, f64, f64), f64, f64);

/// The least-squares rigid (or, `with_scale`, similarity) transform mapping the tracked
/// `recorded` points onto `model` (Umeyama 1991), as `torso fit` registers a frame: returns
/// (rotation bytes, 3 x 3 row-major; translation (3); scale; rms residual [m]).
#[pyfunction]
#[pyo3(signature = (model, recorded, with_scale=false))]
fn register<'py>(
    py: Python<'py>,
    model: &[u8],
    recorded: &[u8],
    with_scale: bool,
) -> PyResult<Transform<'py>> {
    let model = from_f64_bytes(model, "model")?;
    let recorded = from_f64_bytes(recorded, "recorded")?;
    if model.len() % 3 != 0 || model.len() != recorded.len() {
        return Err(PyValueError::new_err(format!(
            "model and recorded: {} and {} values, expected the same number of points x 3",
            model.len(),
            recorded.len()
        )));
    }
    let n = model.len() / 3;
    let model: Vec<Point3<f64>> = model
        .chunks_exact(3)
        .map(|p| Point3::new(p[0], p[1], p[2]))
        .collect();
    let recorded = frames_of(&recorded, n).pop().unwrap_or_default();
    let (t, rms) = breathing_torso::anatomy::skin::register_rigid(&model, &recorded, with_scale)
        .map_err(to_py)?;
    let m = t.rotation.to_rotation_matrix();
    let rows: Vec<f64> = (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .map(|(i, j)| m.matrix()[(i, j)])
        .collect();
    Ok((
        f64_bytes(py, &rows),
        (t.translation.x, t.translation.y, t.translation.z),
        t.scale,
        rms,
    ))
}

/// A Python error raised inside a fit's progress callback, carried out of the fit by
/// unwinding (`resume_unwind` runs no panic hook, so nothing is printed) and raised again.
struct Interrupted(PyErr);

/// Fits the recording at `path` as `torso fit` does, writing the result JSON at `out` (with
/// its CSV and figure beside it); returns the JSON's path.
#[pyfunction]
#[pyo3(signature = (path, out, subject=None, posture="standing", lod=None, solver="dopri5", rtol=1e-6, grid="10x6", units=None, rate=None, method="nelder-mead", max_evals=120, seed=1, threads=None, skin_fit=false, marker_offsets=false, fit_size=None, drift=true, sway=true, reference=Vec::new(), marker_radius=0.0, anterior=Vec::new(), ti_ttot=Some(0.5), progress=None, muscle_law="thesis", gravity=9.81, gravity_loads="preloaded", postural_tone=true))]
#[allow(clippy::too_many_arguments)]
fn fit(
    py: Python<'_>,
    path: PathBuf,
    out: PathBuf,
    subject: Option<&Bound<'_, PyDict>>,
    posture: &str,
    lod: Option<u32>,
    solver: &str,
    rtol: f64,
    grid: &str,
    units: Option<&str>,
    rate: Option<f64>,
    method: &str,
    max_evals: usize,
    seed: u64,
    threads: Option<usize>,
    skin_fit: bool,
    marker_offsets: bool,
    fit_size: Option<bool>,
    drift: bool,
    sway: bool,
    reference: Vec<String>,
    marker_radius: f64,
    anterior: Vec<String>,
    ti_ttot: Option<f64>,
    progress: Option<Py<PyAny>>,
    muscle_law: &str,
    gravity: f64,
    gravity_loads: &str,
    postural_tone: bool,
) -> PyResult<String> {
    let laws = Laws {
        muscle_law,
        gravity,
        gravity_loads,
        postural_tone,
    };
    let scene = Scene::new(subject, posture, lod, solver, rtol, "quiet", None, &laws)?;
    let model = ModelArgs {
        subject: scene.subject,
        solver: scene.solver,
        grid: grid.into(),
    };
    let read = read_options(units, rate)?;
    if let Some(f) = ti_ttot {
        let (lo, hi) = breathing_torso::model::drive::INSPIRATORY_FRACTION_RANGE;
        if !(lo..=hi).contains(&f) {
            return Err(to_py(Error::invalid(
                "ti_ttot",
                f,
                format!("[{lo}, {hi}] or None (auto)"),
            )));
        }
    }
    let options = FitOptions {
        method: Method::from_name(method).map_err(to_py)?,
        max_evals,
        seed,
        threads: threads.unwrap_or_else(default_threads),
        inspiratory_fraction: ti_ttot,
        marker_offsets,
        reference,
        marker_radius: marker_radius * 1e-3,
        ..FitOptions::default()
    };
    if !(marker_radius.is_finite() && marker_radius >= 0.0) {
        return Err(to_py(Error::invalid(
            "marker_radius",
            marker_radius,
            "a finite distance >= 0 mm",
        )));
    }
    if !(1..=2).contains(&options.threads) {
        return Err(to_py(Error::invalid("threads", options.threads, "1 or 2")));
    }
    let flags = FitFlags {
        skin_fit,
        fit_size: fit_size == Some(true),
        no_fit_size: fit_size == Some(false),
        no_drift: !drift,
        no_sway: !sway,
        pose: PoseOptions { anterior },
    };
    // Called on this thread at every evaluation the search reports: the GIL is taken back
    // for the signal check and the user's callback; an exception from either ends the fit.
    let mut observer = |n: usize, best: f64| {
        let outcome = Python::attach(|py| -> PyResult<()> {
            py.check_signals()?;
            if let Some(cb) = &progress {
                cb.call1(py, (n, best))?;
            }
            Ok(())
        });
        if let Err(e) = outcome {
            std::panic::resume_unwind(Box::new(Interrupted(e)));
        }
    };
    let result = py.detach(|| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            breathing_torso::cli::fit::fit_file_observed(
                &path,
                &read,
                &model,
                &out,
                &options,
                &flags,
                Some(&mut observer),
            )
        }))
    });
    match result {
        Ok(Ok(_)) => Ok(out.display().to_string()),
        Ok(Err(e)) => Err(to_py(e)),
        Err(payload) => match payload.downcast::<Interrupted>() {
            Ok(interrupted) => Err(interrupted.0),
            Err(other) => {
                let what = other
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| other.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_else(|| "a panic".into());
                Err(TorsoError::new_err(format!("the fit failed: {what}")))
            }
        },
    }
}

/// A series from f64 bytes of times and values.
fn series(time: &[u8], values: &[u8], column: &str, source: &str) -> PyResult<Series> {
    let time = from_f64_bytes(time, source)?;
    let values = from_f64_bytes(values, source)?;
    if time.len() != values.len() {
        return Err(PyValueError::new_err(format!(
            "{source}: {} times and {} values",
            time.len(),
            values.len()
        )));
    }
    Ok(Series {
        time,
        values,
        column: column.into(),
        source: source.into(),
    })
}

/// Compares a simulated lung volume with a spirogram as `torso validate` does; returns the
/// statistics as JSON text and writes every output into `out` when given. `sim` is a CSV
/// path or (time, values) bytes; `spiro` a CSV path or (time, values, "volume"|"flow").
#[pyfunction]
#[pyo3(signature = (sim_path, sim_arrays, spiro_path, spiro_arrays, out=None, sim_column=None, lung_ratio=None, max_lag=100, harmonics=4, bootstrap=399, max_ar_order=8, seed=1, bars_iterations=2200, detrend=false))]
#[allow(clippy::too_many_arguments)]
fn validate(
    py: Python<'_>,
    sim_path: Option<PathBuf>,
    sim_arrays: Option<(Vec<u8>, Vec<u8>)>,
    spiro_path: Option<PathBuf>,
    spiro_arrays: Option<(Vec<u8>, Vec<u8>, String)>,
    out: Option<PathBuf>,
    sim_column: Option<String>,
    lung_ratio: Option<f64>,
    max_lag: usize,
    harmonics: usize,
    bootstrap: usize,
    max_ar_order: usize,
    seed: u64,
    bars_iterations: usize,
    detrend: bool,
) -> PyResult<String> {
    use breathing_torso::cli::validate::{ValidateArgs, options, read_sim, read_spiro};
    let args = ValidateArgs {
        sim: sim_path.clone().unwrap_or_default(),
        spiro: spiro_path.clone().unwrap_or_default(),
        out: out.clone().unwrap_or_default(),
        sim_column,
        lung_ratio,
        max_lag,
        harmonics,
        bootstrap,
        max_ar_order,
        seed,
        bars_iterations,
        detrend,
    };
    let opts = options(&args).map_err(to_py)?;
    let sim = match (&sim_path, sim_arrays) {
        (Some(_), _) => read_sim(&args).map_err(to_py)?,
        (None, Some((t, v))) => series(&t, &v, "volume.lung", "sim")?,
        (None, None) => return Err(PyValueError::new_err("sim: give a CSV path or arrays")),
    };
    let (spiro, kind) = match (&spiro_path, spiro_arrays) {
        (Some(_), _) => read_spiro(&args).map_err(to_py)?,
        (None, Some((t, v, kind))) => {
            let kind = match kind.as_str() {
                "volume" => SpiroKind::Volume,
                "flow" => SpiroKind::Flow,
                other => {
                    return Err(to_py(Error::invalid("spiro kind", other, "volume or flow")));
                }
            };
            (series(&t, &v, &kind_name(kind), "spiro")?, kind)
        }
        (None, None) => return Err(PyValueError::new_err("spiro: give a CSV path or arrays")),
    };
    py.detach(|| {
        let v = breathing_torso::stats::validation::validate(&sim, &spiro, kind, &opts)?;
        if let Some(dir) = &out {
            breathing_torso::stats::validation::write_outputs(&v, dir)?;
        }
        serde_json::to_string(&v).map_err(|e| Error::State(format!("JSON encoding failed: {e}")))
    })
    .map_err(to_py)
}

fn kind_name(kind: SpiroKind) -> String {
    match kind {
        SpiroKind::Volume => "volume".into(),
        SpiroKind::Flow => "flow".into(),
    }
}

/// The crate's version.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

/// The module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Torso>()?;
    m.add_function(wrap_pyfunction!(read_recording, m)?)?;
    m.add_function(wrap_pyfunction!(write_recording, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(validate, m)?)?;
    m.add_function(wrap_pyfunction!(breathing_frequency, m)?)?;
    m.add_function(wrap_pyfunction!(register, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add("TorsoError", m.py().get_type::<TorsoError>())?;
    Ok(())
}
