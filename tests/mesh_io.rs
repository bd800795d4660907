//! File-format round trips and malformed-file errors for `mesh::io`.

use breathing_torso::Error;
use breathing_torso::mesh::{TriMesh, io};
use nalgebra::{Point3, Vector3};

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("torso_mesh_io_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn sample() -> TriMesh {
    TriMesh::ellipsoid(
        &Point3::new(0.1, -0.2, 0.3),
        &Vector3::new(0.3, 0.2, 0.15),
        3,
    )
    .unwrap()
}

fn parse_err(e: Error) -> (usize, usize, String) {
    match e {
        Error::Parse {
            line,
            column,
            message,
            ..
        } => (line, column, message),
        other => panic!("expected a parse error, got {other:?}"),
    }
}

#[test]
fn round_trip_every_format() {
    let m = sample();
    for (name, tol) in [
        ("a.obj", 0.0),
        ("a.off", 0.0),
        ("a.vtk", 0.0),
        ("a.stl", 1e-6),
    ] {
        let p = tmp(name);
        io::write(&m, &p).unwrap();
        let r = io::read(&p).unwrap();
        assert_eq!(r.num_vertices(), m.num_vertices(), "{name}");
        assert_eq!(r.num_triangles(), m.num_triangles(), "{name}");
        // STL stores f32: positions agree to single precision.
        let err = if tol > 0.0 { 1e-6 } else { 0.0 };
        if name.ends_with("stl") {
            let mut worst: f64 = 0.0;
            for p in &m.vertices {
                let d = r
                    .vertices
                    .iter()
                    .map(|q| (q - p).norm())
                    .fold(f64::INFINITY, f64::min);
                worst = worst.max(d);
            }
            assert!(worst <= err, "{name}: {worst}");
            assert!(r.is_closed() && r.is_consistently_oriented());
        } else {
            assert_eq!(r, m, "{name}");
        }
        assert!((r.volume() - m.volume()).abs() < 1e-5 * m.volume());
    }
    let p = tmp("ascii.stl");
    io::write_as(&m, &p, io::Format::StlAscii).unwrap();
    let r = io::read(&p).unwrap();
    assert_eq!(r.num_vertices(), m.num_vertices());
    assert!(r.is_closed());
}

#[test]
fn obj_polygons_slashes_and_negative_indices() {
    let text = "# a unit square pyramid\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n\
                f 4/1/1 3/1/1 2/1/1 1/1/1\nv 0.5 0.5 1\nf 1//1 2//1 -1\nf 2/1 3/1 -1\nf -3 -2 -1\nf 4 1 5\n";
    let m = io::parse_obj(text, "pyr.obj").unwrap();
    assert_eq!(m.num_vertices(), 5);
    assert_eq!(m.num_triangles(), 6);
    assert!(m.is_closed() && m.is_consistently_oriented());
    assert!((m.volume() - 1.0 / 3.0).abs() < 1e-12, "{}", m.volume());
}

#[test]
fn stl_welds_with_tolerance() {
    let m = sample();
    let mut soup = TriMesh::default();
    for t in 0..m.num_triangles() {
        let b = soup.vertices.len() as u32;
        for (k, p) in m.corners(t).iter().enumerate() {
            // jitter each copy by well under the tolerance
            soup.vertices
                .push(p + Vector3::new(1e-7 * k as f64, -1e-7, 0.0));
        }
        soup.triangles.push([b, b + 1, b + 2]);
    }
    let bytes = io::to_stl_binary(&soup);
    let exact = io::parse_stl(&bytes, "soup.stl", 0.0).unwrap();
    assert!(exact.num_vertices() > m.num_vertices());
    let welded = io::parse_stl(&bytes, "soup.stl", 1e-5).unwrap();
    assert_eq!(welded.num_vertices(), m.num_vertices());
    assert!(welded.is_closed());
}

