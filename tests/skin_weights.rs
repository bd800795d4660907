//! Bone-heat weights and linear blend skinning on the generated skin with the anatomy's
//! handles (ribs, sternum, spine, free abdominal wall).

use breathing_torso::anatomy::skin::{MarkerGrid, Skin, SkinOptions, vertex_neighbours};
use breathing_torso::anatomy::{Anatomy, Subject};
use breathing_torso::observe::markers::anatomy_handles;
use breathing_torso::observe::skinning::{
    BoneHeat, Handle, HandleKind, HandlePose, InfluenceSource, PATCH_RADIUS, Skinning,
    SkinningOptions,
};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use std::sync::OnceLock;

struct Setup {
    skin: Skin,
    handles: Vec<Handle>,
    skinning: Skinning,
}

fn setup() -> &'static Setup {
    static S: OnceLock<Setup> = OnceLock::new();
    S.get_or_init(|| {
        let subject = Subject::default();
        let anatomy = Anatomy::build(&subject, 1).unwrap();
        let skin = Skin::for_anatomy(&anatomy, &SkinOptions::default()).unwrap();
        let (handles, _) = anatomy_handles(&anatomy);
        let skinning = Skinning::new(
            &skin.vertices,
            &skin.triangles,
            &handles,
            &SkinningOptions::default(),
        )
        .unwrap();
        Setup {
            skin,
            handles,
            skinning,
        }
    })
}

fn rest_poses(handles: &[Handle]) -> Vec<HandlePose> {
    handles.iter().map(|h| HandlePose::rest(h.kind)).collect()
}

#[test]
fn weights_are_in_unit_interval_and_sum_to_one() {
    let s = setup();
    let w = s.skinning.weights();
    for i in 0..s.skin.vertices.len() {
        let mut sum = 0.0;
        for (j, x) in w.of_vertex(i) {
            assert!(
                (0.0..=1.0).contains(&x),
                "vertex {i} influence {j} weight {x}"
            );
            sum += x;
        }
        assert!((sum - 1.0).abs() < 1e-12, "vertex {i} weights sum to {sum}");
    }
    // Translation handles were grouped into patches of pi PATCH_RADIUS^2 of wall each.
    let patches = s
        .skinning
        .influences()
        .iter()
        .filter(|f| matches!(f.source, InfluenceSource::TranslationGroup(_)))
        .count();
    let wall: Vec<&Handle> = s
        .handles
        .iter()
        .filter(|h| h.kind == HandleKind::Translation)
        .collect();
    let translations = wall.len();
    assert!(translations > 100, "{translations} wall handles");
    let area: f64 = wall.iter().map(|h| h.area).sum();
    let patch = std::f64::consts::PI * PATCH_RADIUS * PATCH_RADIUS;
    assert_eq!(patches, (area / patch).ceil() as usize, "wall {area} m^2");
}

#[test]
fn raw_heat_fields_satisfy_the_equilibrium_bound() {
    // (K + A H) w = A H p  =>  w_i - (sum_k K_ik w_k)/K_ii ... at each vertex
    // |w_i - cotangent mean of neighbours| = A_i H_i |p_i - w_i| / K_ii.
    let s = setup();
    let heat = BoneHeat::new(
        &s.skin.vertices,
        &s.skin.triangles,
        s.skinning.influences(),
        &SkinningOptions::default(),
    )
    .unwrap();
    let lap = &heat.laplacian;
    for j in [0usize, 5, 12, 24, 25, 30] {
        let w = heat.solve(j);
        for i in 0..w.len() {
            let mean: f64 = lap.neighbours[i]
                .iter()
                .map(|&(k, c)| c * w[k as usize])
                .sum::<f64>()
                / lap.diagonal[i];
            let p = if heat.nearest[i] == Some(j as u32) {
                1.0
            } else {
                0.0
            };
            let expected = lap.areas[i] * heat.heat[i] * (p - w[i]) / lap.diagonal[i];
            assert!(
                ((w[i] - mean) - expected).abs() < 1e-9,
                "influence {j} vertex {i}"
            );
        }
    }
}

