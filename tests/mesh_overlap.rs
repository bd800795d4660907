//! Overlap resolution between two ellipsoids (inner must stay inside outer, or outside).

mod mesh_support;

use breathing_torso::mesh::overlap::penetrating_vertices;
use breathing_torso::mesh::{Bvh, OverlapOptions, Relation, TriMesh, hausdorff, resolve_overlap};
use nalgebra::{Point3, Vector3};

#[test]
fn inner_ellipsoid_is_pushed_inside_the_outer() {
    let outer = TriMesh::ellipsoid(&Point3::origin(), &Vector3::new(0.30, 0.20, 0.15), 4).unwrap();
    let inner0 = TriMesh::ellipsoid(
        &Point3::new(0.04, 0.0, 0.0),
        &Vector3::new(0.22, 0.15, 0.17),
        4,
    )
    .unwrap();
    let fixed = Bvh::new(&outer);
    let opts = OverlapOptions::for_mesh(&inner0, Relation::Inside);
    let pen0 = penetrating_vertices(&inner0, &fixed, Relation::Inside, opts.margin);
    assert!(
        pen0.len() > 100,
        "the test needs a real overlap: {}",
        pen0.len()
    );
    let mut inner = inner0.clone();
    let rep = resolve_overlap(&mut inner, &outer, &opts).unwrap();
    assert!(penetrating_vertices(&inner, &fixed, Relation::Inside, opts.margin).is_empty());
    assert!(fixed.intersections_with(&Bvh::new(&inner)).is_empty());
    assert!(inner.is_closed() && inner.is_consistently_oriented());
    assert!(Bvh::new(&inner).self_intersections().is_empty());
    // vertices well inside and away from the pushed region did not move
    let deep: Vec<usize> = (0..inner0.num_vertices())
        .filter(|&i| fixed.signed_distance(&inner0.vertices[i]) < -0.04)
        .collect();
    assert!(!deep.is_empty());
    for i in deep {
        assert_eq!(inner.vertices[i], inner0.vertices[i]);
    }
    // the change is bounded by the deepest penetration (0.17 - 0.15 in z) plus the margin
    // and a smoothing allowance of one mean edge length
    let h = hausdorff(&inner, &inner0);
    let bound = 0.02 + opts.margin + inner0.mean_edge_length();
    assert!(h < bound, "Hausdorff {h} >= {bound}; {rep:?}");
    assert!(rep.vertices_moved >= pen0.len());
    // idempotent once resolved
    let again = inner.clone();
    let rep2 = resolve_overlap(&mut inner, &outer, &opts).unwrap();
    assert_eq!(rep2.vertices_moved, 0);
    assert_eq!(inner, again);
}

#[test]
fn a_surface_is_pushed_out_of_another() {
    let bone = TriMesh::ellipsoid(
        &Point3::new(0.25, 0.0, 0.0),
        &Vector3::new(0.08, 0.08, 0.08),
        3,
    )
    .unwrap();
    let organ0 = TriMesh::ellipsoid(&Point3::origin(), &Vector3::new(0.22, 0.15, 0.15), 4).unwrap();
    let opts = OverlapOptions::for_mesh(&organ0, Relation::Outside);
    let fixed = Bvh::new(&bone);
    assert!(!penetrating_vertices(&organ0, &fixed, Relation::Outside, opts.margin).is_empty());
    let mut organ = organ0.clone();
    resolve_overlap(&mut organ, &bone, &opts).unwrap();
    assert!(penetrating_vertices(&organ, &fixed, Relation::Outside, opts.margin).is_empty());
    assert!(fixed.intersections_with(&Bvh::new(&organ)).is_empty());
    assert!(organ.volume() < organ0.volume());
    // the far side (x < 0) is untouched
    for (a, b) in organ0.vertices.iter().zip(&organ.vertices) {
        if a.x < 0.0 {
            assert_eq!(a, b);
        }
    }
}

#[test]
fn an_enclosed_surface_cannot_be_pushed_out() {
    let small = TriMesh::ellipsoid(&Point3::origin(), &Vector3::new(0.05, 0.05, 0.05), 3).unwrap();
    let mut big = TriMesh::ellipsoid(&Point3::origin(), &Vector3::new(0.2, 0.2, 0.2), 3).unwrap();
    let opts = OverlapOptions::for_mesh(&big, Relation::Outside);
    assert!(matches!(
        resolve_overlap(&mut big, &small, &opts),
        Err(breathing_torso::Error::State(_))
    ));
    let bad = OverlapOptions {
        margin: f64::NAN,
        ..opts
    };
    assert!(resolve_overlap(&mut big, &small, &bad).is_err());
}
