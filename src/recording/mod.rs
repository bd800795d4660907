//! Marker recordings: one file per format, each read into one structure ([`Markers`]): the
//! labels, the frame times, the positions in metres and the samples that are missing. This
//! module holds what the formats share: the length unit ([`Units`]), the format a path names
//! ([`Format`]), what a reader needs when a file does not say it ([`ReadOptions`]), the
//! recording of named markers ([`Markers`]) with its checks, and reading and writing by
//! extension.
//!
//! | file | format | extension | read | written |
//! |---|---|---|---|---|
//! | [`c3d`] | C3D (Vicon, Qualisys) | `.c3d` | `c3dio`: POINT:LABELS, POINT:UNITS, POINT:RATE, residual < 0 missing | here: Intel, float points, residual word -1 for a missing point |
//! | [`trc`] | TRC (OpenSim) | `.trc` | tab-separated header, empty cells missing | here |
//! | [`named_csv`] | wide CSV of named markers | `.csv` | `NAME X`/`NAME.x`/`NAME_x` columns, optional time column | here |
//! | [`grid_csv`] | the project's SLP grid CSV | `.csv` | [`Recording`] (`time,marker[1].x,...`) | [`Recording`] |
//!
//! A `.csv` file is a grid recording when its header starts `time,marker[1].x`, otherwise a
//! file of named markers. Missing samples (gaps, residual < 0, empty cells, NaN) are `None`,
//! never zero. Everything else that is malformed is an [`Error::Parse`] naming the file, the
//! line (or, in a C3D file, the frame) and the column (header name and index).
//!
//! The grid's markers carry the labels `marker[1]`..`marker[R*C]` (row-major from the top
//! row, column 1 on the subject's right) in every format. How a recording was made is kept
//! as key/value pairs ([`Markers::provenance`]): `# key: value` comment lines in CSV, extra
//! header fields in TRC, the parameter group `BREATHING_TORSO` (`KEYS`, `VALUES`) in C3D.

pub mod c3d;
pub mod grid_csv;
pub mod named_csv;
pub mod trc;

pub use c3d::{C3D_GROUP, read_c3d};
pub use grid_csv::{MAX_GRID_SIDE, Recording, grid_label, parse_grid};
pub use named_csv::{parse_csv, parse_named_csv};
pub use trc::parse_trc;

use c3d::c3d_bytes;
use named_csv::csv_text;
use trc::trc_text;

use crate::{Error, Result};
use nalgebra::Point3;
use std::collections::HashMap;
use std::path::Path;

/// Length unit of a recording file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Units {
    /// Metres.
    Metres,
    /// Millimetres.
    Millimetres,
    /// Centimetres.
    Centimetres,
}

impl Units {
    /// Metres per file unit.
    pub fn to_metres(self) -> f64 {
        match self {
            Units::Metres => 1.0,
            Units::Millimetres => 1e-3,
            Units::Centimetres => 1e-2,
        }
    }

    /// The unit spelt `m`, `cm` or `mm` (case-insensitive, surrounding blanks ignored).
    pub fn parse(s: &str) -> Option<Units> {
        match s.trim().to_ascii_lowercase().as_str() {
            "m" => Some(Units::Metres),
            "cm" => Some(Units::Centimetres),
            "mm" => Some(Units::Millimetres),
            _ => None,
        }
    }

    /// The spelling used in `# units:` lines.
    pub fn name(self) -> &'static str {
        match self {
            Units::Metres => "m",
            Units::Millimetres => "mm",
            Units::Centimetres => "cm",
        }
    }
}

/// File format of a marker recording.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// C3D binary file.
    C3d,
    /// OpenSim TRC text file.
    Trc,
    /// Wide CSV of named markers.
    MarkerCsv,
    /// The project's SLP grid CSV.
    GridCsv,
}

