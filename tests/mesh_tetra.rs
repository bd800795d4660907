//! Isosurface stuffing: closed surfaces become tetrahedral meshes of bounded quality.

use breathing_torso::mesh::tetra::{dihedral_angles, radius_edge};
use breathing_torso::mesh::{StuffOptions, TriMesh, hausdorff, stuff};
use nalgebra::{Point3, Vector3};

fn check(surface: &TriMesh, cells: usize) -> breathing_torso::mesh::TetQuality {
    let opts = StuffOptions::with_cells(surface, cells);
    let tm = stuff(surface, &opts).unwrap();
    let q = tm.quality();
    assert!(q.tets > 100);
    // every tetrahedron positively oriented
    for t in &tm.tets {
        let p = t.map(|i| tm.vertices[i as usize]);
        assert!((p[1] - p[0]).cross(&(p[2] - p[0])).dot(&(p[3] - p[0])) > 0.0);
    }
    // the boundary is a closed, consistently oriented surface close to the input
    let b = tm.boundary();
    let top = b.topology();
    assert!(top.is_closed() && top.is_consistently_oriented(), "{top:?}");
    assert!((b.volume() - q.volume).abs() < 1e-9 * q.volume);
    let h = hausdorff(&b, surface);
    assert!(
        h < 0.5 * opts.spacing,
        "Hausdorff {h} vs spacing {}",
        opts.spacing
    );
    let dv = (q.volume - surface.volume()).abs() / surface.volume();
    assert!(dv < 0.03, "volume off by {dv}");
    q
}

#[test]
fn sphere_and_ellipsoid_are_stuffed() {
    let s = TriMesh::icosphere(4).unwrap();
    let q = check(&s, 12);
    println!("sphere: {q:?}");
    assert!(
        q.min_dihedral_deg > 10.7 && q.max_dihedral_deg < 164.8,
        "{q:?}"
    );
    let e = TriMesh::ellipsoid(
        &Point3::new(0.1, 0.2, 0.3),
        &Vector3::new(0.3, 0.2, 0.12),
        4,
    )
    .unwrap();
    let q = check(&e, 20);
    println!("ellipsoid: {q:?}");
    assert!(
        q.min_dihedral_deg > 10.7 && q.max_dihedral_deg < 164.8,
        "{q:?}"
    );
}

#[test]
fn quality_measures_of_a_regular_tetrahedron() {
    let p = [
        Point3::new(1.0, 1.0, 1.0),
        Point3::new(1.0, -1.0, -1.0),
        Point3::new(-1.0, 1.0, -1.0),
        Point3::new(-1.0, -1.0, 1.0),
    ];
    for a in dihedral_angles(&p) {
        assert!((a - (1.0f64 / 3.0).acos().to_degrees()).abs() < 1e-9);
    }
    assert!((radius_edge(&p) - (6.0f64).sqrt() / 4.0).abs() < 1e-12);
}

#[test]
fn writers_and_bad_input() {
    let s = TriMesh::icosphere(3).unwrap();
    let tm = stuff(&s, &StuffOptions::with_cells(&s, 8)).unwrap();
    let vtk = tm.to_vtk();
    assert!(vtk.contains(&format!("CELLS {} {}", tm.tets.len(), 5 * tm.tets.len())));
    assert_eq!(vtk.lines().filter(|l| *l == "10").count(), tm.tets.len());
    let msh = tm.to_msh();
    assert!(msh.starts_with("$MeshFormat\n2.2 0 8\n"));
    assert_eq!(
        msh.lines()
            .filter(|l| l.split(' ').nth(1) == Some("4"))
            .count(),
        tm.tets.len()
    );
    let mut open = s.clone();
    open.triangles.pop();
    assert!(stuff(&open, &StuffOptions::with_cells(&s, 8)).is_err());
    let bad = StuffOptions {
        spacing: -1.0,
        ..StuffOptions::with_cells(&s, 8)
    };
    assert!(stuff(&s, &bad).is_err());
    let huge = StuffOptions {
        spacing: 1e-5,
        ..StuffOptions::with_cells(&s, 8)
    };
    assert!(stuff(&s, &huge).is_err());
    let dir = std::env::temp_dir().join(format!("torso_tetra_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    tm.write(dir.join("a.msh")).unwrap();
    tm.write(dir.join("a.vtk")).unwrap();
    assert!(tm.write(dir.join("a.xyz")).is_err());
}
