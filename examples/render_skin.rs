//! Renders the default subject's skin with its 10 x 6 marker grid at rest to
//! `docs/skin.png` (or the path given as first argument), and writes the skin, marker grid and
//! stand-in ribs as OBJ next to it. Run: `cargo run --release --example render_skin`.

use breathing_torso::anatomy::Subject;
use breathing_torso::anatomy::skin::export::{MeshPart, PolylinePart, write_obj};
use breathing_torso::anatomy::skin::render::{RenderOptions, render_png};
use breathing_torso::anatomy::skin::{MarkerGrid, ReferenceSkeleton, Skin};
use std::path::PathBuf;

fn main() -> breathing_torso::Result<()> {
    let out = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("docs/skin.png"));
    let subject = Subject::default();
    let skin = Skin::generate(&subject)?;
    let grid = MarkerGrid::place(&skin, 10, 6)?;
    let markers = grid.positions(&skin.vertices, &skin.triangles);
    let mut links = Vec::new();
    for r in 0..grid.rows {
        for c in 0..grid.cols {
            let i = r * grid.cols + c;
            if c + 1 < grid.cols {
                links.push((i, i + 1));
            }
            if r + 1 < grid.rows {
                links.push((i, i + grid.cols));
            }
        }
    }
    render_png(
        &out,
        &skin.vertices,
        &skin.triangles,
        &markers,
        &links,
        &RenderOptions::default(),
    )?;
    let bones = ReferenceSkeleton::for_subject(&subject)?;
    let mut polylines: Vec<PolylinePart> = bones
        .ribs
        .iter()
        .map(|(n, p)| PolylinePart { name: n, points: p })
        .collect();
    polylines.push(PolylinePart {
        name: "sternum",
        points: &bones.sternum,
    });
    polylines.push(PolylinePart {
        name: "spine",
        points: &bones.spine,
    });
    let rows: Vec<Vec<nalgebra::Point3<f64>>> = (0..grid.rows)
        .map(|r| markers[r * grid.cols..(r + 1) * grid.cols].to_vec())
        .collect();
    let names: Vec<String> = (0..grid.rows).map(|r| format!("marker_row{r}")).collect();
    for (r, row) in rows.iter().enumerate() {
        polylines.push(PolylinePart {
            name: &names[r],
            points: row,
        });
    }
    let obj = out.with_extension("obj");
    write_obj(
        &obj,
        &[MeshPart {
            name: "skin",
            vertices: &skin.vertices,
            triangles: &skin.triangles,
        }],
        &polylines,
    )?;
    println!("wrote {} and {}", out.display(), obj.display());
    Ok(())
}
