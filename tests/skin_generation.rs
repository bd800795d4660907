//! Skin generation: size, closedness, no self-intersection, determinism, enclosure of the
//! anatomy's rib cage and abdominal wall, agreement with the ANSUR II dimensions.

use breathing_torso::anatomy::skin::{Skin, dense_bone_points, geometry, wall_points};
use breathing_torso::anatomy::{Anatomy, Sex, Subject};

fn female() -> Subject {
    Subject {
        sex: Sex::Female,
        age: 30.0,
        stature: 1.65,
        mass: 55.0,
        breast_size: 0.8,
        ..Subject::default()
    }
}

#[test]
fn default_skin_is_closed_manifold_without_self_intersections() {
    let skin = Skin::generate(&Subject::default()).unwrap();
    let n = skin.vertices.len();
    println!("vertices {n}, triangles {}", skin.triangles.len());
    assert!((6000..=7000).contains(&n), "vertex count {n}");
    // Euler characteristic of a sphere: V - E + F = 2 with E = 3F/2.
    assert_eq!(n as i64 - skin.triangles.len() as i64 / 2, 2);
    geometry::check_closed_manifold(n, &skin.triangles).unwrap();
    assert!(geometry::self_intersections(&skin.vertices, &skin.triangles).is_empty());
    assert!(
        skin.volume() > 0.0,
        "outward orientation gives a positive volume"
    );
}

#[test]
fn female_and_extreme_subjects_are_valid_surfaces() {
    for s in [
        female(),
        Subject {
            stature: 1.45,
            mass: 42.0,
            age: 80.0,
            ..female()
        },
        Subject {
            stature: 2.05,
            mass: 150.0,
            age: 20.0,
            ..Subject::default()
        },
    ] {
        let skin = Skin::generate(&s).unwrap();
        skin.check().unwrap_or_else(|e| panic!("{s:?}: {e}"));
    }
}

#[test]
fn generation_is_deterministic() {
    let a = Skin::generate(&female()).unwrap();
    let b = Skin::generate(&female()).unwrap();
    assert_eq!(a, b);
}

#[test]
fn skin_encloses_the_anatomy_with_soft_tissue_gap() {
    let subject = Subject::default();
    let skin = Skin::generate(&subject).unwrap();
    let anatomy = Anatomy::build(&subject, 0).unwrap();
    // The skin is cut at the hips; the cavity's pelvic part below the cut is not enclosed.
    let (lo, hi) = (skin.landmarks.bottom_height, skin.landmarks.top_height);
    let all = wall_points(&anatomy);
    let within: Vec<_> = all.into_iter().filter(|p| p.y > lo && p.y < hi).collect();
    assert!(
        within.len() > 30,
        "{} wall vertices within the skin",
        within.len()
    );
    let wall = skin.gap_report(&within);
    println!("gap to the free abdominal wall above the hip cut: {wall:?}");
    assert_eq!(wall.outside, 0);
    assert!(wall.min > 0.008, "min wall gap {}", wall.min);
    let gap = skin.gap_report(&dense_bone_points(&anatomy, 0.005));
    println!("gap to bone centrelines: {gap:?}");
    assert_eq!(gap.outside, 0);
    // Centreline to skin: at least the rib half-thickness (~6 mm) plus a few mm of tissue.
    assert!(gap.min > 0.010, "min gap {}", gap.min);
    assert!(gap.mean > 0.015 && gap.mean < 0.06, "mean gap {}", gap.mean);
}

#[test]
fn circumferences_match_ansur_where_bones_allow() {
    let skin = Skin::generate(&Subject::default()).unwrap();
    let d = &skin.dimensions;
    let waist = skin.circumference_at(d.omphalion_height);
    let chest = skin.circumference_at(d.chest_height);
    println!(
        "waist {waist:.4} (ANSUR {:.4}), chest {chest:.4} (ANSUR {:.4})",
        d.waist_circumference, d.chest_circumference
    );
    assert!((waist - d.waist_circumference).abs() < 0.03 * d.waist_circumference);
    // The chest may be widened to enclose the rib cage, never narrowed.
    assert!(chest > 0.98 * d.chest_circumference && chest < 1.12 * d.chest_circumference);
}
