//! Surface file formats: Wavefront OBJ, STL (binary and ASCII), OFF and legacy VTK PolyData
//! (ASCII), read and written; vertex welding for formats that store triangle soups. Malformed
//! input is reported as [`Error::Parse`] naming the file, 1-based line and column (the record
//! number for binary STL).

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use nalgebra::Point3;

use super::TriMesh;
use crate::{Error, Result};

/// Surface file formats known to [`read()`] and [`write()`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Wavefront OBJ (`v` and `f` records).
    Obj,
    /// Binary STL (written by [`write()`]; reading detects binary or ASCII).
    Stl,
    /// ASCII STL.
    StlAscii,
    /// Object File Format.
    Off,
    /// Legacy VTK PolyData, ASCII.
    Vtk,
}

impl Format {
    /// The format named by a file's extension (`obj`, `stl`, `off`, `vtk`, case-insensitive).
    pub fn from_path(path: &Path) -> Result<Format> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        match ext.as_str() {
            "obj" => Ok(Format::Obj),
            "stl" => Ok(Format::Stl),
            "off" => Ok(Format::Off),
            "vtk" => Ok(Format::Vtk),
            _ => Err(Error::invalid(
                format!("extension of {}", path.display()),
                format!("{ext:?}"),
                "one of obj, stl, off, vtk",
            )),
        }
    }
}

/// Reads a surface, choosing the format by extension. STL triangle soups are welded exactly
/// (tolerance 0); use [`read_stl`] for a tolerance.
pub fn read(path: impl AsRef<Path>) -> Result<TriMesh> {
    let path = path.as_ref();
    let format = Format::from_path(path)?;
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let name = path.display().to_string();
    match format {
        Format::Obj => parse_obj(&as_text(&bytes, &name)?, &name),
        Format::Stl | Format::StlAscii => parse_stl(&bytes, &name, 0.0),
        Format::Off => parse_off(&as_text(&bytes, &name)?, &name),
        Format::Vtk => parse_vtk(&as_text(&bytes, &name)?, &name),
    }
}

/// Reads an STL file (binary or ASCII) and welds vertices closer than `weld_tolerance`.
pub fn read_stl(path: impl AsRef<Path>, weld_tolerance: f64) -> Result<TriMesh> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_stl(&bytes, &path.display().to_string(), weld_tolerance)
}

/// Writes a surface, choosing the format by extension (`.stl` is written binary).
pub fn write(mesh: &TriMesh, path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    write_as(mesh, path, Format::from_path(path)?)
}

/// Writes a surface in the given format.
pub fn write_as(mesh: &TriMesh, path: impl AsRef<Path>, format: Format) -> Result<()> {
    let path = path.as_ref();
    let bytes = match format {
        Format::Obj => to_obj(mesh).into_bytes(),
        Format::Stl => to_stl_binary(mesh),
        Format::StlAscii => to_stl_ascii(mesh).into_bytes(),
        Format::Off => to_off(mesh).into_bytes(),
        Format::Vtk => to_vtk(mesh).into_bytes(),
    };
    std::fs::write(path, bytes).map_err(|e| Error::io(path, e))
}

fn as_text(bytes: &[u8], name: &str) -> Result<String> {
    String::from_utf8(bytes.to_vec()).map_err(|e| {
        let upto = &bytes[..e.utf8_error().valid_up_to()];
        let line = upto.iter().filter(|&&b| b == b'\n').count() + 1;
        let column = upto.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
        Error::parse(name, line, column, "invalid UTF-8 text")
    })
}

/// Whitespace-separated tokens of one line with their 1-based columns.
fn tokens(line: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, ch) in line.char_indices() {
        if ch.is_whitespace() {
            if let Some(s) = start.take() {
                out.push((s + 1, &line[s..i]));
            }
        } else if start.is_none() {
            start = Some(i);
        }
    }
    if let Some(s) = start {
        out.push((s + 1, &line[s..]));
    }
    out.into_iter()
}

fn parse_f64(tok: &str, name: &str, line: usize, col: usize, what: &str) -> Result<f64> {
    match tok.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(Error::parse(
            name,
            line,
            col,
            format!("expected a finite number for {what}, found {tok:?}"),
        )),
    }
}

// ---------------------------------------------------------------------------------------------
// OBJ

