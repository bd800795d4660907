//! Geometry of the default subject's anatomy: closed, consistently oriented cavities with
//! plausible volumes, and the thesis's muscle element counts at full detail.

use breathing_torso::anatomy::{Anatomy, MuscleGroup, Subject};
use breathing_torso::mesh::TriMesh;

fn mesh(anatomy: &Anatomy, triangles: Vec<[u32; 3]>) -> TriMesh {
    let vertices = anatomy.anchors.iter().map(|a| a.rest).collect();
    TriMesh {
        vertices,
        triangles,
    }
}

/// Elements of a group: each path segment is one spring element of the thesis.
fn elements(a: &Anatomy, g: MuscleGroup) -> usize {
    a.muscles
        .iter()
        .filter(|m| m.group == g)
        .map(|m| m.path.len() - 1)
        .sum()
}

#[test]
fn cavities_are_closed_and_oriented_at_every_level_of_detail() {
    for lod in 0..3 {
        let a = Anatomy::build(&Subject::default(), lod).unwrap();
        let abdomen = mesh(&a, a.abdomen.anchor_triangles().collect());
        let thorax = mesh(&a, a.thorax_triangles());
        for (name, m, lo, hi) in [
            ("abdomen", &abdomen, 6.0, 14.0),
            ("thorax", &thorax, 3.0, 7.0),
        ] {
            let litres = m.volume() * 1e3;
            println!(
                "lod {lod} {name}: {litres:.3} L, {} vertices",
                a.abdomen.len()
            );
            assert!(
                m.is_closed() && m.is_edge_manifold(),
                "{name} at lod {lod} not closed"
            );
            assert!(
                m.is_consistently_oriented(),
                "{name} at lod {lod} not oriented"
            );
            assert!(
                (lo..=hi).contains(&litres),
                "{name} at lod {lod}: {litres} L"
            );
        }
    }
}

#[test]
fn abdominal_surface_sizes_follow_the_level_of_detail() {
    let sizes: Vec<usize> = (0..3)
        .map(|lod| {
            Anatomy::build(&Subject::default(), lod)
                .unwrap()
                .abdomen
                .len()
        })
        .collect();
    assert_eq!(sizes, vec![162, 642, 2562]);
}

#[test]
fn full_detail_has_the_thesis_element_counts() {
    let a = Anatomy::build(&Subject::default(), 2).unwrap();
    for g in MuscleGroup::ALL {
        let n = elements(&a, g);
        let target = g.default_count();
        println!("{}: {n} elements (thesis {target})", g.name());
        assert!(
            n as f64 >= 0.5 * target as f64 && n as f64 <= 1.5 * target as f64,
            "{}: {n} vs {target}",
            g.name()
        );
    }
}

#[test]
fn left_and_right_mirror_each_other() {
    let a = Anatomy::build(&Subject::default(), 1).unwrap();
    for level in 1..=12 {
        let r = &a.ribs[level - 1];
        let l = &a.ribs[12 + level - 1];
        for (p, q) in r.bone.iter().zip(&l.bone) {
            assert!(
                (p.x - q.x).abs() < 1e-12 && (p.y - q.y).abs() < 1e-12 && (p.z + q.z).abs() < 1e-12
            );
        }
        assert!((r.inertia_about_axis() - l.inertia_about_axis()).abs() < 1e-12);
    }
}
