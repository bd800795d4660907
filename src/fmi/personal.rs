//! Personalised FMUs: a subject fitted by `torso fit` baked into the FMU. This module turns a
//! fit result JSON into the parameters whose start values the FMU's model description
//! carries (the subject, the fitted drive and the model the fit ran: level of detail, marker
//! grid, lung ratio, skin reference, subject mesh), the files the subject needs at run time
//! (copied under `resources/subject/`) and the fit's report (under `documentation/`); and,
//! at `fmi2Instantiate`, finds the parameter set a personalised FMU carries in its
//! resources ([`PARAMETERS`]) and, for a fit of a named marker set, the set's bindings on the
//! skin ([`MARKERS`]), from which its variable table (the set's markers as outputs, named by
//! their labels) and GUID follow ([`crate::fmi::variables::Table::personalised`]).
//!
//! The same parameters are written beside the FMU as an SSP parameter set ([`super::ssv`])
//! for the generic FMU; there the skin reference and mesh folder are absolute paths of the
//! files the fit used, since the generic FMU does not carry them.

use super::ssv;
use super::variables::{
    Causality, Personalisation, ScalarType, Table, Value, personalised_table, table,
};
use crate::anatomy::skin::MarkerSet;
use crate::anatomy::{Posture, Sex};
use crate::{Error, Result};
use serde_json::Value as Json;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where a personalised FMU keeps its parameter set, relative to its `resources/`.
pub const PARAMETERS: &str = "subject/parameters.ssv";
/// Folder of the subject's files, relative to the FMU's `resources/`.
pub const SUBJECT_DIR: &str = "subject";
/// Where a personalised FMU of a named marker set keeps the set (labels and bindings on the
/// rest skin), relative to its `resources/`: `{"name": .., "bindings": [..]}` with the
/// bindings of [`crate::anatomy::skin::MarkerSet::bindings_json`].
pub const MARKERS: &str = "subject/markers.json";

/// The variable table of the FMU whose resources are `resources`: the personalised table of
/// the parameter set at [`PARAMETERS`], when there is one, otherwise the generic table. An
/// error names the set and what is wrong in it.
pub fn table_in(resources: Option<&Path>) -> Result<&'static Table> {
    let Some(path) = resources
        .map(|r| r.join(PARAMETERS))
        .filter(|p| p.is_file())
    else {
        return Ok(table());
    };
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    let name = path.display().to_string();
    let starts = ssv::parse(&text, &name)?;
    ssv::check(table(), &starts, &name)?;
    let markers = match resources.map(|r| r.join(MARKERS)).filter(|p| p.is_file()) {
        None => None,
        Some(path) => Some(Arc::new(read_markers(&path)?)),
    };
    personalised_table(&Personalisation { starts, markers })
}

/// The marker set a personalised FMU carries at [`MARKERS`]; an error names the file and
/// what is wrong in it.
pub fn read_markers(path: &Path) -> Result<MarkerSet> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let source = path.display().to_string();
    let json: Json = serde_json::from_slice(&bytes).map_err(|e| Error::Parse {
        path: source.clone(),
        line: e.line(),
        column: e.column(),
        message: format!("not JSON: {e}"),
    })?;
    let name = json
        .get("name")
        .and_then(Json::as_str)
        .ok_or_else(|| Error::invalid(format!("{source}: name"), "missing", "a string"))?;
    let bindings = json
        .get("bindings")
        .ok_or_else(|| Error::invalid(format!("{source}: bindings"), "missing", "an array"))?;
    MarkerSet::from_bindings_json(name, bindings, &source)
}

/// The content of [`MARKERS`] for `set`.
pub fn markers_file(set: &MarkerSet) -> Vec<u8> {
    let json = serde_json::json!({
        "name": set.name,
        "bindings": set.bindings_json(),
    });
    let mut text = serde_json::to_string_pretty(&json).unwrap_or_default();
    text.push('\n');
    text.into_bytes()
}

/// The drive parameters a fit result names at its top level (`drive_fmi`).
pub const FIT_DRIVE_KEYS: [&str; 8] = [
    "drive.frequency",
    "drive.inspiratory_fraction",
    "drive.ribs.amplitude",
    "drive.ribs.phase",
    "drive.diaphragm.amplitude",
    "drive.diaphragm.phase",
    "drive.abdominals.amplitude",
    "drive.abdominals.phase",
];
/// The subject parameters of a fit result's `subject` object.
pub const FIT_SUBJECT_KEYS: [&str; 6] = [
    "subject.sex",
    "subject.age",
    "subject.stature",
    "subject.mass",
    "subject.breast_size",
    "posture",
];
/// The model parameters of a fit result's `model` object that must be there; `lung.ratio`,
/// `slp.reference`, `subject.mesh_dir` and the laws the fit ran (`muscle_law`, `gravity`,
/// `gravity_loads`, `postural_tone`) are taken when present (fits written before the laws
/// were recorded carry none, and the FMU's defaults stand).
pub const FIT_MODEL_KEYS: [&str; 3] = ["scene.level_of_detail", "grid.rows", "grid.cols"];
const FIT_MODEL_OPTIONAL: [&str; 7] = [
    "lung.ratio",
    "slp.reference",
    "subject.mesh_dir",
    "muscle_law",
    "gravity",
    "gravity_loads",
    "postural_tone",
];