/// Parses Wavefront OBJ text: `v x y z [w]` and `f` records with `a`, `a/b`, `a//c`, `a/b/c`
/// corners, 1-based or negative (relative) indices; polygons are fan-triangulated. Other
/// records (vt, vn, g, o, s, usemtl, mtllib, l, ...) are ignored.
pub fn parse_obj(text: &str, name: &str) -> Result<TriMesh> {
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for (ln, raw) in text.lines().enumerate() {
        let line = ln + 1;
        let content = raw.split('#').next().unwrap_or("");
        let mut toks = tokens(content);
        let Some((_, key)) = toks.next() else {
            continue;
        };
        match key {
            "v" => {
                let mut c = [0.0; 3];
                for (k, ck) in c.iter_mut().enumerate() {
                    let (col, t) = toks.next().ok_or_else(|| {
                        Error::parse(
                            name,
                            line,
                            raw.len() + 1,
                            format!("vertex needs 3 coordinates, found {k}"),
                        )
                    })?;
                    *ck = parse_f64(t, name, line, col, "a vertex coordinate")?;
                }
                vertices.push(Point3::new(c[0], c[1], c[2]));
            }
            "f" => {
                let mut idx = Vec::with_capacity(4);
                for (col, t) in toks {
                    let first = t.split('/').next().unwrap_or("");
                    let i: i64 = first.parse().map_err(|_| {
                        Error::parse(
                            name,
                            line,
                            col,
                            format!("expected a vertex index, found {t:?}"),
                        )
                    })?;
                    let n = vertices.len() as i64;
                    let resolved = if i > 0 { i - 1 } else { n + i };
                    if i == 0 || resolved < 0 || resolved >= n {
                        return Err(Error::parse(
                            name,
                            line,
                            col,
                            format!("vertex index {i} out of range: {n} vertices defined so far"),
                        ));
                    }
                    idx.push(resolved as u32);
                }
                if idx.len() < 3 {
                    return Err(Error::parse(
                        name,
                        line,
                        1,
                        format!("face needs at least 3 vertices, found {}", idx.len()),
                    ));
                }
                for k in 1..idx.len() - 1 {
                    triangles.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok(TriMesh {
        vertices,
        triangles,
    })
}

/// OBJ text of a surface (`v` and 1-based `f` records).
pub fn to_obj(mesh: &TriMesh) -> String {
    let mut s = String::with_capacity(mesh.vertices.len() * 40 + mesh.triangles.len() * 24);
    for p in &mesh.vertices {
        let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
    }
    for t in &mesh.triangles {
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

// ---------------------------------------------------------------------------------------------
// STL

/// Parses STL bytes, binary when the size matches the binary layout (84 + 50 n bytes),
/// otherwise ASCII; vertices closer than `weld_tolerance` are merged and triangles that
/// collapse are dropped.
pub fn parse_stl(bytes: &[u8], name: &str, weld_tolerance: f64) -> Result<TriMesh> {
    let binary_size = (bytes.len() >= 84).then(|| {
        84 + 50 * u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize
    });
    let looks_ascii = bytes.trim_ascii_start().starts_with(b"solid");
    let soup = if binary_size == Some(bytes.len()) && !(looks_ascii && ascii_facets(bytes)) {
        parse_stl_binary(bytes, name)?
    } else if looks_ascii {
        parse_stl_ascii(&as_text(bytes, name)?, name)?
    } else if bytes.len() < 84 {
        return Err(Error::parse(
            name,
            0,
            0,
            format!(
                "binary STL shorter than its 84-byte header ({} bytes)",
                bytes.len()
            ),
        ));
    } else {
        let n = (bytes.len() - 84) / 50;
        return Err(Error::parse(
            name,
            0,
            0,
            format!(
                "record {}: binary STL truncated: header announces {} triangles, file holds {} bytes ({} whole records)",
                n + 1,
                u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]),
                bytes.len(),
                n
            ),
        ));
    };
    Ok(weld(&soup, weld_tolerance))
}

fn ascii_facets(bytes: &[u8]) -> bool {
    bytes.windows(5).take(4096).any(|w| w == b"facet")
}

fn parse_stl_binary(bytes: &[u8], name: &str) -> Result<TriMesh> {
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
    let mut vertices = Vec::with_capacity(3 * n);
    let mut triangles = Vec::with_capacity(n);
    for r in 0..n {
        let rec = &bytes[84 + 50 * r..84 + 50 * (r + 1)];
        for k in 0..3 {
            let mut c = [0.0; 3];
            for (j, cj) in c.iter_mut().enumerate() {
                let o = 12 + 12 * k + 4 * j;
                let v = f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]);
                if !v.is_finite() {
                    return Err(Error::parse(
                        name,
                        0,
                        0,
                        format!(
                            "record {}: vertex {} has a non-finite coordinate",
                            r + 1,
                            k + 1
                        ),
                    ));
                }
                *cj = v as f64;
            }
            vertices.push(Point3::new(c[0], c[1], c[2]));
        }
        let b = 3 * r as u32;
        triangles.push([b, b + 1, b + 2]);
    }
    Ok(TriMesh {
        vertices,
        triangles,
    })
}

fn parse_stl_ascii(text: &str, name: &str) -> Result<TriMesh> {
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    let mut in_loop: Option<(usize, usize)> = None;
    let mut seen_solid = false;
    for (ln, raw) in text.lines().enumerate() {
        let line = ln + 1;
        let mut toks = tokens(raw);
        let Some((col, key)) = toks.next() else {
            continue;
        };
        match key {
            "solid" => seen_solid = true,
            "facet" | "endfacet" | "endsolid" => {}
            "outer" => in_loop = Some((line, vertices.len())),
            "vertex" => {
                if in_loop.is_none() {
                    return Err(Error::parse(
                        name,
                        line,
                        col,
                        "`vertex` outside an `outer loop`",
                    ));
                }
                let mut c = [0.0; 3];
                for (k, ck) in c.iter_mut().enumerate() {
                    let (col, t) = toks.next().ok_or_else(|| {
                        Error::parse(
                            name,
                            line,
                            raw.len() + 1,
                            format!("vertex needs 3 coordinates, found {k}"),
                        )
                    })?;
                    *ck = parse_f64(t, name, line, col, "a vertex coordinate")?;
                }
                vertices.push(Point3::new(c[0], c[1], c[2]));
            }
            "endloop" => {
                let Some((_, start)) = in_loop.take() else {
                    return Err(Error::parse(
                        name,
                        line,
                        col,
                        "`endloop` without `outer loop`",
                    ));
                };
                let n = vertices.len() - start;
                if n != 3 {
                    return Err(Error::parse(
                        name,
                        line,
                        col,
                        format!("facet loop has {n} vertices, expected 3"),
                    ));
                }
                let b = start as u32;
                triangles.push([b, b + 1, b + 2]);
            }
            other => {
                return Err(Error::parse(
                    name,
                    line,
                    col,
                    format!("unexpected keyword {other:?} in ASCII STL"),
                ));
            }
        }
        if !seen_solid {
            return Err(Error::parse(
                name,
                line,
                1,
                "ASCII STL must start with `solid`",
            ));
        }
    }
    if let Some((line, _)) = in_loop {
        return Err(Error::parse(
            name,
            line,
            1,
            "`outer loop` never closed by `endloop`",
        ));
    }
    Ok(TriMesh {
        vertices,
        triangles,
    })
}

/// Binary STL bytes (80-byte header, facet normals from the geometry).
pub fn to_stl_binary(mesh: &TriMesh) -> Vec<u8> {
    let mut out = Vec::with_capacity(84 + 50 * mesh.triangles.len());
    let mut header = [0u8; 80];
    let tag = b"binary STL written by breathing-torso";
    header[..tag.len()].copy_from_slice(tag);
    out.extend_from_slice(&header);
    out.extend_from_slice(&(mesh.triangles.len() as u32).to_le_bytes());
    for t in 0..mesh.triangles.len() {
        let n = mesh.face_normal(t);
        for c in n.iter() {
            out.extend_from_slice(&(*c as f32).to_le_bytes());
        }
        for p in mesh.corners(t) {
            for c in p.coords.iter() {
                out.extend_from_slice(&(*c as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    out
}

/// ASCII STL text.
pub fn to_stl_ascii(mesh: &TriMesh) -> String {
    let mut s = String::from("solid breathing_torso\n");
    for t in 0..mesh.triangles.len() {
        let n = mesh.face_normal(t);
        let _ = writeln!(s, "  facet normal {} {} {}\n    outer loop", n.x, n.y, n.z);
        for p in mesh.corners(t) {
            let _ = writeln!(s, "      vertex {} {} {}", p.x, p.y, p.z);
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    s.push_str("endsolid breathing_torso\n");
    s
}

/// Merges vertices closer than `tolerance` (exactly equal ones when `tolerance` is 0), keeping
/// the first of each cluster, and drops triangles that become degenerate. Uses a uniform grid
/// of cell size `tolerance`, so each query visits 27 cells.
pub fn weld(mesh: &TriMesh, tolerance: f64) -> TriMesh {
    let tol = if tolerance.is_finite() && tolerance > 0.0 {
        tolerance
    } else {
        0.0
    };
    let mut map = vec![0u32; mesh.vertices.len()];
    let mut vertices: Vec<Point3<f64>> = Vec::with_capacity(mesh.vertices.len());
    if tol == 0.0 {
        let mut seen: HashMap<[u64; 3], u32> = HashMap::with_capacity(mesh.vertices.len());
        for (i, p) in mesh.vertices.iter().enumerate() {
            let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            map[i] = *seen.entry(key).or_insert_with(|| {
                vertices.push(*p);
                (vertices.len() - 1) as u32
            });
        }
    } else {
        let cell = |p: &Point3<f64>| -> [i64; 3] {
            [
                (p.x / tol).floor() as i64,
                (p.y / tol).floor() as i64,
                (p.z / tol).floor() as i64,
            ]
        };
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::with_capacity(mesh.vertices.len());
        for (i, p) in mesh.vertices.iter().enumerate() {
            let c = cell(p);
            let mut found = None;
            'search: for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        // saturating: far coordinates over a fine tolerance reach i64::MAX
                        let key = [
                            c[0].saturating_add(dx),
                            c[1].saturating_add(dy),
                            c[2].saturating_add(dz),
                        ];
                        if let Some(list) = grid.get(&key) {
                            for &j in list {
                                if (vertices[j as usize] - p).norm() <= tol {
                                    found = Some(j);
                                    break 'search;
                                }
                            }
                        }
                    }
                }
            }
            map[i] = found.unwrap_or_else(|| {
                vertices.push(*p);
                let j = (vertices.len() - 1) as u32;
                grid.entry(c).or_default().push(j);
                j
            });
        }
    }
    let triangles = mesh
        .triangles
        .iter()
        .map(|t| [map[t[0] as usize], map[t[1] as usize], map[t[2] as usize]])
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
        .collect();
    TriMesh {
        vertices,
        triangles,
    }
}

// ---------------------------------------------------------------------------------------------
// Token stream for OFF and VTK

struct Stream<'a> {
    name: &'a str,
    toks: Vec<(usize, usize, &'a str)>,
    pos: usize,
    last_line: usize,
}

impl<'a> Stream<'a> {
    fn new(text: &'a str, name: &'a str, skip_lines: usize, comments: bool) -> Self {
        let mut toks = Vec::new();
        let mut last_line = 0;
        for (ln, raw) in text.lines().enumerate().skip(skip_lines) {
            let content = if comments {
                raw.split('#').next().unwrap_or("")
            } else {
                raw
            };
            for (col, t) in tokens(content) {
                toks.push((ln + 1, col, t));
            }
            last_line = ln + 1;
        }
        Stream {
            name,
            toks,
            pos: 0,
            last_line,
        }
    }

    fn next(&mut self, what: &str) -> Result<(usize, usize, &'a str)> {
        let t = self.toks.get(self.pos).copied().ok_or_else(|| {
            Error::parse(
                self.name,
                self.last_line.max(1),
                0,
                format!("unexpected end of file, expected {what}"),
            )
        })?;
        self.pos += 1;
        Ok(t)
    }

    /// Tokens not read yet: the most items any count in the file can still describe, so
    /// that a header count never reserves more memory than the file can fill.
    fn remaining(&self) -> usize {
        self.toks.len() - self.pos
    }

    fn peek(&self) -> Option<&'a str> {
        self.toks.get(self.pos).map(|t| t.2)
    }

    fn f64(&mut self, what: &str) -> Result<f64> {
        let (l, c, t) = self.next(what)?;
        parse_f64(t, self.name, l, c, what)
    }

    fn usize(&mut self, what: &str) -> Result<(usize, usize, usize)> {
        let (l, c, t) = self.next(what)?;
        t.parse::<usize>().map(|v| (v, l, c)).map_err(|_| {
            Error::parse(
                self.name,
                l,
                c,
                format!("expected a non-negative integer for {what}, found {t:?}"),
            )
        })
    }

    fn index(&mut self, n: usize, what: &str) -> Result<u32> {
        let (v, l, c) = self.usize(what)?;
        if v >= n {
            return Err(Error::parse(
                self.name,
                l,
                c,
                format!("{what} {v} out of range [0, {n})"),
            ));
        }
        Ok(v as u32)
    }

    fn keyword(&mut self, expected: &str) -> Result<()> {
        let (l, c, t) = self.next(expected)?;
        if t.eq_ignore_ascii_case(expected) {
            Ok(())
        } else {
            Err(Error::parse(
                self.name,
                l,
                c,
                format!("expected `{expected}`, found {t:?}"),
            ))
        }
    }
}

fn fan(idx: &[u32], out: &mut Vec<[u32; 3]>) {
    for k in 1..idx.len().saturating_sub(1) {
        out.push([idx[0], idx[k], idx[k + 1]]);
    }
}

// ---------------------------------------------------------------------------------------------
// OFF

/// Parses OFF text (`OFF`, counts `nv nf ne`, vertices, faces `n i1 .. in [colour]`);
/// polygons are fan-triangulated, `#` starts a comment.
pub fn parse_off(text: &str, name: &str) -> Result<TriMesh> {
    let mut s = Stream::new(text, name, 0, true);
    let (l, c, head) = s.next("the OFF header")?;
    if head != "OFF" {
        let msg = if head.ends_with("OFF") {
            format!("unsupported OFF variant {head:?}: only plain `OFF` is read")
        } else {
            format!("expected `OFF` header, found {head:?}")
        };
        return Err(Error::parse(name, l, c, msg));
    }
    let (nv, ..) = s.usize("the vertex count")?;
    let (nf, ..) = s.usize("the face count")?;
    let _ = s.usize("the edge count")?;
    let mut vertices = Vec::with_capacity(nv.min(s.remaining() / 3));
    for _ in 0..nv {
        let x = s.f64("a vertex coordinate")?;
        let y = s.f64("a vertex coordinate")?;
        let z = s.f64("a vertex coordinate")?;
        vertices.push(Point3::new(x, y, z));
    }
    let mut triangles = Vec::with_capacity(nf.min(s.remaining() / 4));
    for _ in 0..nf {
        let (k, l, c) = s.usize("the face's vertex count")?;
        if k < 3 {
            return Err(Error::parse(
                name,
                l,
                c,
                format!("face needs at least 3 vertices, found {k}"),
            ));
        }
        let idx = (0..k)
            .map(|_| s.index(nv, "vertex index"))
            .collect::<Result<Vec<_>>>()?;
        fan(&idx, &mut triangles);
        // Optional per-face colour: skip numbers remaining on the same line.
        while s.toks.get(s.pos).is_some_and(|t| t.0 == l) {
            s.pos += 1;
        }
    }
    Ok(TriMesh {
        vertices,
        triangles,
    })
}

/// OFF text of a surface.
pub fn to_off(mesh: &TriMesh) -> String {
    let mut s = format!(
        "OFF\n{} {} {}\n",
        mesh.vertices.len(),
        mesh.triangles.len(),
        mesh.edges().len()
    );
    for p in &mesh.vertices {
        let _ = writeln!(s, "{} {} {}", p.x, p.y, p.z);
    }
    for t in &mesh.triangles {
        let _ = writeln!(s, "3 {} {} {}", t[0], t[1], t[2]);
    }
    s
}

// ---------------------------------------------------------------------------------------------
// VTK PolyData

/// Parses legacy ASCII VTK PolyData: `POINTS n type`, and `POLYGONS` either in the classic
/// `n size` + `k i1 .. ik` layout or the 5.1 `OFFSETS`/`CONNECTIVITY` layout; `TRIANGLE_STRIPS`
/// are unrolled; polygons are fan-triangulated; `VERTICES`, `LINES` and attribute data are
/// skipped.
pub fn parse_vtk(text: &str, name: &str) -> Result<TriMesh> {
    let mut lines = text.lines();
    let first = lines.next().unwrap_or("");
    if !first.starts_with("# vtk DataFile") {
        return Err(Error::parse(
            name,
            1,
            1,
            "expected `# vtk DataFile Version x.x`",
        ));
    }
    let mut s = Stream::new(text, name, 2, false);
    s.keyword("ASCII")?;
    s.keyword("DATASET")?;
    let (l, c, kind) = s.next("a dataset type")?;
    if !kind.eq_ignore_ascii_case("POLYDATA") {
        return Err(Error::parse(
            name,
            l,
            c,
            format!("only `DATASET POLYDATA` is supported, found {kind:?}"),
        ));
    }
    let mut vertices: Vec<Point3<f64>> = Vec::new();
    let mut triangles = Vec::new();
    while let Some(key) = s.peek() {
        let (l, c, _) = s.next("a section keyword")?;
        match key.to_ascii_uppercase().as_str() {
            "POINTS" => {
                let (n, ..) = s.usize("the point count")?;
                let _ = s.next("the point data type")?;
                vertices.reserve(n.min(s.remaining() / 3));
                for _ in 0..n {
                    let x = s.f64("a point coordinate")?;
                    let y = s.f64("a point coordinate")?;
                    let z = s.f64("a point coordinate")?;
                    vertices.push(Point3::new(x, y, z));
                }
            }
            k @ ("POLYGONS" | "TRIANGLE_STRIPS" | "VERTICES" | "LINES") => {
                let keep = k == "POLYGONS" || k == "TRIANGLE_STRIPS";
                let strip = k == "TRIANGLE_STRIPS";
                let (a, ..) = s.usize("the cell count")?;
                let (b, ..) = s.usize("the cell list size")?;
                let nv = vertices.len();
                let cells: Vec<Vec<u32>> =
                    if s.peek().is_some_and(|t| t.eq_ignore_ascii_case("OFFSETS")) {
                        s.next("OFFSETS")?;
                        let _ = s.next("the offsets type")?;
                        let mut offs = Vec::with_capacity(a.min(s.remaining()));
                        for _ in 0..a {
                            offs.push(s.usize("an offset")?);
                        }
                        s.keyword("CONNECTIVITY")?;
                        let _ = s.next("the connectivity type")?;
                        let conn = (0..b)
                            .map(|_| s.index(nv, "point index"))
                            .collect::<Result<Vec<_>>>()?;
                        let mut cells = Vec::with_capacity(offs.len().saturating_sub(1));
                        for w in offs.windows(2) {
                            let ((o0, ..), (o1, l1, c1)) = (w[0], w[1]);
                            if o1 < o0 || o1 > conn.len() {
                                return Err(Error::parse(
                                    name,
                                    l1,
                                    c1,
                                    format!("offset {o1} out of range [{o0}, {}]", conn.len()),
                                ));
                            }
                            cells.push(conn[o0..o1].to_vec());
                        }
                        cells
                    } else {
                        let mut cells = Vec::with_capacity(a.min(s.remaining()));
                        let mut used = 0usize;
                        for _ in 0..a {
                            let (k, ..) = s.usize("the cell's point count")?;
                            used = used.saturating_add(k).saturating_add(1);
                            cells.push(
                                (0..k)
                                    .map(|_| s.index(nv, "point index"))
                                    .collect::<Result<Vec<_>>>()?,
                            );
                        }
                        if used != b {
                            return Err(Error::parse(
                                name,
                                l,
                                c,
                                format!("{k} size {b} does not match its cells ({used} numbers)"),
                            ));
                        }
                        cells
                    };
                if keep {
                    for cell in cells {
                        if strip {
                            for i in 0..cell.len().saturating_sub(2) {
                                let t = if i % 2 == 0 {
                                    [cell[i], cell[i + 1], cell[i + 2]]
                                } else {
                                    [cell[i + 1], cell[i], cell[i + 2]]
                                };
                                triangles.push(t);
                            }
                        } else {
                            fan(&cell, &mut triangles);
                        }
                    }
                }
            }
            "POINT_DATA" | "CELL_DATA" | "METADATA" | "FIELD" => break,
            other => {
                return Err(Error::parse(
                    name,
                    l,
                    c,
                    format!("unexpected VTK keyword {other:?}"),
                ));
            }
        }
    }
    Ok(TriMesh {
        vertices,
        triangles,
    })
}

/// Legacy ASCII VTK PolyData text of a surface.
pub fn to_vtk(mesh: &TriMesh) -> String {
    let mut s = format!(
        "# vtk DataFile Version 3.0\nbreathing-torso surface\nASCII\nDATASET POLYDATA\nPOINTS {} double\n",
        mesh.vertices.len()
    );
    for p in &mesh.vertices {
        let _ = writeln!(s, "{} {} {}", p.x, p.y, p.z);
    }
    let _ = writeln!(
        s,
        "POLYGONS {} {}",
        mesh.triangles.len(),
        4 * mesh.triangles.len()
    );
    for t in &mesh.triangles {
        let _ = writeln!(s, "3 {} {} {}", t[0], t[1], t[2]);
    }
    s
}