impl Format {
    /// A short human-readable name.
    pub fn name(self) -> &'static str {
        match self {
            Format::C3d => "C3D",
            Format::Trc => "TRC (OpenSim)",
            Format::MarkerCsv => "CSV of named markers",
            Format::GridCsv => "SLP grid CSV",
        }
    }

    /// The format a path's extension names (`.csv` reads as either CSV; writing a `.csv`
    /// writes the grid format when the labels are the grid's).
    pub fn from_path(path: &Path) -> Result<Format> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("c3d") => Ok(Format::C3d),
            Some("trc") => Ok(Format::Trc),
            Some("csv") => Ok(Format::MarkerCsv),
            _ => Err(Error::invalid(
                format!("the extension of {}", path.display()),
                ext.map_or("(none)".to_string(), |e| format!(".{e}")),
                ".c3d, .trc or .csv",
            )),
        }
    }
}

/// What a reader needs when the file does not say it (flags `--units`, `--rate`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReadOptions {
    /// Length unit of a CSV of named markers without a `# units:` line.
    pub units: Option<Units>,
    /// Frame rate [Hz] of a CSV of named markers without a time column or `# rate:` line.
    pub rate: Option<f64>,
}

/// A marker recording: named markers over time, in metres.
#[derive(Clone, Debug, PartialEq)]
pub struct Markers {
    /// Marker labels, one per column of `frames`.
    pub labels: Vec<String>,
    /// Frame times [s], strictly increasing.
    pub times: Vec<f64>,
    /// Per frame, per marker: the position [m], or `None` when the sample is missing.
    pub frames: Vec<Vec<Option<Point3<f64>>>>,
    /// Unit of the file it was read from (or is to be written in).
    pub units: Units,
    /// Format it was read from.
    pub format: Format,
    /// How the recording was made, as key/value pairs in file order.
    pub provenance: Vec<(String, String)>,
}

/// Splits `line` on `sep`, returning each cell with its 1-based character column.
fn split_cells(line: &str, sep: char) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut start = 0;
    let mut col = 1;
    for (chars, (i, c)) in line.char_indices().enumerate() {
        if c == sep {
            out.push((col, &line[start..i]));
            start = i + c.len_utf8();
            col = chars + 2;
        }
    }
    out.push((col, &line[start..]));
    out
}

/// A cell as a coordinate: `None` when empty or NaN, an error naming the cell otherwise.
fn coordinate(s: &str, at: impl Fn(String) -> Error) -> Result<Option<f64>> {
    let s = s.trim();
    if s.is_empty() {
        return Ok(None);
    }
    match s.parse::<f64>() {
        Ok(v) if v.is_nan() => Ok(None),
        Ok(v) if v.is_finite() => Ok(Some(v)),
        Ok(_) => Err(at(format!(
            "`{s}` is infinite (leave the cell empty or NaN for a missing sample)"
        ))),
        Err(_) => Err(at(format!("`{s}` is not a number"))),
    }
}

/// A point from three optional coordinates: missing unless all three are present.
fn point(xyz: [Option<f64>; 3], scale: f64) -> Option<Point3<f64>> {
    match xyz {
        [Some(x), Some(y), Some(z)] => Some(Point3::new(x * scale, y * scale, z * scale)),
        _ => None,
    }
}

impl Markers {
    /// Number of markers.
    pub fn markers(&self) -> usize {
        self.labels.len()
    }

    /// Mean frame rate [Hz] from the mean frame interval.
    pub fn rate(&self) -> f64 {
        let n = self.times.len();
        if n < 2 {
            return 0.0;
        }
        (n - 1) as f64 / (self.times[n - 1] - self.times[0])
    }

    /// Duration from the first to the last frame [s].
    pub fn duration(&self) -> f64 {
        self.times.last().unwrap_or(&0.0) - self.times.first().unwrap_or(&0.0)
    }

    /// Missing samples of each marker.
    pub fn missing_per_marker(&self) -> Vec<usize> {
        (0..self.markers())
            .map(|k| self.frames.iter().filter(|f| f[k].is_none()).count())
            .collect()
    }

