//! Geometric attachments survive re-meshing; a surface that stops short is extended to its
//! target (Peeters & Pronost 2013, sections 3.4 and 3.8).

mod mesh_support;

use breathing_torso::mesh::{Attachment, Bvh, Taubin, TriMesh, extrude_to_target, hausdorff};
use nalgebra::{Point3, Vector3};

#[test]
fn attachments_find_their_vertices_after_remeshing() {
    let coarse = TriMesh::icosphere(3).unwrap();
    let idx: Vec<u32> = (0..coarse.num_vertices() as u32)
        .filter(|&i| coarse.vertices[i as usize].x > 0.8)
        .collect();
    let edge = coarse.mean_edge_length();
    let balls = Attachment::from_vertices("diaphragm-rib7", &coarse, &idx).unwrap();
    let pts: Vec<Point3<f64>> = idx.iter().map(|&i| coarse.vertices[i as usize]).collect();
    let hull = Attachment::hull("diaphragm-rib7", &pts, 0.25 * edge).unwrap();
    assert_eq!(balls.find_vertices(&coarse), idx);
    assert_eq!(hull.find_vertices(&coarse), idx);
    // a finer, differently numbered surface: the same area is found, nothing far from it
    let mut fine = TriMesh::icosphere(5).unwrap();
    fine.vertices.reverse();
    let n = fine.num_vertices() as u32;
    for t in &mut fine.triangles {
        for v in t.iter_mut() {
            *v = n - 1 - *v;
        }
    }
    for att in [&balls, &hull] {
        let found = att.find_vertices(&fine);
        assert!(!found.is_empty());
        for &i in &found {
            assert!(
                fine.vertices[i as usize].x > 0.8 - 2.0 * edge,
                "{:?}",
                fine.vertices[i as usize]
            );
        }
        // every fine vertex over a coarse triangle of the area is found
        let cbvh = Bvh::new(&coarse);
        for i in 0..n {
            let p = fine.vertices[i as usize];
            let t = cbvh.closest(&p).unwrap().triangle as usize;
            if coarse.triangles[t]
                .iter()
                .all(|v| idx.binary_search(v).is_ok())
            {
                assert!(
                    found.binary_search(&i).is_ok(),
                    "{p:?} missed by {:?}",
                    att.region
                );
            }
        }
    }
    // Taubin smoothing moves vertices slightly: the attachment still covers them
    let mut smoothed = coarse.clone();
    Taubin::default().smooth(&mut smoothed).unwrap();
    assert_eq!(balls.find_vertices(&smoothed), idx);
    assert!(Attachment::from_points("x", vec![], 1.0).is_err());
    assert!(Attachment::from_vertices("x", &coarse, &[10_000]).is_err());
    let json = serde_json::to_string(&hull).unwrap();
    let back: Attachment = serde_json::from_str(&json).unwrap();
    assert_eq!(back.find_vertices(&fine), hull.find_vertices(&fine));
}

#[test]
fn a_short_surface_is_extended_to_its_target() {
    // a muscle-like ellipsoid whose lowest point (y = -0.2) stops 0.05 short of a bone top at y = -0.25
    let muscle0 = TriMesh::ellipsoid(&Point3::origin(), &Vector3::new(0.05, 0.2, 0.05), 4).unwrap();
    let bone: Vec<Point3<f64>> = (0..25)
        .map(|k| {
            Point3::new(
                0.02 * (k % 5) as f64 - 0.04,
                -0.25,
                0.02 * (k / 5) as f64 - 0.04,
            )
        })
        .collect();
    let down = Vector3::new(0.0, -1.0, 0.0);
    let mut m = muscle0.clone();
    let ext = extrude_to_target(&mut m, &down, &bone, 60.0).unwrap();
    assert!((ext.distance - 0.05).abs() < 1e-9);
    assert!(ext.bottom_faces > 0 && ext.rings >= 1, "{ext:?}");
    let top = m.topology();
    assert!(top.is_closed() && top.is_consistently_oriented(), "{top:?}");
    assert_eq!(top.euler_characteristic, 2);
    assert!(Bvh::new(&m).self_intersections().is_empty());
    // it now reaches the bone within half an edge (local smoothing rounds the tip)
    let lowest = m.vertices.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    assert!(
        lowest < -0.25 + 0.5 * muscle0.mean_edge_length(),
        "lowest {lowest}"
    );
    assert!(m.volume() > muscle0.volume());
    // the upper part is untouched
    for (a, b) in muscle0.vertices.iter().zip(&m.vertices) {
        if a.y > -0.1 {
            assert_eq!(a, b);
        }
    }
    assert!(hausdorff(&m, &muscle0) < 0.06);
    // the generated part is stored as an attachment covering the new vertices
    let att = ext.attachment.unwrap();
    let found = att.find_vertices(&m);
    let missed: Vec<_> = ext
        .new_vertices
        .iter()
        .filter(|v| found.binary_search(v).is_err())
        .collect();
    assert!(
        missed.is_empty(),
        "{} of {} missed, e.g. {:?}",
        missed.len(),
        ext.new_vertices.len(),
        m.vertices[*missed[0] as usize]
    );
    // a surface that already reaches its target is left alone
    let mut again = m.clone();
    let e2 = extrude_to_target(&mut again, &down, &[Point3::new(0.0, lowest, 0.0)], 60.0).unwrap();
    assert_eq!(e2.bottom_faces, 0);
    assert_eq!(again, m);
}

#[test]
fn attachments_are_saved_and_loaded() {
    use breathing_torso::mesh::attach::{load, save};
    let m = TriMesh::icosphere(3).unwrap();
    let a = Attachment::from_vertices("rectus-pelvis", &m, &[0, 1, 2]).unwrap();
    let dir = std::env::temp_dir().join(format!("torso_att_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("attachments.json");
    save(&p, std::slice::from_ref(&a)).unwrap();
    assert_eq!(load(&p).unwrap(), vec![a]);
    std::fs::write(&p, "[\n  {\"name\": \"x\",\n   \"region\": oops}\n]").unwrap();
    match load(&p) {
        Err(breathing_torso::Error::Parse { line, .. }) => assert_eq!(line, 3),
        other => panic!("{other:?}"),
    }
    std::fs::write(
        &p,
        r#"[{"name":"x","region":{"Balls":{"points":[[0,0,0]],"radius":-1}}}]"#,
    )
    .unwrap();
    assert!(load(&p).is_err());
}