#[test]
fn weights_vary_smoothly_over_the_skin() {
    // Bound: a weight moves from 1 to 0 across the gap between two neighbouring handles. The
    // closest handles (adjacent ribs) are >= 25 mm apart and the skin edges are <= 15 mm
    // long, so a smooth transition spans at least two edges and one vertex can depart from
    // the mean of its one-ring by at most about half the full swing: 0.5. A field jumping
    // from 0 to 1 between neighbours (nearest-bone assignment) would reach 1 - 1/6.
    let s = setup();
    let nb = vertex_neighbours(s.skin.vertices.len(), &s.skin.triangles);
    let w = s.skinning.weights();
    let mut worst: f64 = 0.0;
    let mut sum = 0.0;
    let mut count = 0usize;
    for (i, ring) in nb.iter().enumerate() {
        for (j, wi) in w.of_vertex(i) {
            let mean: f64 =
                ring.iter().map(|&k| w.get(k as usize, j)).sum::<f64>() / ring.len() as f64;
            worst = worst.max((wi - mean).abs());
            sum += (wi - mean).abs();
            count += 1;
        }
    }
    println!(
        "largest departure from the one-ring mean {worst:.4}, mean {:.5}",
        sum / count as f64
    );
    assert!(worst < 0.5, "{worst}");
    assert!(sum / (count as f64) < 0.05);
}

#[test]
fn rest_pose_reproduces_the_skin_exactly() {
    let s = setup();
    let frame = s.skinning.frame(&rest_poses(&s.handles)).unwrap();
    let mut out = Vec::new();
    s.skinning.deform_all(&frame, &mut out);
    assert_eq!(out, s.skin.vertices);
    let grid = MarkerGrid::place(&s.skin, 10, 6).unwrap();
    let bound = s
        .skinning
        .bind(&s.skin.triangles, &grid.bindings())
        .unwrap();
    let mut m = vec![Point3::origin(); bound.len()];
    bound.evaluate(&frame, &mut m);
    assert_eq!(m, grid.positions(&s.skin.vertices, &s.skin.triangles));
}

#[test]
fn common_rigid_motion_moves_the_skin_rigidly_and_markers_match_the_skin() {
    let s = setup();
    let iso = Isometry3::from_parts(
        Translation3::new(0.01, -0.02, 0.005),
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.1),
    );
    let poses: Vec<HandlePose> = s
        .handles
        .iter()
        .map(|h| match h.kind {
            HandleKind::Rigid => HandlePose::Rigid(iso),
            HandleKind::Translation => HandlePose::Translation(Vector3::zeros()),
        })
        .collect();
    // Translation handles stay, so only vertices fully owned by bones follow the isometry.
    let frame = s.skinning.frame(&poses).unwrap();
    let grid = MarkerGrid::place(&s.skin, 10, 6).unwrap();
    let bound = s
        .skinning
        .bind(&s.skin.triangles, &grid.bindings())
        .unwrap();
    let mut m = vec![Point3::origin(); bound.len()];
    bound.evaluate(&frame, &mut m);
    let mut all = Vec::new();
    s.skinning.deform_all(&frame, &mut all);
    let direct = grid.positions(&all, &s.skin.triangles);
    for (a, b) in m.iter().zip(&direct) {
        assert!(
            (a - b).norm() < 1e-12,
            "bound point {a} vs deformed skin {b}"
        );
    }
    // Top of the neck is owned by the spine: moves with the isometry.
    let top = s.skin.vertices.len() - 1;
    assert!((all[top] - iso.transform_point(&s.skin.vertices[top])).norm() < 1e-9);
}

#[test]
fn abdominal_displacement_moves_lower_markers_not_upper_ones() {
    let s = setup();
    let poses: Vec<HandlePose> = s
        .handles
        .iter()
        .map(|h| match h.kind {
            HandleKind::Rigid => HandlePose::rest(HandleKind::Rigid),
            HandleKind::Translation => HandlePose::Translation(Vector3::new(0.005, 0.0, 0.0)),
        })
        .collect();
    let frame = s.skinning.frame(&poses).unwrap();
    let grid = MarkerGrid::place(&s.skin, 10, 6).unwrap();
    let bound = s
        .skinning
        .bind(&s.skin.triangles, &grid.bindings())
        .unwrap();
    let mut m = vec![Point3::origin(); bound.len()];
    bound.evaluate(&frame, &mut m);
    let rest = bound.rest();
    let dx = |r: usize| {
        (0..6)
            .map(|c| m[r * 6 + c].x - rest[r * 6 + c].x)
            .sum::<f64>()
            / 6.0
    };
    println!(
        "row ventral motion (mm): {:?}",
        (0..10)
            .map(|r| (dx(r) * 1e3 * 100.0).round() / 100.0)
            .collect::<Vec<_>>()
    );
    assert!(dx(9) > 0.003, "umbilical row {}", dx(9));
    assert!(dx(0).abs() < 0.0005, "clavicle row {}", dx(0));
}

#[test]
fn bad_poses_are_rejected() {
    let s = setup();
    assert!(s.skinning.frame(&[]).is_err());
    let mut poses = rest_poses(&s.handles);
    poses[0] = HandlePose::Translation(Vector3::zeros());
    assert!(s.skinning.frame(&poses).is_err());
}
