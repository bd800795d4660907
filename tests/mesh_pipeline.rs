//! The whole preparation pipeline: smoothing, repair, overlap; idempotent on clean input.

mod mesh_support;

use breathing_torso::mesh::pipeline::{is_inside, read_prepared, write_prepared};
use breathing_torso::mesh::{PrepareOptions, TriMesh, hausdorff, prepare};
use mesh_support::{folded_sphere, noisy_ellipsoid, rms_distance};
use nalgebra::{Point3, Vector3};

fn abdomen() -> TriMesh {
    // pokes 5 mm through the skin in z
    let (_, mut a) = noisy_ellipsoid(Vector3::new(0.10, 0.14, 0.125), 4, 0.01, 5);
    a.translate(&Vector3::new(0.0, -0.1, 0.0));
    a
}

#[test]
fn noisy_skin_and_overlapping_abdomen_are_prepared() {
    let (clean, skin) = noisy_ellipsoid(Vector3::new(0.15, 0.30, 0.12), 4, 0.03, 1);
    let (out, rep) = prepare(skin.clone(), Some(abdomen()), &PrepareOptions::default()).unwrap();
    let a = out.abdomen.as_ref().unwrap();
    for m in [&out.skin, a] {
        let t = m.topology();
        assert!(t.is_closed() && t.is_consistently_oriented());
        assert!(breathing_torso::mesh::repair::self_intersections(m).is_empty());
    }
    assert!(is_inside(a, &out.skin));
    // noise reduced, shape kept: RMS distance to the clean skin falls, volume within 1 %
    let (e0, e1) = (rms_distance(&skin, &clean), rms_distance(&out.skin, &clean));
    assert!(e1 < 0.5 * e0, "{e0} -> {e1}");
    assert!((out.skin.volume() / clean.volume() - 1.0).abs() < 0.01);
    assert!(hausdorff(&out.skin, &clean) < 0.03 * 0.12);
    let ov = &rep.surfaces[1].overlaps[0].report;
    assert!(ov.penetrating_at_start > 0 && ov.vertices_moved > 0);
    let md = rep.to_markdown();
    assert!(md.contains("## skin") && md.contains("## abdomen"));
}

#[test]
fn pipeline_is_idempotent_on_clean_input() {
    let (_, skin) = noisy_ellipsoid(Vector3::new(0.15, 0.30, 0.12), 4, 0.03, 2);
    let (once, _) = prepare(skin, Some(abdomen()), &PrepareOptions::default()).unwrap();
    let (twice, rep) = prepare(
        once.skin.clone(),
        once.abdomen.clone(),
        &PrepareOptions::default(),
    )
    .unwrap();
    // the second pass finds the surfaces smooth, sound and apart: nothing changes
    assert!(twice == once, "second pass changed the surfaces");
    for s in &rep.surfaces {
        assert!(s.smoothing.as_ref().unwrap().skipped, "{:?}", s.smoothing);
        assert_eq!(
            s.repair.collapsed_edges + s.repair.triangles_removed + s.repair.opposite_faces_removed,
            0
        );
    }
    assert!(
        rep.surfaces[1]
            .overlaps
            .iter()
            .all(|o| o.report.vertices_moved == 0)
    );
    // a clean generated surface is left exactly as it is, too
    let clean = TriMesh::ellipsoid(&Point3::origin(), &Vector3::new(0.15, 0.30, 0.12), 4).unwrap();
    let (out, rep2) = prepare(clean.clone(), None, &PrepareOptions::default()).unwrap();
    assert!(out.skin == clean, "{:?}", rep2.surfaces[0]);
}

#[test]
fn folded_skin_is_repaired_and_written() {
    let mut skin = folded_sphere(4);
    skin.scale(&Point3::origin(), &Vector3::new(0.15, 0.3, 0.15));
    let (out, rep) = prepare(skin, None, &PrepareOptions::default()).unwrap();
    assert!(rep.surfaces[0].repair.intersecting_pairs > 0);
    assert_eq!(rep.surfaces[0].output.self_intersections, 0);
    assert!(rep.surfaces[0].output.topology.is_closed());
    let dir = std::env::temp_dir().join(format!("torso_prepared_{}", std::process::id()));
    write_prepared(&dir, &out, &rep).unwrap();
    let back = read_prepared(&dir).unwrap();
    assert_eq!(back.skin.num_triangles(), out.skin.num_triangles());
    assert!(back.abdomen.is_none());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    assert!(json["times"]["repair_ms"].as_f64().unwrap() >= 0.0);
    assert!(prepare(TriMesh::default(), None, &PrepareOptions::default()).is_err());
}

