//! The SLP grid CSV ([`Recording`]): the format shared with scripts outside the project,
//! read and written with errors naming the file, line and column of the first problem, and
//! its conversion to and from the [`Markers`] of the other formats.
//!
//! Format (UTF-8): optional leading comment lines starting with `#`, among them
//! `# grid: RxC` (rows x columns) and `# units: m`, `# units: cm` or `# units: mm`, and
//! any other `# key: value` lines, kept as the recording's provenance; a header row `time`
//! followed by `marker[i].x,marker[i].y,marker[i].z` for i = 1..R*C (row-major from the top
//! row, column 1 on the subject's right); one row per frame, time in seconds, strictly
//! increasing. An empty x, y, z triple means the point was not tracked in that frame.
//! Without `# grid:` a 60-point recording is a 10 x 6 grid; other sizes need the line.
//! Positions are held in metres whatever the file's unit.

use super::{Format, Markers, Units, split_cells};
use crate::{Error, Result};
use nalgebra::Point3;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

/// Largest grid side accepted (the marker grid's own limit).
pub const MAX_GRID_SIDE: usize = 16;

/// A structured-light recording: grid points over time, in metres.
#[derive(Clone, Debug, PartialEq)]
pub struct Recording {
    /// Grid size (rows, columns).
    pub grid: (usize, usize),
    /// Frame times [s], strictly increasing.
    pub times: Vec<f64>,
    /// Per frame, per grid point (row-major from the top row): the position [m], or `None`
    /// when the point was not tracked.
    pub frames: Vec<Vec<Option<Point3<f64>>>>,
    /// Unit of the file it was read from (or is to be written in).
    pub units: Units,
    /// How the recording was made: the `# key: value` comment lines other than `grid` and
    /// `units`, in file order (see [`crate::recording`] for the keys `torso synth` writes).
    pub provenance: Vec<(String, String)>,
}

/// Whether a provenance entry can be written as one `# key: value` line and read back: a
/// non-empty key without `:`, tabs or line breaks, a value on one line without tabs. The
/// reader refuses what `Recording::validate` would.
fn provenance_entry_is_valid(key: &str, value: &str) -> bool {
    !key.trim().is_empty()
        && !key.contains([':', '\n', '\r', '\t'])
        && !value.contains(['\n', '\r', '\t'])
}

/// The expected header cell of field `k` (0 = time).
fn header_name(k: usize) -> String {
    if k == 0 {
        "time".into()
    } else {
        let i = (k - 1) / 3 + 1;
        format!("marker[{i}].{}", ["x", "y", "z"][(k - 1) % 3])
    }
}

/// Parses a marker grid `RxC` (also `R x C`, `R X C`) with 1..[`MAX_GRID_SIDE`] rows and
/// columns, the range of the FMU's and the C ABI's `grid.rows` and `grid.cols`; `None` for
/// anything else. The one grid parser of the recordings and the command line.
pub fn parse_grid(s: &str) -> Option<(usize, usize)> {
    let lower = s.trim().to_ascii_lowercase();
    let (r, c) = lower.split_once('x')?;
    let (r, c) = (r.trim().parse().ok()?, c.trim().parse().ok()?);
    let side = 1..=MAX_GRID_SIDE;
    (side.contains(&r) && side.contains(&c)).then_some((r, c))
}

impl Recording {
    /// Number of grid points.
    pub fn points(&self) -> usize {
        self.grid.0 * self.grid.1
    }

    /// Mean sampling rate [Hz] from the mean frame interval.
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

    /// Tracked points over all frames.
    pub fn tracked(&self) -> usize {
        self.frames.iter().flatten().filter(|p| p.is_some()).count()
    }

