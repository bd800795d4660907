//! Abdominal-wall motion of the default upright subject over one breath (end-expiration to
//! end-inspiration of the second breath, level of detail 1): the free cavity vertices binned
//! by rest height (2 cm) and by azimuth about the cavity's axis (ventral within 20 deg of the
//! midline, ventrolateral to 50 deg, lateral to 90 deg, dorsolateral beyond; the dome
//! apart), with their mean displacement ventral / cranial / outward-lateral in mm, and the
//! abdominal pressure at both ends. It shows where the volume the diaphragm pushes down goes.
//!
//! `cargo run --release --example wall_motion [forced] [membrane=<stiffness factor>]`

mod common;

use breathing_torso::Quantity;
use breathing_torso::anatomy::VertexRole;
use breathing_torso::dynamics::Layout;
use std::collections::{BTreeMap, HashMap};

/// Azimuth sector of a wall vertex (0 ventral .. 3 dorsolateral), 9 for the dome.
fn sector(role: Option<VertexRole>, dx: f64, z: f64) -> u8 {
    if role == Some(VertexRole::Dome) {
        return 9;
    }
    match z.atan2(dx).to_degrees().abs() {
        a if a < 20.0 => 0,
        a if a < 50.0 => 1,
        a if a < 90.0 => 2,
        _ => 3,
    }
}

fn main() {
    let membrane = common::factor_from_args("membrane");
    let mut torso = common::torso_with(common::drive_from_args(), |p| {
        p.membrane_stiffness *= membrane
    });
    let params = torso.config().params.clone().unwrap();
    let compiled = torso.compiled().clone();
    let ab = &compiled.anatomy.abdomen;
    let role: HashMap<u32, VertexRole> = ab.anchor.iter().copied().zip(ab.roles.clone()).collect();
    let model = &compiled.model;
    let layout = Layout::new(model);
    let reads = [
        Quantity::AbdominalPressure,
        Quantity::AbdomenDisplaced,
        Quantity::RibCageDisplaced,
    ];
    let (lo, hi) = common::second_breath(&mut torso, &reads);
    let d = |k: usize| hi.reads[k] - lo.reads[k];
    let (dp, dab, drc) = (d(0), d(1), d(2));
    println!(
        "tidal volume {:.3} L; abdominal pressure {:.1} -> {:.1} Pa (above rest); displaced by \
         the rib cage {drc:.3} L, by the abdominal wall {dab:.3} L",
        hi.lung - lo.lung,
        lo.reads[0],
        hi.reads[0],
    );
    println!(
        "abdominal wall: displaced volume / pressure rise {:.2e} m^3/Pa against its \
         foundation's compliance {:.2e} m^3/Pa",
        dab * 1e-3 / dp,
        params.abdominal_wall_compliance
    );
    let mut bins: BTreeMap<(i64, u8), (usize, [f64; 3])> = BTreeMap::new();
    for (j, &a) in model.vertex_anchor.iter().enumerate() {
        let p = model.rest[a as usize];
        let at = |s: &[f64], k: usize| s[layout.vertex_x + 3 * j + k];
        let d = [0, 1, 2].map(|k| (at(&hi.state, k) - at(&lo.state, k)) * 1e3);
        // lateral motion counted outward on both sides
        let outward = if p.z < 0.0 { -d[2] } else { d[2] };
        let key = (
            (p.y * 50.0).floor() as i64,
            sector(role.get(&a).copied(), p.x - ab.axis_x, p.z),
        );
        let e = bins.entry(key).or_insert((0, [0.0; 3]));
        e.0 += 1;
        e.1[0] += d[0];
        e.1[1] += d[1];
        e.1[2] += outward;
    }
    println!("sectors: 0 ventral, 1 ventrolateral, 2 lateral, 3 dorsolateral, 9 dome");
    println!("height [mm] sector vertices   ventral cranial outward [mm]");
    for ((h, s), (n, d)) in &bins {
        let m = d.map(|x| x / *n as f64);
        println!(
            "{:6}      {s}     {n:4}      {:7.2} {:7.2} {:7.2}",
            h * 20,
            m[0],
            m[1],
            m[2]
        );
    }
}