#[test]
fn ribs_go_inside_the_skin_and_the_abdomen_out_of_the_ribs() {
    use breathing_torso::mesh::overlap::penetrating_vertices;
    use breathing_torso::mesh::pipeline::prepare_all;
    use breathing_torso::mesh::{Bvh, Relation};
    let skin = TriMesh::ellipsoid(&Point3::origin(), &Vector3::new(0.15, 0.30, 0.12), 4).unwrap();
    let abd = TriMesh::ellipsoid(
        &Point3::new(0.0, -0.1, 0.0),
        &Vector3::new(0.10, 0.14, 0.10),
        4,
    )
    .unwrap();
    // a rib-like rod that pokes out of the skin at both ends and cuts 10 mm into the abdomen
    let rib = TriMesh::ellipsoid(
        &Point3::new(0.0, -0.05, 0.095),
        &Vector3::new(0.2, 0.012, 0.012),
        3,
    )
    .unwrap();
    let (out, rep) = prepare_all(
        skin,
        Some(abd),
        vec![("rib7_left".into(), rib)],
        &PrepareOptions::default(),
    )
    .unwrap();
    let (skin, abd, rib) = (&out.skin, out.abdomen.as_ref().unwrap(), &out.ribs[0].1);
    assert!(is_inside(rib, skin));
    assert!(is_inside(abd, skin));
    let rb = Bvh::new(rib);
    assert!(penetrating_vertices(abd, &rb, Relation::Outside, 0.0).is_empty());
    assert!(rb.intersections_with(&Bvh::new(abd)).is_empty());
    assert!(
        rep.surfaces[2]
            .overlaps
            .iter()
            .any(|o| o.report.vertices_moved > 0)
    );
    // the rib is shortened to the skin's chord along its axis (0.176 at its height), not
    // squashed: it still spans most of that chord and keeps its thickness
    let chord = 2.0 * 0.15 * (1.0f64 - (0.095f64 / 0.12).powi(2) - (0.05f64 / 0.3).powi(2)).sqrt();
    let ext = rib.bounding_box().extent();
    assert!(
        ext.x > 0.8 * chord && ext.x < 1.1 * chord,
        "{ext:?} vs chord {chord}"
    );
    assert!(ext.y > 0.02 && ext.z > 0.02, "{ext:?}");
    assert!(
        rep.surfaces[1]
            .overlaps
            .iter()
            .any(|o| o.against == "rib7_left" && o.report.vertices_moved > 0)
    );
    for (name, m) in [("skin", skin), ("abdomen", abd), ("rib", rib)] {
        let si = breathing_torso::mesh::repair::self_intersections(m).len();
        assert!(
            m.is_closed() && si == 0,
            "{name}: {si} self-intersecting pairs"
        );
    }
}

#[test]
fn an_open_scan_is_closed_by_the_pipeline() {
    let (clean, mut skin) = noisy_ellipsoid(Vector3::new(0.15, 0.30, 0.12), 4, 0.03, 4);
    // cut neck and waist openings, as a trunk scan has
    let keep: Vec<bool> = (0..skin.num_triangles())
        .map(|t| skin.face_centroid(t).y.abs() < 0.27)
        .collect();
    let mut k = 0;
    skin.triangles.retain(|_| {
        k += 1;
        keep[k - 1]
    });
    skin.remove_unreferenced_vertices();
    assert!(skin.topology().boundary_edges > 0);
    let (out, rep) = prepare(skin, None, &PrepareOptions::default()).unwrap();
    assert!(rep.surfaces[0].holes_closed > 0);
    let t = out.skin.topology();
    assert!(t.is_closed() && t.is_consistently_oriented(), "{t:?}");
    assert!(breathing_torso::mesh::repair::self_intersections(&out.skin).is_empty());
    // the capped openings stay near the ellipsoid's ends (the caps are faired, not flat)
    assert!(
        hausdorff(&out.skin, &clean) < 0.03,
        "{}",
        hausdorff(&out.skin, &clean)
    );
    assert!((out.skin.volume() / clean.volume() - 1.0).abs() < 0.02);
}