    /// Reads a recording file.
    pub fn read(path: &Path) -> Result<Recording> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Recording::parse(&text, &path.display().to_string())
    }

    /// Parses recording text; `name` is used in error messages.
    pub fn parse(text: &str, name: &str) -> Result<Recording> {
        let mut grid: Option<(usize, usize)> = None;
        let mut grid_line = 0;
        let mut units = Units::Metres;
        let mut provenance = Vec::new();
        let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
        // Leading comments, then the header.
        let (header_no, header) = loop {
            let Some((no, raw)) = lines.next() else {
                return Err(Error::parse(
                    name,
                    0,
                    0,
                    "no header row (`time,marker[1].x,...`) found",
                ));
            };
            let line = raw.trim_end_matches('\r');
            let Some(comment) = line.strip_prefix('#') else {
                if line.trim().is_empty() {
                    continue;
                }
                break (no, line);
            };
            let body = comment.trim();
            let col_of = |key: &str| line.find(key).map_or(1, |b| b + 1);
            if let Some((key, value)) = body.split_once(':') {
                match key.trim().to_ascii_lowercase().as_str() {
                    "grid" => match parse_grid(value) {
                        Some(g) => {
                            grid = Some(g);
                            grid_line = no;
                        }
                        None => {
                            return Err(Error::parse(
                                name,
                                no,
                                col_of(value.trim()),
                                format!(
                                    "bad grid `{}`: expected ROWSxCOLS with 1..{MAX_GRID_SIDE} each, e.g. `# grid: 10x6`",
                                    value.trim()
                                ),
                            ));
                        }
                    },
                    "units" => {
                        units = match Units::parse(value) {
                            Some(u) => u,
                            None => {
                                let other = value.trim();
                                return Err(Error::parse(
                                    name,
                                    no,
                                    col_of(other),
                                    format!("unknown units `{other}`: expected `m`, `cm` or `mm`"),
                                ));
                            }
                        }
                    }
                    _ => {
                        let (key, value) = (key.trim(), value.trim());
                        if !provenance_entry_is_valid(key, value) {
                            return Err(Error::parse(
                                name,
                                no,
                                1,
                                "comment `# key: value` with an empty key, a tab or a carriage return inside the line",
                            ));
                        }
                        provenance.push((key.to_string(), value.to_string()))
                    }
                }
            }
        };

        // Header.
        let head = split_cells(header, ',');
        for (k, (col, cell)) in head.iter().enumerate() {
            let want = header_name(k);
            if cell.trim() != want {
                return Err(Error::parse(
                    name,
                    header_no,
                    *col,
                    format!(
                        "header cell {} is `{}`, expected `{want}`",
                        k + 1,
                        cell.trim()
                    ),
                ));
            }
        }
        if head.len() < 4 || !(head.len() - 1).is_multiple_of(3) {
            let col = header.chars().count() + 1;
            return Err(Error::parse(
                name,
                header_no,
                col,
                format!(
                    "header ends after {} cells, expected `time` then x, y, z for each grid point (next: `{}`)",
                    head.len(),
                    header_name(head.len())
                ),
            ));
        }
        let points = (head.len() - 1) / 3;
        let grid = match grid {
            Some((r, c)) if r * c == points => (r, c),
            Some((r, c)) => {
                return Err(Error::parse(
                    name,
                    grid_line,
                    1,
                    format!(
                        "grid {r}x{c} has {} points but the header has {points}",
                        r * c
                    ),
                ));
            }
            None if points == 60 => (10, 6),
            None => {
                return Err(Error::parse(
                    name,
                    1,
                    1,
                    format!(
                        "the header has {points} grid points: add a `# grid: ROWSxCOLS` line before it (only 60-point recordings default to 10x6)"
                    ),
                ));
            }
        };

        // Frames.
        let scale = units.to_metres();
        let mut times = Vec::new();
        let mut frames = Vec::new();
        let mut blank_at: Option<usize> = None;
        for (no, raw) in lines {
            let line = raw.trim_end_matches('\r');
            if line.trim().is_empty() {
                blank_at.get_or_insert(no);
                continue;
            }
            if let Some(b) = blank_at {
                return Err(Error::parse(name, b, 1, "empty line between frames"));
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
                let col = if row.len() > head.len() {
                    row[head.len()].0
                } else {
                    line.chars().count() + 1
                };
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
            let number = |k: usize| -> Result<Option<f64>> {
                let (col, cell) = row[k];
                let s = cell.trim();
                if s.is_empty() {
                    return Ok(None);
                }
                let v: f64 = s.parse().map_err(|_| {
                    Error::parse(
                        name,
                        no,
                        col,
                        format!("{}: `{s}` is not a number", header_name(k)),
                    )
                })?;
                if !v.is_finite() {
                    return Err(Error::parse(
                        name,
                        no,
                        col,
                        format!(
                            "{}: `{s}` is not finite (leave the cell empty for an untracked point)",
                            header_name(k)
                        ),
                    ));
                }
                Ok(Some(v))
            };
            let t = number(0)?.ok_or_else(|| Error::parse(name, no, 1, "time: empty cell"))?;
            if let Some(&prev) = times.last()
                && t <= prev
            {
                return Err(Error::parse(
                    name,
                    no,
                    1,
                    format!("time {t} s does not increase (previous frame: {prev} s)"),
                ));
            }
            let mut frame = Vec::with_capacity(points);
            for i in 0..points {
                let k = 1 + 3 * i;
                let xyz = [number(k)?, number(k + 1)?, number(k + 2)?];
                match xyz {
                    [Some(x), Some(y), Some(z)] => {
                        frame.push(Some(Point3::new(x * scale, y * scale, z * scale)))
                    }
                    [None, None, None] => frame.push(None),
                    _ => {
                        let missing = xyz.iter().position(|v| v.is_none()).unwrap_or(0);
                        return Err(Error::parse(
                            name,
                            no,
                            row[k + missing].0,
                            format!(
                                "marker[{}]: partly empty; leave x, y and z all empty for an untracked point",
                                i + 1
                            ),
                        ));
                    }
                }
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
        Ok(Recording {
            grid,
            times,
            frames,
            units,
            provenance,
        })
    }

    /// Checks the invariants a hand-built recording must satisfy before writing or fitting.
    pub fn validate(&self) -> Result<()> {
        let (r, c) = self.grid;
        if !(1..=MAX_GRID_SIDE).contains(&r) || !(1..=MAX_GRID_SIDE).contains(&c) {
            return Err(Error::invalid(
                "recording grid",
                format!("{r}x{c}"),
                format!("1..{MAX_GRID_SIDE} rows and columns"),
            ));
        }
        self.validate_frames()
    }

    /// The checks of [`Recording::validate`] other than the grid's size: times, frames,
    /// provenance. A recording of a marker set other than the grid holds its markers as one
    /// column, `grid = (markers, 1)`, which may exceed the grid's limit.
    pub fn validate_frames(&self) -> Result<()> {
        let (r, c) = self.grid;
        if r == 0 || c == 0 {
            return Err(Error::invalid(
                "recording grid",
                format!("{r}x{c}"),
                "at least one point",
            ));
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
        for (k, v) in &self.provenance {
            if !provenance_entry_is_valid(k, v) {
                return Err(Error::invalid(
                    "recording provenance",
                    format!("{k:?}: {v:?}"),
                    "a non-empty key without `:`, tabs or line breaks; a value on one line without tabs",
                ));
            }
        }
        for (i, f) in self.frames.iter().enumerate() {
            if f.len() != r * c {
                return Err(Error::invalid(
                    format!("recording frame {}", i + 1),
                    format!("{} points", f.len()),
                    format!("{} points ({r}x{c})", r * c),
                ));
            }
            if f.iter()
                .flatten()
                .any(|p| p.coords.iter().any(|v| !v.is_finite()))
            {
                return Err(Error::invalid(
                    format!("recording frame {}", i + 1),
                    "a non-finite coordinate",
                    "finite coordinates or untracked points",
                ));
            }
        }
        Ok(())
    }

    /// The file text in `self.units` (positions to 0.1 um, times to 1 ns).
    pub fn to_csv(&self) -> Result<String> {
        self.validate()?;
        let scale = 1.0 / self.units.to_metres();
        let digits = match self.units {
            Units::Metres => 7,
            Units::Centimetres => 5,
            Units::Millimetres => 4,
        };
        let mut s = String::new();
        let (r, c) = self.grid;
        // Writing to a String cannot fail.
        let _ = writeln!(s, "# grid: {r}x{c}");
        let _ = writeln!(s, "# units: {}", self.units.name());
        for (k, v) in &self.provenance {
            let _ = writeln!(s, "# {k}: {v}");
        }
        s.push_str("time");
        for k in 1..=3 * self.points() {
            s.push(',');
            s.push_str(&header_name(k));
        }
        s.push('\n');
        for (t, frame) in self.times.iter().zip(&self.frames) {
            let _ = write!(s, "{t:.9}");
            for p in frame {
                match p {
                    Some(p) => {
                        for v in p.coords.iter() {
                            let _ = write!(s, ",{:.*}", digits, v * scale);
                        }
                    }
                    None => s.push_str(",,,"),
                }
            }
            s.push('\n');
        }
        Ok(s)
    }

    /// Writes the recording (creating the parent directory).
    pub fn write(&self, path: &Path) -> Result<()> {
        let text = self.to_csv()?;
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        std::fs::write(path, text).map_err(|e| Error::io(path, e))
    }
}

/// The label of grid marker `k` (0-based): `marker[k+1]`.
pub fn grid_label(k: usize) -> String {
    format!("marker[{}]", k + 1)
}

impl Markers {
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

    /// The grid the recording names (`grid` provenance), or 10 x 6 for 60 markers.
    pub fn grid_shape(&self) -> Option<(usize, usize)> {
        match self.provenance_value("grid") {
            Some(g) => parse_grid(g),
            None if self.markers() == 60 => Some((10, 6)),
            None => None,
        }
    }
}
