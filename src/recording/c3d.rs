//! The C3D binary marker file (Vicon, Qualisys): read with `c3dio` (the file's size and the
//! residual word's sign checked here), written here (Intel, float points, residual word -1
//! for a missing point, the provenance in the parameter group [`C3D_GROUP`]).

use super::{Format, Markers, Units, extra_provenance};
use crate::{Error, Result};
use nalgebra::Point3;

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
pub(super) fn c3d_bytes(m: &Markers) -> Result<Vec<u8>> {
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
