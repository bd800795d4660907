//! The displaced compartments of optoelectronic plethysmography: the rib-cage and abdominal
//! walls split the trunk surface between them, so their displaced volumes add up to the
//! trunk's volume change for any deformation; the splitting plane (the lowest point of the
//! costal margin) lies between the sternum's lower end and the bottom of the abdomen.

use breathing_torso::anatomy::{Anatomy, Side, rib_index};
use breathing_torso::dynamics::{Model, Params};
use breathing_torso::model::Config;
use breathing_torso::observe::{Compartments, costal_margin_height, observe};
use nalgebra::{Point3, Vector3};

fn compile(lod: u32) -> Model {
    let c = Config::default();
    let anatomy = Anatomy::build(&c.subject, lod).unwrap();
    Model::compile(&anatomy, Params::for_posture(c.subject.posture))
}

/// A smooth deformation of every vertex, a few millimetres, different in each direction.
fn deform(rest: &[Point3<f64>], scale: f64) -> Vec<Point3<f64>> {
    rest.iter()
        .map(|p| {
            let d = Vector3::new(
                (7.0 * p.y).sin() * (3.0 * p.z).cos(),
                (5.0 * p.x + 2.0 * p.z).cos(),
                (4.0 * p.y).sin() + p.x,
            );
            p + scale * d
        })
        .collect()
}

#[test]
fn compartments_add_up_to_the_trunk_volume_change() {
    for lod in [0, 1] {
        let model = compile(lod);
        let c = Compartments::new(&model);
        let still = vec![nalgebra::Vector3::zeros(); model.rest.len()];
        let rest = observe(&model, &c, &model.rest, &still, 0.0, None);
        assert!(rest.rib_cage_displaced.abs() < 1e-15 && rest.abdomen_displaced.abs() < 1e-15);
        for scale in [1e-3, 5e-3] {
            let pos = deform(&model.rest, scale);
            let o = observe(&model, &c, &pos, &still, 0.0, None);
            let trunk_change = o.trunk - rest.trunk;
            let sum = o.rib_cage_displaced + o.abdomen_displaced;
            println!(
                "lod {lod}, scale {scale}: rib cage {:.3e}, abdomen {:.3e}, trunk change {:.3e} m^3",
                o.rib_cage_displaced, o.abdomen_displaced, trunk_change
            );
            // Each compartment is measured; neither takes all of the change.
            assert!(o.rib_cage_displaced.abs() > 1e-3 * trunk_change.abs());
            assert!(o.abdomen_displaced.abs() > 1e-3 * trunk_change.abs());
            assert!(
                (sum - trunk_change).abs() <= 1e-9 * trunk_change.abs().max(1e-6),
                "compartments {sum:e} against trunk change {trunk_change:e}"
            );
        }
    }
}

#[test]
fn the_split_lies_at_the_lowest_point_of_the_costal_margin() {
    let model = compile(1);
    let margin = costal_margin_height(&model);
    let lowest_of = |anchors: &[u32]| {
        anchors
            .iter()
            .map(|&i| model.rest[i as usize].y)
            .fold(f64::INFINITY, f64::min)
    };
    // Lower than any anchor of the ninth ribs and than the sternum; no tenth-rib anchor lies
    // below it.
    for side in [Side::Right, Side::Left] {
        let ninth = lowest_of(&model.rib_anchors[rib_index(9, side)]);
        let tenth = lowest_of(&model.rib_anchors[rib_index(10, side)]);
        assert!(margin < ninth, "margin {margin} m, ninth rib {ninth} m");
        assert!(margin <= tenth);
    }
    let sternum = lowest_of(&model.sternum_anchors);
    assert!(margin < sternum, "margin {margin} m, sternum {sternum} m");
    let lowest_abdomen = lowest_of(&model.abdomen_triangles.concat());
    assert!(margin > lowest_abdomen + 0.05, "margin {margin} m");
    println!("costal margin {margin:.4} m, bottom of the abdomen {lowest_abdomen:.4} m");
}
