//! Marker grid layout and export writers.

use breathing_torso::anatomy::Subject;
use breathing_torso::anatomy::skin::export::{MeshPart, PolylinePart, VtkSeries, write_obj};
use breathing_torso::anatomy::skin::{MarkerGrid, Skin};

#[test]
fn grid_is_row_major_from_the_top_with_column_zero_on_the_right() {
    let skin = Skin::generate(&Subject::default()).unwrap();
    for (rows, cols) in [(10, 6), (16, 16), (5, 5)] {
        let grid = MarkerGrid::place(&skin, rows, cols).unwrap();
        let p = grid.positions(&skin.vertices, &skin.triangles);
        assert_eq!(p.len(), rows * cols);
        for r in 0..rows {
            for c in 0..cols {
                let i = r * cols + c;
                assert_eq!((grid.markers[i].row, grid.markers[i].col), (r, c));
                if c + 1 < cols {
                    assert!(p[i].z > p[i + 1].z, "column 0 on the subject's right");
                }
                if r + 1 < rows {
                    assert!(p[i].y > p[i + cols].y, "row 0 at the top");
                }
                assert!(p[i].x > 0.05, "markers on the anterior surface");
            }
        }
        let lm = &skin.landmarks;
        assert!(p[0].y < lm.suprasternale_height && p[0].y > lm.suprasternale_height - 0.03);
        assert!(p[(rows - 1) * cols].y < lm.omphalion_height);
    }
}

#[test]
fn obj_and_vtk_series_are_written() {
    let skin = Skin::generate(&Subject::default()).unwrap();
    let dir = std::env::temp_dir().join(format!("skin_export_{}", std::process::id()));
    let obj = dir.join("skin.obj");
    let line = [skin.vertices[0], skin.vertices[100], skin.vertices[200]];
    write_obj(
        &obj,
        &[MeshPart {
            name: "skin",
            vertices: &skin.vertices,
            triangles: &skin.triangles,
        }],
        &[PolylinePart {
            name: "line",
            points: &line,
        }],
    )
    .unwrap();
    let text = std::fs::read_to_string(&obj).unwrap();
    assert_eq!(
        text.lines().filter(|l| l.starts_with("v ")).count(),
        skin.vertices.len() + 3
    );
    assert_eq!(
        text.lines().filter(|l| l.starts_with("f ")).count(),
        skin.triangles.len()
    );
    let n = skin.vertices.len();
    assert!(text.contains(&format!("l {} {} {}", n + 1, n + 2, n + 3)));

    let mut series = VtkSeries::new(&dir, "skin");
    let scalar: Vec<f64> = skin.vertices.iter().map(|v| v.y).collect();
    for t in [0.0, 0.5] {
        series
            .add_frame(
                t,
                &skin.vertices,
                &skin.triangles,
                &[vec![0, 1, 2]],
                &[("height", &scalar)],
            )
            .unwrap();
    }
    let pvd = series.finish().unwrap();
    let index = std::fs::read_to_string(&pvd).unwrap();
    assert!(index.contains("file=\"skin_00000.vtp\"") && index.contains("timestep=\"0.5\""));
    let vtp = std::fs::read_to_string(dir.join("skin_00001.vtp")).unwrap();
    assert!(
        vtp.contains(&format!("NumberOfPoints=\"{n}\""))
            && vtp.contains(&format!("NumberOfPolys=\"{}\"", skin.triangles.len()))
    );
    assert!(
        series
            .add_frame(f64::NAN, &skin.vertices, &skin.triangles, &[], &[])
            .is_err()
    );
    assert!(
        write_obj(
            &obj,
            &[MeshPart {
                name: "bad",
                vertices: &line,
                triangles: &[[0, 1, 7]]
            }],
            &[]
        )
        .is_err()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
