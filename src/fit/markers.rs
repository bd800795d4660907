//! Marker recordings in the common lab formats, read into one structure ([`Markers`]): the
//! labels, the frame times, the positions in metres and the samples that are missing.
//!
//! | format | extension | read | written |
//! |---|---|---|---|
//! | C3D (Vicon, Qualisys) | `.c3d` | `c3dio`: POINT:LABELS, POINT:UNITS, POINT:RATE, residual < 0 missing | here: Intel, float points, residual word -1 for a missing point |
//! | TRC (OpenSim) | `.trc` | tab-separated header, empty cells missing | here |
//! | wide CSV of named markers | `.csv` | `NAME X`/`NAME.x`/`NAME_x` columns, optional time column | here |
//! | the project's SLP grid CSV | `.csv` | [`Recording`] (`time,marker[1].x,...`) | [`Recording`] |
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

use super::recording::{Recording, Units, parse_grid};
use crate::{Error, Result};
use nalgebra::Point3;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

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

/// The label of grid marker `k` (0-based): `marker[k+1]`.
pub fn grid_label(k: usize) -> String {
    format!("marker[{}]", k + 1)
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

    /// The markers of a grid recording, labelled `marker[1]`..; its grid joins the provenance.
    pub fn from_recording(rec: &Recording) -> Markers {
        let mut provenance = vec![("grid".to_string(), format!("{}x{}", rec.grid.0, rec.grid.1))];
        provenance.extend(rec.provenance.iter().cloned());
        Markers {
            labels: (0..rec.points()).map(grid_label).collect(),
            times: rec.times.clone(),
            frames: rec.frames.clone(),
            units: rec.units,
            format: Format::GridCsv,
            provenance,
        }
    }

    /// The grid recording of a file whose labels are the grid's `marker[1]`..`marker[R*C]`
    /// (in any column order); `grid` is the model's marker grid. An error names the labels
    /// that are not the grid's and what is expected.
    pub fn to_recording(&self, grid: (usize, usize)) -> Result<Recording> {
        let n = grid.0 * grid.1;
        let index: HashMap<&str, usize> = self
            .labels
            .iter()
            .enumerate()
            .map(|(k, l)| (l.as_str(), k))
            .collect();
        let unknown: Vec<&str> = self
            .labels
            .iter()
            .map(String::as_str)
            .filter(|l| !(0..n).any(|k| grid_label(k) == *l))
            .collect();
        let absent: Vec<String> = (0..n)
            .map(grid_label)
            .filter(|l| !index.contains_key(l.as_str()))
            .collect();
        if !unknown.is_empty() || !absent.is_empty() {
            let list = |v: &[String]| {
                if v.len() > 6 {
                    format!("{}, ... ({} in all)", v[..6].join(", "), v.len())
                } else {
                    v.join(", ")
                }
            };
            let unknown: Vec<String> = unknown.iter().map(|s| s.to_string()).collect();
            let mut msg = format!(
                "the recording's markers are not the model's {}x{} grid: expected the labels marker[1]..marker[{n}] (row-major from the top row, column 1 on the subject's right)",
                grid.0, grid.1
            );
            if !unknown.is_empty() {
                let _ = write!(msg, "; not grid labels: {}", list(&unknown));
            }
            if !absent.is_empty() {
                let _ = write!(msg, "; missing: {}", list(&absent));
            }
            msg.push_str(" (`torso fit` registers other marker sets to the skin instead, docs/recordings.md)");
            return Err(Error::State(msg));
        }
        let order: Vec<usize> = (0..n).map(|k| index[grid_label(k).as_str()]).collect();
        let rec = Recording {
            grid,
            times: self.times.clone(),
            frames: self
                .frames
                .iter()
                .map(|f| order.iter().map(|&k| f[k]).collect())
                .collect(),
            units: self.units,
            provenance: self
                .provenance
                .iter()
                .filter(|(k, _)| k != "grid" && k != "units")
                .cloned()
                .collect(),
        };
        rec.validate()?;
        Ok(rec)
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

    /// The grid the recording names (`grid` provenance), or 10 x 6 for 60 markers.
    pub fn grid_shape(&self) -> Option<(usize, usize)> {
        match self.provenance_value("grid") {
            Some(g) => parse_grid(g),
            None if self.markers() == 60 => Some((10, 6)),
            None => None,
        }
    }
}

/// The provenance entries other than the ones a format writes in its own fields.
fn extra_provenance(m: &Markers) -> impl Iterator<Item = &(String, String)> {
    m.provenance
        .iter()
        .filter(|(k, _)| k != "units" && k != "rate")
}

// ---------------------------------------------------------------------------------------
// CSV of named markers

/// The marker name and axis (0, 1, 2) of a header cell `NAME X`, `NAME.x` or `NAME_x`.
fn named_axis(cell: &str) -> Option<(String, usize)> {
    let cell = cell.trim();
    let n = cell.len();
    if n < 3 || !cell.is_char_boundary(n - 2) {
        return None;
    }
    let (name, tail) = cell.split_at(n - 2);
    let mut tail = tail.chars();
    let sep = tail.next()?;
    let axis = match tail.next()?.to_ascii_lowercase() {
        'x' => 0,
        'y' => 1,
        'z' => 2,
        _ => return None,
    };
    let name = name.trim();
    ([' ', '.', '_'].contains(&sep) && !name.is_empty()).then(|| (name.to_string(), axis))
}

fn is_time_header(cell: &str) -> bool {
    let c = cell.trim().to_ascii_lowercase();
    c == "t" || c == "time" || c == "time (s)" || c == "time [s]" || c == "time_s"
}

fn is_frame_header(cell: &str) -> bool {
    let c = cell.trim().to_ascii_lowercase();
    c == "frame" || c == "frame#" || c == "frame number"
}

/// Parses a `.csv`: the grid format when the header starts `time,marker[1].x`, the
/// named-marker format otherwise. `name` is used in error messages.
pub fn parse_csv(text: &str, name: &str, options: &ReadOptions) -> Result<Markers> {
    let header = text
        .lines()
        .map(|l| l.trim_end_matches('\r'))
        .find(|l| !l.trim().is_empty() && !l.starts_with('#'));
    if header.is_some_and(|h| h.replace(' ', "").starts_with("time,marker[1].x")) {
        return Ok(Markers::from_recording(&Recording::parse(text, name)?));
    }
    parse_named_csv(text, name, options)
}

/// Parses a wide CSV of named markers (see the module documentation).
pub fn parse_named_csv(text: &str, name: &str, options: &ReadOptions) -> Result<Markers> {
    let mut file_units: Option<(Units, usize)> = None;
    let mut file_rate: Option<f64> = None;
    let mut provenance = Vec::new();
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')));
    let (header_no, header) = loop {
        let Some((no, line)) = lines.next() else {
            return Err(Error::parse(
                name,
                0,
                0,
                "no header row found: expected columns `NAME X, NAME Y, NAME Z` or `NAME.x, NAME.y, NAME.z` per marker and an optional `time` column",
            ));
        };
        let Some(comment) = line.strip_prefix('#') else {
            if line.trim().is_empty() {
                continue;
            }
            break (no, line);
        };
        let Some((key, value)) = comment.split_once(':') else {
            continue;
        };
        let (key, value) = (key.trim(), value.trim());
        let col = line.find(value).map_or(1, |b| b + 1);
        match key.to_ascii_lowercase().as_str() {
            "units" => match Units::parse(value) {
                Some(u) => file_units = Some((u, no)),
                None => {
                    return Err(Error::parse(
                        name,
                        no,
                        col,
                        format!("unknown units `{value}`: expected `m`, `cm` or `mm`"),
                    ));
                }
            },
            "rate" => match value.trim_end_matches("Hz").trim().parse::<f64>() {
                Ok(r) if r.is_finite() && r > 0.0 => file_rate = Some(r),
                _ => {
                    return Err(Error::parse(
                        name,
                        no,
                        col,
                        format!("bad rate `{value}`: expected a frame rate in Hz > 0"),
                    ));
                }
            },
            _ => provenance.push((key.to_string(), value.to_string())),
        }
    };

    // Header: a time column, a frame column, and x, y, z per marker.
    let head = split_cells(header, ',');
    let mut time_col = None;
    let mut labels: Vec<String> = Vec::new();
    let mut axes: Vec<[Option<usize>; 3]> = Vec::new();
    for (k, (col, cell)) in head.iter().enumerate() {
        if is_time_header(cell) && time_col.is_none() {
            time_col = Some(k);
            continue;
        }
        if is_frame_header(cell) {
            continue;
        }
        let Some((marker, axis)) = named_axis(cell) else {
            return Err(Error::parse(
                name,
                header_no,
                *col,
                format!(
                    "column {} `{}`: expected `time`, `frame` or a marker coordinate `NAME X`, `NAME.x` or `NAME_x` (axis x, y or z)",
                    k + 1,
                    cell.trim()
                ),
            ));
        };
        let m = match labels.iter().position(|l| l.eq_ignore_ascii_case(&marker)) {
            Some(m) => m,
            None => {
                labels.push(marker.clone());
                axes.push([None; 3]);
                labels.len() - 1
            }
        };
        if let Some(first) = axes[m][axis] {
            return Err(Error::parse(
                name,
                header_no,
                *col,
                format!(
                    "column {} `{}`: marker `{marker}` already has a {} column (column {})",
                    k + 1,
                    cell.trim(),
                    ["x", "y", "z"][axis],
                    first + 1
                ),
            ));
        }
        axes[m][axis] = Some(k);
    }
    if labels.is_empty() {
        return Err(Error::parse(
            name,
            header_no,
            1,
            "no marker columns: expected `NAME X, NAME Y, NAME Z` or `NAME.x, NAME.y, NAME.z` per marker",
        ));
    }
    for (m, a) in axes.iter().enumerate() {
        if let Some(axis) = a.iter().position(Option::is_none) {
            return Err(Error::parse(
                name,
                header_no,
                header.chars().count() + 1,
                format!(
                    "marker `{}` has no {} column",
                    labels[m],
                    ["x", "y", "z"][axis]
                ),
            ));
        }
    }
    let units = match (file_units, options.units) {
        (Some((f, no)), Some(o)) if f != o => {
            return Err(Error::parse(
                name,
                no,
                1,
                format!(
                    "the file says `# units: {}` but --units says {}",
                    f.name(),
                    o.name()
                ),
            ));
        }
        (Some((f, _)), _) => f,
        (None, Some(o)) => o,
        (None, None) => {
            return Err(Error::parse(
                name,
                header_no,
                1,
                "the file does not say its length unit: pass --units mm|cm|m or add a `# units: mm` line before the header",
            ));
        }
    };
    let rate = options.rate.or(file_rate);
    if time_col.is_none() && rate.is_none() {
        return Err(Error::parse(
            name,
            header_no,
            1,
            "no `time` column and no frame rate: pass --rate HZ or add a `# rate: HZ` line before the header",
        ));
    }

    // Frames.
    let scale = units.to_metres();
    let mut times = Vec::new();
    let mut frames = Vec::new();
    for (no, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        if line.starts_with('#') {
            return Err(Error::parse(
                name,
                no,
                1,
                "comment lines are only allowed before the header",
            ));
        }
        let row = split_cells(line, ',');
        if row.len() != head.len() {
            let col = row
                .get(head.len())
                .map_or(line.chars().count() + 1, |c| c.0);
            return Err(Error::parse(
                name,
                no,
                col,
                format!(
                    "ragged row: {} cells, the header has {}",
                    row.len(),
                    head.len()
                ),
            ));
        }
        let cell = |k: usize| -> Result<Option<f64>> {
            let (col, s) = row[k];
            coordinate(s, |m| {
                Error::parse(
                    name,
                    no,
                    col,
                    format!("column {} `{}`: {m}", k + 1, head[k].1.trim()),
                )
            })
        };
        let t = match time_col {
            Some(k) => cell(k)?.ok_or_else(|| {
                Error::parse(
                    name,
                    no,
                    row[k].0,
                    format!("column {} `{}`: empty time", k + 1, head[k].1.trim()),
                )
            })?,
            None => frames.len() as f64 / rate.unwrap_or(1.0),
        };
        if let Some(&prev) = times.last()
            && t <= prev
        {
            let col = time_col.map_or(1, |k| row[k].0);
            return Err(Error::parse(
                name,
                no,
                col,
                format!("time {t} s does not increase (previous frame: {prev} s)"),
            ));
        }
        let mut frame = Vec::with_capacity(labels.len());
        for a in &axes {
            let xyz = [
                cell(a[0].unwrap_or(0))?,
                cell(a[1].unwrap_or(0))?,
                cell(a[2].unwrap_or(0))?,
            ];
            frame.push(point(xyz, scale));
        }
        times.push(t);
        frames.push(frame);
    }
    if frames.len() < 2 {
        return Err(Error::parse(
            name,
            header_no + frames.len() + 1,
            1,
            format!("{} frame(s): a recording needs at least two", frames.len()),
        ));
    }
    Ok(Markers {
        labels,
        times,
        frames,
        units,
        format: Format::MarkerCsv,
        provenance,
    })
}

/// The named-marker CSV text (`# units:`, provenance lines, `time,NAME.x,NAME.y,NAME.z,...`).
fn csv_text(m: &Markers) -> String {
    let scale = 1.0 / m.units.to_metres();
    let mut s = String::new();
    let _ = writeln!(s, "# units: {}", m.units.name());
    for (k, v) in extra_provenance(m) {
        let _ = writeln!(s, "# {k}: {v}");
    }
    s.push_str("time");
    for l in &m.labels {
        let _ = write!(s, ",{l}.x,{l}.y,{l}.z");
    }
    s.push('\n');
    for (t, f) in m.times.iter().zip(&m.frames) {
        let _ = write!(s, "{t:.9}");
        for p in f {
            match p {
                Some(p) => {
                    for v in p.coords.iter() {
                        let _ = write!(s, ",{}", v * scale);
                    }
                }
                None => s.push_str(",,,"),
            }
        }
        s.push('\n');
    }
    s
}

// ---------------------------------------------------------------------------------------
// TRC

/// The header fields of TRC line 2 that the format defines.
const TRC_FIELDS: [&str; 8] = [
    "DataRate",
    "CameraRate",
    "NumFrames",
    "NumMarkers",
    "Units",
    "OrigDataRate",
    "OrigDataStartFrame",
    "OrigNumFrames",
];

/// Parses an OpenSim TRC file. `name` is used in error messages.
pub fn parse_trc(text: &str, name: &str) -> Result<Markers> {
    let lines: Vec<&str> = text.lines().map(|l| l.trim_end_matches('\r')).collect();
    let line = |i: usize| lines.get(i).copied().unwrap_or("");
    if !line(0).starts_with("PathFileType") {
        return Err(Error::parse(
            name,
            1,
            1,
            "expected a TRC file starting `PathFileType` (OpenSim marker file)",
        ));
    }
    let keys = split_cells(line(1), '\t');
    let values = split_cells(line(2), '\t');
    let field = |key: &str| -> Result<(usize, &str)> {
        let k = keys
            .iter()
            .position(|(_, c)| c.trim().eq_ignore_ascii_case(key))
            .ok_or_else(|| {
                Error::parse(name, 2, 1, format!("header line 2 has no `{key}` field"))
            })?;
        let (col, v) = values.get(k).copied().ok_or_else(|| {
            Error::parse(
                name,
                3,
                line(2).chars().count() + 1,
                format!("no value under `{key}`"),
            )
        })?;
        Ok((col, v.trim()))
    };
    let positive = |key: &str| -> Result<f64> {
        let (col, v) = field(key)?;
        v.parse::<f64>()
            .ok()
            .filter(|r| r.is_finite() && *r > 0.0)
            .ok_or_else(|| Error::parse(name, 3, col, format!("{key}: `{v}` is not a number > 0")))
    };
    let count = |key: &str| -> Result<usize> {
        let (col, v) = field(key)?;
        v.parse::<usize>()
            .map_err(|_| Error::parse(name, 3, col, format!("{key}: `{v}` is not a whole number")))
    };
    positive("DataRate")?;
    let num_frames = count("NumFrames")?;
    let num_markers = count("NumMarkers")?;
    let (units_col, units_text) = field("Units")?;
    let units = Units::parse(units_text).ok_or_else(|| {
        Error::parse(
            name,
            3,
            units_col,
            format!("Units: `{units_text}` is not mm, cm or m"),
        )
    })?;
    let provenance: Vec<(String, String)> = keys
        .iter()
        .enumerate()
        .filter(|(_, (_, k))| {
            !k.trim().is_empty() && !TRC_FIELDS.iter().any(|f| f.eq_ignore_ascii_case(k.trim()))
        })
        .map(|(i, (_, k))| {
            let v = values.get(i).map_or("", |c| c.1.trim());
            (k.trim().to_string(), v.to_string())
        })
        .collect();

    // Line 4: Frame#, Time, then each label followed by two empty cells.
    let names = split_cells(line(3), '\t');
    if names.len() < 2
        || !names[0].1.trim().eq_ignore_ascii_case("Frame#")
        || !names[1].1.trim().eq_ignore_ascii_case("Time")
    {
        return Err(Error::parse(
            name,
            4,
            1,
            "line 4 should start `Frame#<TAB>Time`",
        ));
    }
    let labels: Vec<String> = names[2..]
        .iter()
        .map(|(_, c)| c.trim())
        .filter(|c| !c.is_empty())
        .map(str::to_string)
        .collect();
    if labels.len() != num_markers {
        return Err(Error::parse(
            name,
            4,
            1,
            format!(
                "line 4 names {} markers, NumMarkers says {num_markers}",
                labels.len()
            ),
        ));
    }
    for (k, (col, c)) in names[2..].iter().enumerate() {
        let want_label = k % 3 == 0;
        if want_label == c.trim().is_empty() {
            return Err(Error::parse(
                name,
                4,
                *col,
                format!(
                    "column {}: expected {} (each label is followed by two empty cells)",
                    k + 3,
                    if want_label {
                        "a marker label"
                    } else {
                        "an empty cell"
                    }
                ),
            ));
        }
    }
    let width = 2 + 3 * num_markers;
    let column_name = |k: usize| -> String {
        match k {
            0 => "Frame#".into(),
            1 => "Time".into(),
            _ => format!("{} {}", labels[(k - 2) / 3], ["X", "Y", "Z"][(k - 2) % 3]),
        }
    };
    let scale = units.to_metres();
    let mut times = Vec::new();
    let mut frames = Vec::new();
    let mut last_no = 5;
    for (i, raw) in lines.iter().enumerate().skip(5) {
        let no = i + 1;
        if raw.trim().is_empty() {
            continue;
        }
        last_no = no;
        let row = split_cells(raw, '\t');
        if row.len() > width && row[width..].iter().any(|(_, c)| !c.trim().is_empty()) {
            return Err(Error::parse(
                name,
                no,
                row[width].0,
                format!("{} cells, the header has {width}", row.len()),
            ));
        }
        let cell = |k: usize| -> Result<Option<f64>> {
            match row.get(k) {
                None => Ok(None),
                Some(&(col, s)) => coordinate(s, |m| {
                    Error::parse(
                        name,
                        no,
                        col,
                        format!("column {} `{}`: {m}", k + 1, column_name(k)),
                    )
                }),
            }
        };
        let t = cell(1)?.ok_or_else(|| {
            let col = row.get(1).map_or(raw.chars().count() + 1, |c| c.0);
            Error::parse(name, no, col, "column 2 `Time`: empty time")
        })?;
        if let Some(&prev) = times.last()
            && t <= prev
        {
            return Err(Error::parse(
                name,
                no,
                row[1].0,
                format!("column 2 `Time`: {t} s does not increase (previous frame: {prev} s)"),
            ));
        }
        let mut frame = Vec::with_capacity(num_markers);
        for m in 0..num_markers {
            let k = 2 + 3 * m;
            frame.push(point([cell(k)?, cell(k + 1)?, cell(k + 2)?], scale));
        }
        times.push(t);
        frames.push(frame);
    }
    if frames.len() != num_frames {
        return Err(Error::parse(
            name,
            last_no,
            1,
            format!(
                "{} frames of data, NumFrames says {num_frames}",
                frames.len()
            ),
        ));
    }
    if frames.len() < 2 {
        return Err(Error::parse(
            name,
            last_no,
            1,
            format!("{} frame(s): a recording needs at least two", frames.len()),
        ));
    }
    Ok(Markers {
        labels,
        times,
        frames,
        units,
        format: Format::Trc,
        provenance,
    })
}

/// The TRC text of `m` (rate from the mean frame interval; provenance as extra header
/// fields after the eight the format defines).
fn trc_text(m: &Markers, path: &Path) -> String {
    let scale = 1.0 / m.units.to_metres();
    let rate = m.rate();
    let n = m.times.len();
    let file = path
        .file_name()
        .and_then(|f| f.to_str())
        .unwrap_or("markers.trc");
    let mut s = String::new();
    let _ = writeln!(s, "PathFileType\t4\t(X/Y/Z)\t{file}");
    let extra: Vec<&(String, String)> = extra_provenance(m).collect();
    s.push_str(&TRC_FIELDS.join("\t"));
    for (k, _) in &extra {
        let _ = write!(s, "\t{k}");
    }
    s.push('\n');
    let _ = write!(
        s,
        "{rate}\t{rate}\t{n}\t{}\t{}\t{rate}\t1\t{n}",
        m.markers(),
        m.units.name()
    );
    for (_, v) in &extra {
        let _ = write!(s, "\t{v}");
    }
    s.push('\n');
    s.push_str("Frame#\tTime");
    for l in &m.labels {
        let _ = write!(s, "\t{l}\t\t");
    }
    s.push_str("\n\t");
    for k in 1..=m.markers() {
        let _ = write!(s, "\tX{k}\tY{k}\tZ{k}");
    }
    s.push_str("\n\n");
    for (i, (t, f)) in m.times.iter().zip(&m.frames).enumerate() {
        let _ = write!(s, "{}\t{t:.9}", i + 1);
        for p in f {
            match p {
                Some(p) => {
                    for v in p.coords.iter() {
                        let _ = write!(s, "\t{}", v * scale);
                    }
                }
                None => s.push_str("\t\t\t"),
            }
        }
        s.push('\n');
    }
    s
}

// ---------------------------------------------------------------------------------------
// C3D

/// The C3D parameter group holding the provenance.
pub const C3D_GROUP: &str = "BREATHING_TORSO";

/// Reads C3D bytes with `c3dio`. `name` is used in error messages (the "line" of a C3D
/// error is the frame, 1-based; the column the marker).
pub fn read_c3d(bytes: &[u8], name: &str) -> Result<Markers> {
    check_c3d_size(bytes, name)?;
    // c3dio indexes by header fields without checking all of them: a malformed file may
    // panic inside it, which becomes the same error as a parse failure.
    let parsed =
        std::panic::catch_unwind(|| c3dio::C3d::from_bytes(bytes).map_err(|e| format!("{e:?}")))
            .map_err(|p| {
                Error::parse(
                    name,
                    0,
                    0,
                    format!(
                        "not a readable C3D file (the parser stopped: {})",
                        crate::error::panic_message(p.as_ref())
                    ),
                )
            })?;
    let c3d =
        parsed.map_err(|e| Error::parse(name, 0, 0, format!("not a readable C3D file: {e}")))?;
    let points = &c3d.points;
    let count = points.cols();
    let units_text: String = points
        .units
        .iter()
        .collect::<String>()
        .trim_matches(['\0', ' '])
        .to_string();
    let units = Units::parse(&units_text).ok_or_else(|| {
        Error::parse(
            name,
            0,
            0,
            format!("POINT:UNITS is `{units_text}`: expected mm, cm or m"),
        )
    })?;
    let rate = f64::from(points.frame_rate);
    if !(rate.is_finite() && rate > 0.0) {
        return Err(Error::parse(
            name,
            0,
            0,
            format!("POINT:RATE (frame rate) is {rate}: expected a number > 0"),
        ));
    }
    if count == 0 {
        return Err(Error::parse(
            name,
            0,
            0,
            "POINT:USED is 0: the file has no markers",
        ));
    }
    let mut labels: Vec<String> = points.labels.iter().map(|l| l.trim().to_string()).collect();
    if labels.len() < count {
        return Err(Error::parse(
            name,
            0,
            0,
            format!(
                "POINT:LABELS has {} labels for {count} markers",
                labels.len()
            ),
        ));
    }
    labels.truncate(count);
    let scale = units.to_metres();
    let invalid = invalid_points(bytes, points.rows(), count);
    let first = f64::from(points.first_frame.max(1)) - 1.0;
    let mut times = Vec::with_capacity(points.rows());
    let mut frames = Vec::with_capacity(points.rows());
    for i in 0..points.rows() {
        let mut frame = Vec::with_capacity(count);
        for (k, label) in labels.iter().enumerate() {
            let p = &points[i][k];
            let present = match &invalid {
                Some(inv) => !inv[i * count + k],
                None => p.residual >= 0.0,
            };
            let finite = p.point.iter().all(|v| v.is_finite());
            if present && !finite {
                return Err(Error::parse(
                    name,
                    i + 1,
                    k + 1,
                    format!(
                        "marker `{label}`: a non-finite coordinate with residual {} (>= 0: valid)",
                        p.residual
                    ),
                ));
            }
            frame.push(present.then(|| {
                Point3::new(
                    f64::from(p.point[0]) * scale,
                    f64::from(p.point[1]) * scale,
                    f64::from(p.point[2]) * scale,
                )
            }));
        }
        times.push((first + i as f64) / rate);
        frames.push(frame);
    }
    if frames.len() < 2 {
        return Err(Error::parse(
            name,
            0,
            0,
            format!("{} frame(s): a recording needs at least two", frames.len()),
        ));
    }
    let mut provenance = Vec::new();
    let strings = |p: &str| -> Vec<String> {
        c3d.parameters
            .get(C3D_GROUP, p)
            .and_then(|p| Vec::<String>::try_from(p).ok())
            .unwrap_or_default()
    };
    let (keys, values) = (strings("KEYS"), strings("VALUES"));
    if keys.len() != values.len() {
        return Err(Error::parse(
            name,
            0,
            0,
            format!(
                "{C3D_GROUP}:KEYS has {} entries, {C3D_GROUP}:VALUES {}",
                keys.len(),
                values.len()
            ),
        ));
    }
    provenance.extend(
        keys.iter()
            .zip(&values)
            .map(|(k, v)| (k.trim().to_string(), v.trim().to_string())),
    );
    Ok(Markers {
        labels,
        times,
        frames,
        units,
        format: Format::C3d,
        provenance,
    })
}

/// Refuses a C3D file whose header promises more point data than the file holds (before
/// `c3dio` allocates for it): the frames, points and analog samples per frame of the header
/// against the bytes after the data start.
fn check_c3d_size(bytes: &[u8], name: &str) -> Result<()> {
    let err = |m: String| Error::parse(name, 0, 0, format!("not a readable C3D file: {m}"));
    let header = bytes.get(..512).ok_or_else(|| {
        err(format!(
            "{} bytes, shorter than the 512-byte header",
            bytes.len()
        ))
    })?;
    let processor = usize::from(header[0])
        .checked_sub(1)
        .and_then(|b| bytes.get(b * 512 + 3).copied());
    let u16_of = |w: usize| {
        let b = [header[2 * w], header[2 * w + 1]];
        if processor == Some(86) {
            usize::from(u16::from_be_bytes(b))
        } else {
            usize::from(u16::from_le_bytes(b))
        }
    };
    let (points, analog, first, last) = (u16_of(1), u16_of(2), u16_of(3), u16_of(4));
    let frames = (last + 1).saturating_sub(first.max(1));
    let start = u16_of(8).saturating_sub(1) * 512;
    let need = start + frames * (4 * points + analog) * 2;
    if need > bytes.len() {
        return Err(err(format!(
            "the header promises {frames} frames of {points} points from byte {start}, at least {need} bytes, but the file has {}",
            bytes.len()
        )));
    }
    Ok(())
}

/// Per frame and point (frame-major), whether the point's residual word is negative (the
/// C3D mark of an invalid point), read off the raw data section; `None` when the header does
/// not describe a data section inside `bytes` (the caller then uses `c3dio`'s residual).
///
/// `c3dio` 0.8 reads the residual as the low byte taken as signed, so a valid point with a
/// residual byte of 128 or more would read as negative; the sign of the whole word is what
/// the format defines. Only the sign is needed, so the three processor types are one test:
/// the sign bit of a 32-bit float is in byte 3 (Intel), byte 1 (DEC) or byte 0 (MIPS), of a
/// 16-bit integer in byte 1 (Intel, DEC) or byte 0 (MIPS).
fn invalid_points(bytes: &[u8], frames: usize, points: usize) -> Option<Vec<bool>> {
    let header = bytes.get(..512)?;
    let processor = *bytes.get((usize::from(header[0]).checked_sub(1)?) * 512 + 3)?;
    let word = |w: usize| -> [u8; 2] { [header[2 * w], header[2 * w + 1]] };
    let u16_of: fn([u8; 2]) -> u16 = match processor {
        84 | 85 => u16::from_le_bytes,
        86 => u16::from_be_bytes,
        _ => return None,
    };
    if usize::from(u16_of(word(1))) != points {
        return None;
    }
    let analog = usize::from(u16_of(word(2)));
    let scale_bytes = [header[12], header[13], header[14], header[15]];
    let float = match processor {
        84 => f32::from_le_bytes(scale_bytes) < 0.0,
        86 => f32::from_be_bytes(scale_bytes) < 0.0,
        // DEC: the sign is bit 7 of the second byte.
        _ => scale_bytes[1] & 0x80 != 0,
    };
    let start = (usize::from(u16_of(word(8))).checked_sub(1)?) * 512;
    let size = if float { 4 } else { 2 };
    let frame_bytes = (4 * points + analog) * size;
    let sign_byte = match (float, processor) {
        (_, 86) => 0,
        (true, 84) => 3,
        _ => 1,
    };
    let mut out = Vec::with_capacity(frames * points);
    for i in 0..frames {
        for k in 0..points {
            let at = start + i * frame_bytes + (4 * k + 3) * size + sign_byte;
            out.push(bytes.get(at)? & 0x80 != 0);
        }
    }
    Some(out)
}

/// Little-endian (Intel) writer of the parameter section's records.
struct Params {
    bytes: Vec<u8>,
    /// Byte offset of each record's start.
    starts: Vec<usize>,
    /// Byte offsets of each record's "next record" word, to chain them.
    links: Vec<usize>,
}

/// A parameter value: characters (with dimensions), 16-bit integers or 32-bit floats.
enum Value<'a> {
    Int(i16),
    Float(f32),
    Text(&'a str),
    Texts(&'a [String]),
}

impl Params {
    fn group(&mut self, id: i8, name: &str) {
        self.starts.push(self.bytes.len());
        self.bytes.push(name.len() as u8);
        self.bytes.push((-id) as u8);
        self.bytes.extend(name.as_bytes());
        self.links.push(self.bytes.len());
        self.bytes.extend([0, 0]);
        self.bytes.push(0); // no description
    }

    fn param(&mut self, id: i8, name: &str, value: Value) {
        self.starts.push(self.bytes.len());
        self.bytes.push(name.len() as u8);
        self.bytes.push(id as u8);
        self.bytes.extend(name.as_bytes());
        self.links.push(self.bytes.len());
        self.bytes.extend([0, 0]);
        match value {
            Value::Int(v) => {
                self.bytes.extend([2, 0]);
                self.bytes.extend(v.to_le_bytes());
            }
            Value::Float(v) => {
                self.bytes.extend([4, 0]);
                self.bytes.extend(v.to_le_bytes());
            }
            Value::Text(s) => {
                self.bytes.extend([0xFF, 1, s.len() as u8]);
                self.bytes.extend(s.as_bytes());
            }
            Value::Texts(v) => {
                let width = v.iter().map(|s| s.len()).max().unwrap_or(1).max(1);
                self.bytes.extend([0xFF, 2, width as u8, v.len() as u8]);
                for s in v {
                    self.bytes.extend(s.as_bytes());
                    self.bytes
                        .extend(std::iter::repeat_n(b' ', width - s.len()));
                }
            }
        }
        self.bytes.push(0); // no description
    }

    /// Chains the records (each offset word points to the next record; the last is 0).
    fn finish(mut self) -> Vec<u8> {
        for w in 0..self.links.len() {
            let at = self.links[w];
            let next = self.starts.get(w + 1).map_or(0, |&start| start - at);
            self.bytes[at..at + 2].copy_from_slice(&(next as u16).to_le_bytes());
        }
        self.bytes
    }
}

/// The C3D bytes of `m`: header block, parameter section (POINT, ANALOG, and the
/// provenance group), float point data with a residual word (0 valid, -1 missing).
fn c3d_bytes(m: &Markers) -> Result<Vec<u8>> {
    let n = m.markers();
    let frames = m.times.len();
    let too_many = |what: &str, v: usize, max: usize| {
        Error::invalid(format!("C3D {what}"), v, format!("at most {max}"))
    };
    if n > 255 {
        return Err(too_many("markers", n, 255));
    }
    if frames > 65_535 {
        return Err(too_many("frames", frames, 65_535));
    }
    let rate = m.rate() as f32;
    let label_ok = |s: &String| s.is_ascii() && s.len() <= 255;
    let keys: Vec<String> = extra_provenance(m).map(|(k, _)| k.clone()).collect();
    let values: Vec<String> = extra_provenance(m).map(|(_, v)| v.clone()).collect();
    for s in m.labels.iter().chain(&keys).chain(&values) {
        if !label_ok(s) {
            return Err(Error::invalid(
                "C3D text",
                s,
                "ASCII, at most 255 characters",
            ));
        }
    }
    if keys.len() > 255 {
        return Err(too_many("provenance entries", keys.len(), 255));
    }
    let write_params = |data_start: u16| -> Vec<u8> {
        let mut p = Params {
            bytes: Vec::new(),
            starts: Vec::new(),
            links: Vec::new(),
        };
        p.group(1, "POINT");
        p.group(2, "ANALOG");
        p.param(1, "USED", Value::Int(n as i16));
        p.param(1, "SCALE", Value::Float(-1.0));
        p.param(1, "RATE", Value::Float(rate));
        p.param(1, "DATA_START", Value::Int(data_start as i16));
        p.param(1, "FRAMES", Value::Int(frames as u16 as i16));
        p.param(1, "UNITS", Value::Text(m.units.name()));
        p.param(1, "LABELS", Value::Texts(&m.labels));
        p.param(1, "DESCRIPTIONS", Value::Texts(&m.labels));
        p.param(2, "USED", Value::Int(0));
        // No analog channels: ANALOG:RATE / POINT:RATE = 0 analog samples per frame (header).
        p.param(2, "RATE", Value::Float(0.0));
        if !keys.is_empty() {
            p.group(3, C3D_GROUP);
            p.param(3, "KEYS", Value::Texts(&keys));
            p.param(3, "VALUES", Value::Texts(&values));
        }
        let body = p.finish();
        let mut section = vec![0x01, 0x50, 0, 84];
        section.extend(body);
        let blocks = section.len().div_ceil(512);
        section[2] = blocks as u8;
        section.resize(blocks * 512, 0);
        section
    };
    // The parameter section's size does not depend on DATA_START's value.
    let blocks = write_params(0).len() / 512;
    let data_start = (2 + blocks) as u16;
    let params = write_params(data_start);

    let mut header = vec![0u8; 512];
    let put16 = |h: &mut Vec<u8>, word: usize, v: u16| {
        h[2 * word..2 * word + 2].copy_from_slice(&v.to_le_bytes())
    };
    header[0] = 2;
    header[1] = 0x50;
    put16(&mut header, 1, n as u16);
    put16(&mut header, 2, 0);
    put16(&mut header, 3, 1);
    put16(&mut header, 4, frames as u16);
    put16(&mut header, 5, 0);
    header[12..16].copy_from_slice(&(-1.0f32).to_le_bytes());
    put16(&mut header, 8, data_start);
    put16(&mut header, 9, 0);
    header[20..24].copy_from_slice(&rate.to_le_bytes());

    let scale = 1.0 / m.units.to_metres();
    let mut data = Vec::with_capacity(frames * n * 16);
    for f in &m.frames {
        for p in f {
            let (xyz, residual) = match p {
                Some(p) => ([p.x, p.y, p.z].map(|v| (v * scale) as f32), 0.0f32),
                None => ([0.0f32; 3], -1.0f32),
            };
            for v in xyz {
                data.extend(v.to_le_bytes());
            }
            data.extend(residual.to_le_bytes());
        }
    }
    data.resize(data.len().div_ceil(512) * 512, 0);
    let mut out = header;
    out.extend(params);
    out.extend(data);
    Ok(out)
}
