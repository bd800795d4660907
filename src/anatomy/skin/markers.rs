//! The SLP-like marker grid (thesis 3.1-3.2): R x C points over the anterior chest and
//! abdomen, the top row on the clavicle line just below the suprasternale, the bottom row
//! below the umbilicus; each marker bound to the skin by barycentric coordinates on the
//! triangle a ray from in front (along -x) hits first.

use super::Skin;
use super::geometry::ray_triangle;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};

/// Largest number of rows or columns of the grid.
pub const MAX_GRID_SIZE: usize = 16;

/// A point of a triangle surface: triangle index and barycentric coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceBinding {
    /// Triangle index into the surface's triangle list.
    pub triangle: u32,
    /// Barycentric coordinates on the triangle's three vertices (sum 1).
    pub barycentric: [f64; 3],
}

impl SurfaceBinding {
    /// The bound point on a surface with these vertices and triangles.
    pub fn point(&self, vertices: &[Point3<f64>], triangles: &[[u32; 3]]) -> Point3<f64> {
        let t = triangles[self.triangle as usize];
        let b = self.barycentric;
        Point3::from(
            vertices[t[0] as usize].coords * b[0]
                + vertices[t[1] as usize].coords * b[1]
                + vertices[t[2] as usize].coords * b[2],
        )
    }
}

/// One marker of the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Marker {
    /// Row, 0 at the top (clavicle line).
    pub row: usize,
    /// Column, 0 on the subject's right (z > 0).
    pub col: usize,
    /// Where the marker sits on the skin.
    pub binding: SurfaceBinding,
}

/// The marker grid: markers in row-major order from the top row, column 0 on the subject's
/// right.
#[derive(Clone, Debug, PartialEq)]
pub struct MarkerGrid {
    /// Number of rows.
    pub rows: usize,
    /// Number of columns.
    pub cols: usize,
    /// Markers, index `row * cols + col`.
    pub markers: Vec<Marker>,
    /// Vertical spacing of the rows [m].
    pub row_spacing: f64,
    /// Horizontal spacing of the columns [m].
    pub col_spacing: f64,
}

impl MarkerGrid {
    /// Places a `rows` x `cols` grid (each 1..=16) on the skin. Rows run from the clavicle
    /// line (15 mm below the suprasternale, scaled by stature) to 40 mm below the omphalion
    /// (a single row lies halfway); columns are centred on the midline with the row spacing,
    /// narrowed when needed so the grid stays within 62 % of the narrowest half-breadth over
    /// the rows (the anterior surface an SLP projector lights).
    pub fn place(skin: &Skin, rows: usize, cols: usize) -> Result<MarkerGrid> {
        for (name, v) in [("grid.rows", rows), ("grid.cols", cols)] {
            if !(1..=MAX_GRID_SIZE).contains(&v) {
                return Err(Error::invalid(name, v, format!("1..={MAX_GRID_SIZE}")));
            }
        }
        let lm = &skin.landmarks;
        let s = lm.stature / super::REFERENCE_STATURE;
        let top = lm.suprasternale_height - 0.015 * s;
        let bottom = lm.omphalion_height - 0.04 * s;
        let row_spacing = (top - bottom) / (rows.max(2) - 1) as f64;
        let heights: Vec<f64> = if rows == 1 {
            vec![0.5 * (top + bottom)]
        } else {
            (0..rows).map(|r| top - r as f64 * row_spacing).collect()
        };
        let half_breadth = heights
            .iter()
            .map(|&y| {
                skin.ring_near(y)
                    .iter()
                    .map(|p| p.z.abs())
                    .fold(0.0, f64::max)
            })
            .fold(f64::MAX, f64::min);
        let col_spacing = row_spacing.min(2.0 * 0.62 * half_breadth / (cols.max(2) - 1) as f64);
        let mut markers = Vec::with_capacity(rows * cols);
        for (row, &y) in heights.iter().enumerate() {
            for col in 0..cols {
                let z = (0.5 * (cols - 1) as f64 - col as f64) * col_spacing;
                let binding = cast_from_front(skin, y, z).ok_or_else(|| {
                    Error::State(format!(
                        "marker row {row} column {col} (y = {y:.3} m, z = {z:.3} m) misses the skin"
                    ))
                })?;
                markers.push(Marker { row, col, binding });
            }
        }
        Ok(MarkerGrid {
            rows,
            cols,
            markers,
            row_spacing,
            col_spacing,
        })
    }

    /// Marker positions on a surface with these vertices (the skin's triangles).
    pub fn positions(&self, vertices: &[Point3<f64>], triangles: &[[u32; 3]]) -> Vec<Point3<f64>> {
        self.markers
            .iter()
            .map(|m| m.binding.point(vertices, triangles))
            .collect()
    }

    /// The bindings of all markers, in index order.
    pub fn bindings(&self) -> Vec<SurfaceBinding> {
        self.markers.iter().map(|m| m.binding).collect()
    }
}

/// The front-most skin point on the horizontal line (y, z), found by a ray from x = +10 m
/// along -x.
fn cast_from_front(skin: &Skin, y: f64, z: f64) -> Option<SurfaceBinding> {
    let o = Point3::new(10.0, y, z);
    let d = Vector3::new(-1.0, 0.0, 0.0);
    let mut best: Option<(f64, SurfaceBinding)> = None;
    for (ti, t) in skin.triangles.iter().enumerate() {
        let (a, b, c) = (
            &skin.vertices[t[0] as usize],
            &skin.vertices[t[1] as usize],
            &skin.vertices[t[2] as usize],
        );
        if let Some((dist, u, v)) = ray_triangle(&o, &d, a, b, c)
            && dist > 0.0
            && best.as_ref().is_none_or(|(bd, _)| dist < *bd)
        {
            best = Some((
                dist,
                SurfaceBinding {
                    triangle: ti as u32,
                    barycentric: [1.0 - u - v, u, v],
                },
            ));
        }
    }
    best.map(|(_, b)| b)
}