#[test]
fn malformed_files_name_line_and_column() {
    let (l, c, m) =
        parse_err(io::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", "x.obj").unwrap_err());
    assert_eq!((l, c), (4, 7), "{m}");
    let (l, c, _) = parse_err(io::parse_obj("v 0 0 0\nv 1 zero 0\n", "x.obj").unwrap_err());
    assert_eq!((l, c), (2, 5));
    let (l, _, _) = parse_err(io::parse_obj("v 0 0 0\nv 1 0 0\nf 1 2\n", "x.obj").unwrap_err());
    assert_eq!(l, 3);
    let (l, c, _) = parse_err(
        io::parse_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "x.off").unwrap_err(),
    );
    assert_eq!((l, c), (6, 7));
    let (l, c, _) = parse_err(io::parse_off("OFF\n3 1 0\n0 0 0\n1 0 nan\n", "x.off").unwrap_err());
    assert_eq!((l, c), (4, 5));
    let (l, _, _) = parse_err(io::parse_off("OFF\n3 1 0\n0 0 0\n1 0 0\n", "x.off").unwrap_err());
    assert_eq!(l, 4);
    let vtk = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0\n0 1 0\nPOLYGONS 1 4\n3 0 1 9\n";
    let (l, c, _) = parse_err(io::parse_vtk(vtk, "x.vtk").unwrap_err());
    assert_eq!((l, c), (9, 7));
    let vtk = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n";
    let (l, c, _) = parse_err(io::parse_vtk(vtk, "x.vtk").unwrap_err());
    assert_eq!((l, c), (4, 9));
    let stl = "solid s\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0\n  endloop\n endfacet\nendsolid\n";
    let (l, _, _) = parse_err(io::parse_stl(stl.as_bytes(), "x.stl", 0.0).unwrap_err());
    assert_eq!(l, 5);
    // binary STL whose header announces more records than the file holds
    let mut bin = io::to_stl_binary(&sample());
    bin.truncate(84 + 50 * 10 + 7);
    let (_, _, msg) = parse_err(io::parse_stl(&bin, "x.stl", 0.0).unwrap_err());
    assert!(msg.contains("record 11"), "{msg}");
    // binary STL with a NaN coordinate in record 3
    let mut bin = io::to_stl_binary(&sample());
    bin[84 + 50 * 2 + 12..84 + 50 * 2 + 16].copy_from_slice(&f32::NAN.to_le_bytes());
    let (_, _, msg) = parse_err(io::parse_stl(&bin, "x.stl", 0.0).unwrap_err());
    assert!(msg.starts_with("record 3"), "{msg}");
    assert!(matches!(
        io::read(tmp("missing.obj")),
        Err(Error::Io { .. })
    ));
    assert!(matches!(
        io::read(tmp("x.ply")),
        Err(Error::InvalidParameter { .. })
    ));
}

#[test]
fn vtk_51_offsets_layout() {
    let vtk = "# vtk DataFile Version 5.1\nt\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n0 0 0 1 0 0 1 1 0 0 1 0\n\
               POLYGONS 2 4\nOFFSETS vtktypeint64\n0 4\nCONNECTIVITY vtktypeint64\n0 1 2 3\n";
    let m = io::parse_vtk(vtk, "q.vtk").unwrap();
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
}

#[test]
fn truncated_and_corrupted_files_never_panic() {
    let m = TriMesh::ellipsoid(&Point3::origin(), &Vector3::new(1.0, 2.0, 3.0), 1).unwrap();
    let texts = [
        ("obj", io::to_obj(&m)),
        ("off", io::to_off(&m)),
        ("vtk", io::to_vtk(&m)),
        ("stl", io::to_stl_ascii(&m)),
    ];
    let mut state = 99u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for (kind, text) in &texts {
        let bytes = text.as_bytes();
        for cut in (0..bytes.len()).step_by(7) {
            let mut b = bytes[..cut].to_vec();
            if cut % 3 == 0 && !b.is_empty() {
                let i = (next() as usize) % b.len();
                b[i] = b"x9 -/\n#"[(next() % 7) as usize];
            }
            let t = String::from_utf8_lossy(&b);
            let r = match *kind {
                "obj" => io::parse_obj(&t, "f"),
                "off" => io::parse_off(&t, "f"),
                "vtk" => io::parse_vtk(&t, "f"),
                _ => io::parse_stl(&b, "f", 0.0),
            };
            if let Ok(mesh) = r {
                mesh.validate().unwrap();
            }
        }
    }
    let bin = io::to_stl_binary(&m);
    for cut in 0..bin.len().min(400) {
        let _ = io::parse_stl(&bin[..cut], "f", 1e-3);
    }
}
