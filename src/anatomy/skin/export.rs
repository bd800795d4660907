//! Writers for triangle meshes and polylines: Wavefront OBJ for a static scene, VTK XML
//! PolyData (.vtp, ASCII) frames with a ParaView .pvd index for animations.

use crate::{Error, Result};
use nalgebra::Point3;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A named triangle mesh to export.
#[derive(Clone, Copy, Debug)]
pub struct MeshPart<'a> {
    /// Object name written to the file.
    pub name: &'a str,
    /// Vertex positions.
    pub vertices: &'a [Point3<f64>],
    /// Triangles indexing `vertices`.
    pub triangles: &'a [[u32; 3]],
}

/// A named polyline (e.g. a rib centreline) to export.
#[derive(Clone, Copy, Debug)]
pub struct PolylinePart<'a> {
    /// Object name written to the file.
    pub name: &'a str,
    /// The points, joined in order.
    pub points: &'a [Point3<f64>],
}

fn write_file(path: &Path, text: &str) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    std::fs::write(path, text).map_err(|e| Error::io(path, e))
}

fn check_indices(name: &str, n: usize, triangles: &[[u32; 3]]) -> Result<()> {
    if let Some(t) = triangles
        .iter()
        .find(|t| t.iter().any(|&i| i as usize >= n))
    {
        return Err(Error::invalid(
            format!("{name} triangle"),
            format!("{t:?}"),
            format!("indices below {n}"),
        ));
    }
    Ok(())
}

/// Writes meshes and polylines into one OBJ file (metres), one `o` object each.
pub fn write_obj(path: &Path, meshes: &[MeshPart], polylines: &[PolylinePart]) -> Result<()> {
    let mut s = String::from(
        "# breathing-torso export, units: metres, frame: x anterior, y superior, z right\n",
    );
    let mut base = 1usize;
    for m in meshes {
        check_indices(m.name, m.vertices.len(), m.triangles)?;
        let _ = writeln!(s, "o {}", m.name);
        for v in m.vertices {
            let _ = writeln!(s, "v {:.6} {:.6} {:.6}", v.x, v.y, v.z);
        }
        for t in m.triangles {
            let _ = writeln!(
                s,
                "f {} {} {}",
                t[0] as usize + base,
                t[1] as usize + base,
                t[2] as usize + base
            );
        }
        base += m.vertices.len();
    }
    for p in polylines {
        let _ = writeln!(s, "o {}", p.name);
        for v in p.points {
            let _ = writeln!(s, "v {:.6} {:.6} {:.6}", v.x, v.y, v.z);
        }
        if p.points.len() >= 2 {
            s.push('l');
            for i in 0..p.points.len() {
                let _ = write!(s, " {}", base + i);
            }
            s.push('\n');
        }
        base += p.points.len();
    }
    write_file(path, &s)
}

/// Writes one VTK XML PolyData file (ASCII): triangles, optional polylines (indices into
/// `vertices`) and named per-point scalar arrays.
pub fn write_vtp(
    path: &Path,
    vertices: &[Point3<f64>],
    triangles: &[[u32; 3]],
    lines: &[Vec<u32>],
    point_scalars: &[(&str, &[f64])],
) -> Result<()> {
    let n = vertices.len();
    check_indices("vtp", n, triangles)?;
    for (name, v) in point_scalars {
        if v.len() != n {
            return Err(Error::invalid(
                format!("point array `{name}`"),
                v.len(),
                format!("{n} values"),
            ));
        }
    }
    if let Some(l) = lines.iter().find(|l| l.iter().any(|&i| i as usize >= n)) {
        return Err(Error::invalid(
            "vtp polyline",
            format!("{l:?}"),
            format!("indices below {n}"),
        ));
    }
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n<PolyData>\n");
    let _ = writeln!(
        s,
        "<Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"0\" NumberOfLines=\"{}\" NumberOfStrips=\"0\" NumberOfPolys=\"{}\">",
        lines.len(),
        triangles.len()
    );
    if !point_scalars.is_empty() {
        s.push_str("<PointData>\n");
        for (name, v) in point_scalars {
            let _ = writeln!(
                s,
                "<DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
            );
            for x in v.iter() {
                let _ = write!(s, "{x:.6e} ");
            }
            s.push_str("\n</DataArray>\n");
        }
        s.push_str("</PointData>\n");
    }
    s.push_str(
        "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n",
    );
    for v in vertices {
        let _ = writeln!(s, "{:.6} {:.6} {:.6}", v.x, v.y, v.z);
    }
    s.push_str("</DataArray>\n</Points>\n");
    let cells = |s: &mut String, tag: &str, conn: Vec<u32>, offsets: Vec<usize>| {
        let _ = writeln!(
            s,
            "<{tag}>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
        );
        for c in conn {
            let _ = write!(s, "{c} ");
        }
        s.push_str(
            "\n</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n",
        );
        for o in offsets {
            let _ = write!(s, "{o} ");
        }
        let _ = writeln!(s, "\n</DataArray>\n</{tag}>");
    };
    if !lines.is_empty() {
        let mut off = 0;
        let offsets = lines.iter().map(|l| {
            off += l.len();
            off
        });
        let offsets: Vec<usize> = offsets.collect();
        cells(
            &mut s,
            "Lines",
            lines.iter().flatten().copied().collect(),
            offsets,
        );
    }
    if !triangles.is_empty() {
        cells(
            &mut s,
            "Polys",
            triangles.iter().flatten().copied().collect(),
            (1..=triangles.len()).map(|i| 3 * i).collect(),
        );
    }
    s.push_str("</Piece>\n</PolyData>\n</VTKFile>\n");
    write_file(path, &s)
}

/// An animation written as numbered .vtp frames plus a .pvd index that ParaView opens as a
/// time series.
#[derive(Clone, Debug)]
pub struct VtkSeries {
    dir: PathBuf,
    stem: String,
    frames: Vec<(f64, String)>,
}

impl VtkSeries {
    /// A new series writing `DIR/STEM_NNNNN.vtp` and `DIR/STEM.pvd`.
    pub fn new(dir: impl Into<PathBuf>, stem: &str) -> Self {
        VtkSeries {
            dir: dir.into(),
            stem: stem.to_string(),
            frames: Vec::new(),
        }
    }

    /// Writes one frame at time `t` [s].
    pub fn add_frame(
        &mut self,
        t: f64,
        vertices: &[Point3<f64>],
        triangles: &[[u32; 3]],
        lines: &[Vec<u32>],
        point_scalars: &[(&str, &[f64])],
    ) -> Result<()> {
        if !t.is_finite() {
            return Err(Error::invalid(
                "frame time",
                t,
                "a finite number of seconds",
            ));
        }
        let file = format!("{}_{:05}.vtp", self.stem, self.frames.len());
        write_vtp(
            &self.dir.join(&file),
            vertices,
            triangles,
            lines,
            point_scalars,
        )?;
        self.frames.push((t, file));
        Ok(())
    }

    /// Writes the .pvd index and returns its path.
    pub fn finish(&self) -> Result<PathBuf> {
        let mut s = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n",
        );
        for (t, f) in &self.frames {
            let _ = writeln!(
                s,
                "<DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"{f}\"/>"
            );
        }
        s.push_str("</Collection>\n</VTKFile>\n");
        let path = self.dir.join(format!("{}.pvd", self.stem));
        write_file(&path, &s)?;
        Ok(path)
    }
}