/// A fit made into a personalised FMU.
#[derive(Clone, Debug)]
pub struct PersonalFmu {
    /// The parameters with their start values inside the FMU (paths relative to its
    /// `resources/`).
    pub personalisation: Personalisation,
    /// The same parameters for the generic FMU (the `.ssv` beside the FMU): paths absolute.
    pub generic: Vec<(String, Value)>,
    /// Entries to add to the FMU: (entry name, content), the parameter set, the subject's
    /// files and the fit's documentation.
    pub entries: Vec<(String, Vec<u8>)>,
}

impl PersonalFmu {
    /// The FMU's variable table.
    pub fn table(&self) -> Result<Table> {
        Table::personalised(&self.personalisation)
    }
}

fn not_a_fit(path: &Path, what: String) -> Error {
    Error::State(format!(
        "{}: not a `torso fit` result: {what}",
        path.display()
    ))
}

/// One parameter's value from a fit result's JSON, typed as the FMU's variable is; sex and
/// posture may be spelt as `torso fit` writes them (`"Female"`, `"Supine"`) or as codes.
fn value_of(path: &Path, name: &str, v: &Json) -> Result<Value> {
    let var = table()
        .by_name(name)
        .filter(|v| v.causality == Causality::Parameter)
        .ok_or_else(|| not_a_fit(path, format!("`{name}` is not an FMU parameter")))?;
    let bad = |want: &str| not_a_fit(path, format!("`{name}` is {v}, not {want}"));
    Ok(match var.ty {
        ScalarType::Real => Value::Real(v.as_f64().ok_or_else(|| bad("a number"))?),
        ScalarType::Integer => {
            let code = match (name, v) {
                ("subject.sex", Json::String(_)) => serde_json::from_value::<Sex>(v.clone())
                    .map(|s| i64::from(s.code()))
                    .map_err(|_| bad("Male or Female"))?,
                ("posture", Json::String(_)) => serde_json::from_value::<Posture>(v.clone())
                    .map(|p| i64::from(p.code()))
                    .map_err(|_| bad("Standing, Sitting or Supine"))?,
                _ => v.as_i64().ok_or_else(|| bad("an integer"))?,
            };
            Value::Integer(i32::try_from(code).map_err(|_| bad("a 32-bit integer"))?)
        }
        ScalarType::Boolean => Value::Boolean(v.as_bool().ok_or_else(|| bad("true or false"))?),
        ScalarType::String => Value::String(v.as_str().ok_or_else(|| bad("a string"))?.to_string()),
    })
}

/// A path the fit result names: as given (relative to the working folder), else relative to
/// the fit result's folder (where `torso fit` writes the skin reference).
fn locate(fit: &Path, name: &str, given: &str, dir: bool) -> Result<PathBuf> {
    let exists = |p: &Path| if dir { p.is_dir() } else { p.is_file() };
    let as_given = PathBuf::from(given);
    let beside = fit
        .parent()
        .map(|d| d.join(as_given.file_name().unwrap_or_default()));
    let found = if exists(&as_given) {
        Some(as_given)
    } else {
        beside.filter(|p| exists(p))
    };
    let found = found.ok_or_else(|| {
        Error::invalid(
            name,
            given,
            format!(
                "an existing {} (named by {}; also looked for beside it)",
                if dir { "folder" } else { "file" },
                fit.display()
            ),
        )
    })?;
    found.canonicalize().map_err(|e| Error::io(&found, e))
}

/// Files under `dir`, as (path relative to `dir` with forward slashes, full path), sorted.
fn files_under(dir: &Path) -> Result<Vec<(String, PathBuf)>> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).map_err(|e| Error::io(&d, e))? {
            let p = entry.map_err(|e| Error::io(&d, e))?.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel: Vec<String> = p
                    .strip_prefix(dir)
                    .unwrap_or(&p)
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                out.push((rel.join("/"), p));
            }
        }
    }
    out.sort();
    Ok(out)
}