    /// The provenance value of `key`, if the recording names it.
    pub fn provenance_value(&self, key: &str) -> Option<&str> {
        self.provenance
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// Checks the invariants a hand-built recording must satisfy before writing.
    pub fn validate(&self) -> Result<()> {
        if self.labels.is_empty() {
            return Err(Error::invalid(
                "marker labels",
                "none",
                "at least one marker",
            ));
        }
        let mut seen = HashMap::new();
        for (k, l) in self.labels.iter().enumerate() {
            if l.trim().is_empty() || l.contains(['\t', '\n', '\r', ',']) {
                return Err(Error::invalid(
                    format!("label of marker {}", k + 1),
                    format!("{l:?}"),
                    "a non-empty name without tabs, commas or line breaks",
                ));
            }
            if let Some(first) = seen.insert(l.as_str(), k) {
                return Err(Error::invalid(
                    format!("label of marker {}", k + 1),
                    l,
                    format!("a name not used before (marker {} has it)", first + 1),
                ));
            }
        }
        if self.times.len() != self.frames.len() || self.times.len() < 2 {
            return Err(Error::invalid(
                "recording frames",
                format!("{} times, {} frames", self.times.len(), self.frames.len()),
                "as many times as frames, at least two",
            ));
        }
        for (i, w) in self.times.windows(2).enumerate() {
            if !(w[0].is_finite() && w[1].is_finite() && w[1] > w[0]) {
                return Err(Error::invalid(
                    format!("recording time of frame {}", i + 2),
                    w[1],
                    format!("finite and > {}", w[0]),
                ));
            }
        }
        for (i, f) in self.frames.iter().enumerate() {
            if f.len() != self.markers() {
                return Err(Error::invalid(
                    format!("recording frame {}", i + 1),
                    format!("{} markers", f.len()),
                    format!("{} markers (one per label)", self.markers()),
                ));
            }
            if f.iter()
                .flatten()
                .any(|p| p.coords.iter().any(|v| !v.is_finite()))
            {
                return Err(Error::invalid(
                    format!("recording frame {}", i + 1),
                    "a non-finite coordinate",
                    "finite coordinates or missing samples",
                ));
            }
        }
        for (k, v) in &self.provenance {
            if k.trim().is_empty()
                || k.contains([':', '\n', '\r', '\t'])
                || v.contains(['\n', '\r', '\t'])
            {
                return Err(Error::invalid(
                    "recording provenance",
                    format!("{k:?}: {v:?}"),
                    "a non-empty key without `:`, tabs or line breaks; a value on one line without tabs",
                ));
            }
        }
        Ok(())
    }

    /// Reads a marker recording, the format chosen by extension (and, for `.csv`, by the
    /// header).
    pub fn read(path: &Path, options: &ReadOptions) -> Result<Markers> {
        let name = path.display().to_string();
        match Format::from_path(path)? {
            Format::C3d => {
                let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
                read_c3d(&bytes, &name)
            }
            _ => {
                let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
                if Format::from_path(path)? == Format::Trc {
                    parse_trc(&text, &name)
                } else {
                    parse_csv(&text, &name, options)
                }
            }
        }
    }

    /// Writes the recording in the format its extension names (creating the parent
    /// directory). A `.csv` is the grid format when the labels are a grid's (with a `grid`
    /// provenance entry, or 60 markers for 10 x 6), the named-marker format otherwise.
    pub fn write(&self, path: &Path) -> Result<()> {
        self.validate()?;
        let bytes = match Format::from_path(path)? {
            Format::C3d => c3d_bytes(self)?,
            Format::Trc => trc_text(self, path).into_bytes(),
            _ => match self.grid_shape().and_then(|g| self.to_recording(g).ok()) {
                Some(rec) => rec.to_csv()?.into_bytes(),
                None => csv_text(self).into_bytes(),
            },
        };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        std::fs::write(path, bytes).map_err(|e| Error::io(path, e))
    }
}

/// The provenance entries other than the ones a format writes in its own fields.
fn extra_provenance(m: &Markers) -> impl Iterator<Item = &(String, String)> {
    m.provenance
        .iter()
        .filter(|(k, _)| k != "units" && k != "rate")
}