/// Reads the fit result at `fit` (the JSON `torso fit` writes) into a personalised FMU: the
/// drive (top-level `drive.*`), the subject (`subject`) and the model (`model`) under their
/// FMI names; its skin reference (`slp.reference`) copied to `resources/subject/` and its
/// subject mesh folder (`subject.mesh_dir`) to `resources/subject/mesh/`, the parameters
/// pointing at them; the JSON as `documentation/fit.json` and its PNG report
/// (`<stem>_report.png`, if beside it) as `documentation/fit_report.png`. An error names the
/// file and the missing or wrong key.
pub fn from_fit_json(fit: &Path) -> Result<PersonalFmu> {
    let bytes = std::fs::read(fit).map_err(|e| Error::io(fit, e))?;
    let json: Json = serde_json::from_slice(&bytes).map_err(|e| Error::Parse {
        path: fit.display().to_string(),
        line: e.line(),
        column: e.column(),
        message: format!("not JSON: {e}"),
    })?;
    let top = json
        .as_object()
        .ok_or_else(|| not_a_fit(fit, "the top level is not an object".into()))?;
    let object = |key: &str| {
        top.get(key)
            .and_then(Json::as_object)
            .ok_or_else(|| not_a_fit(fit, format!("missing key `{key}` (an object)")))
    };
    let subject = object("subject")?;
    let model = object("model")?;
    let mut starts = Vec::new();
    let mut take = |map: &serde_json::Map<String, Json>,
                    key: &str,
                    place: &str,
                    required: bool|
     -> Result<()> {
        match map.get(key) {
            Some(v) => {
                starts.push((key.to_string(), value_of(fit, key, v)?));
                Ok(())
            }
            None if required => Err(not_a_fit(fit, format!("missing key `{key}`{place}"))),
            None => Ok(()),
        }
    };
    for key in FIT_DRIVE_KEYS {
        take(top, key, "", true)?;
    }
    for key in FIT_SUBJECT_KEYS {
        take(subject, key, " in `subject`", true)?;
    }
    for key in FIT_MODEL_KEYS {
        take(model, key, " in `model`", true)?;
    }
    for key in FIT_MODEL_OPTIONAL {
        take(model, key, " in `model`", false)?;
    }

    let mut entries = Vec::new();
    let mut generic = Vec::with_capacity(starts.len());
    for (name, value) in starts.iter_mut() {
        let original = value.clone();
        let Value::String(given) = value else {
            generic.push((name.clone(), original));
            continue;
        };
        if given.is_empty() {
            generic.push((name.clone(), original));
            continue;
        }
        let dir = name == "subject.mesh_dir";
        let source = locate(fit, name, given, dir)?;
        let inside = if dir {
            let inside = format!("{SUBJECT_DIR}/mesh");
            for (rel, file) in files_under(&source)? {
                let data = std::fs::read(&file).map_err(|e| Error::io(&file, e))?;
                entries.push((format!("resources/{inside}/{rel}"), data));
            }
            inside
        } else {
            let file_name = source
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_else(|| "reference.csv".into());
            let inside = format!("{SUBJECT_DIR}/{file_name}");
            let data = std::fs::read(&source).map_err(|e| Error::io(&source, e))?;
            entries.push((format!("resources/{inside}"), data));
            inside
        };
        generic.push((name.clone(), Value::String(source.display().to_string())));
        *given = inside;
    }
    // A fit of a named marker set: its bound markers (labels and bindings on the rest skin)
    // become the FMU's marker outputs.
    let markers = match top.get("marker_set") {
        None | Some(Json::Null) => None,
        Some(m) => {
            let bindings = m.get("bindings").ok_or_else(|| {
                not_a_fit(
                    fit,
                    "missing key `bindings` in `marker_set` (fit results written before the \
                     bindings were recorded lack it: fit again)"
                        .into(),
                )
            })?;
            let source = format!("{} (`marker_set`)", fit.display());
            let set = MarkerSet::from_bindings_json("recording", bindings, &source)?;
            entries.push((format!("resources/{MARKERS}"), markers_file(&set)));
            Some(Arc::new(set))
        }
    };
    let personalisation = Personalisation { starts, markers };
    // Checks every value against the table (type and range) before anything is written.
    Table::personalised(&personalisation)
        .map_err(|e| Error::State(format!("{}: {e}", fit.display())))?;
    entries.push((
        format!("resources/{PARAMETERS}"),
        ssv::write("subject", &personalisation.starts).into_bytes(),
    ));
    entries.push(("documentation/fit.json".into(), bytes));
    let stem = fit
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let png = fit.with_file_name(format!("{stem}_report.png"));
    if png.is_file() {
        let data = std::fs::read(&png).map_err(|e| Error::io(&png, e))?;
        entries.push(("documentation/fit_report.png".into(), data));
    }
    Ok(PersonalFmu {
        personalisation,
        generic,
        entries,
    })
}
