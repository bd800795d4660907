//! Where the coarse diaphragm loses its breath: for the default upright subject at levels of
//! detail 0, 1 and 2, the diaphragm's geometry (insertion length, force-weighted fibre length
//! over the chords and over the smooth dome's arcs, the dome's projected and total areas, the
//! area its horizontal support acts on, the dome membrane's sum of squared edge lengths per
//! area) and the static equilibrium under a constant diaphragm activation alone (the quiet
//! drive's amplitude, or the first argument): the thoracic volume gained, split into the rib
//! cage's displaced volume and the rest (the dome's), the dome's piston descent, the fibres'
//! mean strain against the muscle law's target (beta a), the volume per unit of strain, the
//! abdominal pressure, and the fibres' pull on the ribs (outward from the cavity's axis and
//! cranial, along each insertion's first segment). Then the same equilibria with one thing
//! changed at a time: the fibres as long as their chords (the layout before the smooth arcs),
//! the insertions moved off the ribs onto fixed anchors (the ribs no longer feel the fibres),
//! each fibre leaving its insertion straight up to a rib-carried point below its first dome
//! vertex (the smooth dome's vertical tangent at the margin; its rigid horizontal leg counts
//! in the rest length, so level 0's fibres contract somewhat more than their tissue), and one
//! passive stiffness removed, halved or doubled at a time (dome membrane, central tendon, dome
//! support, abdominal wall, abdominal membrane, bulk modulus), and the tension-only law's toe
//! at a tenth. The second argument keeps only the variants whose name starts with it (`all`
//! keeps every one). For each, also the change of the vertical force on the dome's free
//! vertices from the fibres, from the dome membrane and from the rest (the pressures above
//! all), and the transdiaphragmatic pressure. The third argument, `hill`, takes the
//! passive-and-active law's constants instead of the thesis law's (without its standing tone,
//! which the facade applies, not these equilibria).
//!
//! `cargo run --release --example lod_diaphragm [ACTIVATION [VARIANT|all [hill]]]`

use breathing_torso::anatomy::{Anatomy, Anchor, Body, MuscleGroup, VertexRole};
use breathing_torso::dynamics::kinematics::positions_and_velocities;
use breathing_torso::dynamics::{
    Activations, Data, Layout, Model, Params, Structure, path_length, rest_state,
};
use breathing_torso::observe::{Compartments, observe};
use breathing_torso::solver::Options;
use breathing_torso::{Config, dynamics};

/// Static figures of one level under diaphragm activation `a`.
struct Figures {
    volume: f64,
    descent: f64,
    strain: f64,
    abdominal_pressure: f64,
    rib_cage: f64,
    dome: f64,
    insertion_pull: (f64, f64),
    /// Change from rest of the vertical force [N] on the dome's free vertices from the
    /// diaphragm's elements, from the dome membrane's, and from everything else (the
    /// pressures above all); the constant preloads balance none of the change.
    dome_load: [f64; 3],
    /// Change of the transdiaphragmatic pressure [Pa].
    transdiaphragmatic: f64,
}

/// The vertical force [N] on the dome's free vertices at positions `data.pos` under `act`:
/// in all, from the diaphragm's elements, and from the dome membrane's (passive elements
/// between dome and insertion vertices).
fn dome_forces(model: &Model, anatomy: &Anatomy, data: &mut Data, act: &Activations) -> [f64; 3] {
    let ab = &anatomy.abdomen;
    let role = |a: u32| {
        (0..ab.len())
            .find(|&v| ab.anchor[v] == a)
            .map(|v| ab.roles[v])
    };
    let dome: Vec<usize> = (0..ab.len())
        .filter(|&v| ab.roles[v] == VertexRole::Dome)
        .map(|v| ab.anchor[v] as usize)
        .collect();
    let sum = |s: &Structure, data: &mut Data| {
        dynamics::forces::accumulate(s, data, act);
        dome.iter().map(|&i| data.force[i].y).sum::<f64>()
    };
    let all = sum(model, data);
    let el = &model.elements;
    let diaphragm = |e: usize| el.group[e] == MuscleGroup::Diaphragm.index() as u8;
    let membrane = |e: usize| {
        el.group[e] == dynamics::PASSIVE
            && el.path[el.start[e] as usize..el.start[e + 1] as usize]
                .iter()
                .all(|&a| matches!(role(a), Some(VertexRole::Dome | VertexRole::Insertion)))
    };
    let without = |keep_out: &dyn Fn(usize) -> bool, data: &mut Data| {
        let mut s: Structure = (**model).clone();
        for e in 0..s.elements.len() {
            if keep_out(e) {
                // passive as well: a muscle's tension keeps the tension-only law's smooth
                // floor (toe ln 2 per element) even at zero stiffness and force
                s.elements.stiffness[e] = 0.0;
                s.elements.damping[e] = 0.0;
                s.elements.max_force[e] = 0.0;
                s.elements.slot[e] = dynamics::PASSIVE;
            }
        }
        sum(&s, data)
    };
    [
        all,
        all - without(&diaphragm, data),
        all - without(&membrane, data),
    ]
}

fn solve(anatomy: &Anatomy, params: Params, a: f64, chords: bool) -> Figures {
    let mut structure = Structure::compile(anatomy, params);
    let beta = structure.params.beta_max_diaphragm;
    if chords {
        // the fibres as long as their chords (the layout before the smooth dome's arcs)
        let el = &mut structure.elements;
        for e in 0..structure.muscle_count {
            if el.group[e] == MuscleGroup::Diaphragm.index() as u8 {
                let s = el.gain[e] / beta;
                el.stiffness[e] *= s;
                el.gain[e] = beta;
            }
        }
    }
    // the mass matrix and the preloads of the changed structure
    let model = Model::new(structure);
    let mut groups = [0.0; MuscleGroup::COUNT];
    groups[MuscleGroup::Diaphragm.index()] = a;
    let act = Activations::new(&groups, 1.0, 1.0);
    let start = rest_state(&model);
    let eq = dynamics::equilibrium::solve(&model, &act, &start, 1e-8, Options::default());
    assert!(eq.converged, "equilibrium not converged");
    let l = Layout::new(&model);
    let mut data = Data::new(&model);
    positions_and_velocities(&model, &mut data, &l, &start);
    let compartments = Compartments::new(&model);
    let rest = observe(&model, &compartments, &data.pos, &data.vel, 0.0, None);
    positions_and_velocities(&model, &mut data, &l, &eq.state);
    let o = observe(&model, &compartments, &data.pos, &data.vel, 0.0, None);
    let after = dome_forces(&model, anatomy, &mut data, &act);
    positions_and_velocities(&model, &mut data, &l, &start);
    let before = dome_forces(&model, anatomy, &mut data, &Activations::default());
    positions_and_velocities(&model, &mut data, &l, &eq.state);
    let dome_load = [
        after[1] - before[1],
        after[2] - before[2],
        (after[0] - before[0]) - (after[1] - before[1]) - (after[2] - before[2]),
    ];
    // force-weighted mean strain of the diaphragm's elements, and the pull of the fibres on
    // the insertions: outward (from the cavity's axis) and cranial components [N]
    let el = &model.elements;
    let (mut num, mut den) = (0.0, 0.0);
    let (mut outward, mut cranial) = (0.0, 0.0);
    let axis_x = anatomy.abdomen.axis_x;
    for e in 0..model.muscle_count {
        if el.group[e] != MuscleGroup::Diaphragm.index() as u8 {
            continue;
        }
        let path = &el.path[el.start[e] as usize..el.start[e + 1] as usize];
        let len = path_length(&data.pos, path);
        // the thesis law: the tissue's length l0 s and force F = k beta l0 s (s = gain /
        // beta); the passive-and-active law: the chord and F_max, its tension
        // `muscle::force` at the element's activation
        let hill = el.max_force[e] > 0.0;
        let (tissue, f) = if hill {
            (el.rest_length[e], el.max_force[e])
        } else {
            let tissue = el.rest_length[e] * el.gain[e] / beta;
            (tissue, el.stiffness[e] * beta * tissue)
        };
        num += f * (len - el.rest_length[e]);
        den += f * tissue;
        let tension = if hill {
            dynamics::muscle::force(
                len,
                el.optimal_length[e],
                el.slack_length[e],
                f,
                a * el.drive[e],
                dynamics::muscle::active_stiffness(),
            )
            .max(0.0)
        } else {
            el.stiffness[e] * (len - el.rest_length[e] * (1.0 - a * el.gain[e])).max(0.0)
        };
        for (end, next) in [
            (path[0], path[1]),
            (path[path.len() - 1], path[path.len() - 2]),
        ] {
            if !matches!(
                anatomy.anchors[end as usize].body,
                breathing_torso::anatomy::Body::Rib(_) | breathing_torso::anatomy::Body::Sternum
            ) {
                continue;
            }
            let p = data.pos[end as usize];
            let u = (data.pos[next as usize] - p).normalize();
            let radial = nalgebra::Vector3::new(p.x - axis_x, 0.0, p.z).normalize();
            outward += tension * u.dot(&radial);
            cranial += tension * u.y;
        }
    }
    Figures {
        volume: o.thorax - rest.thorax,
        descent: -(o.diaphragm_displacement - rest.diaphragm_displacement),
        strain: num / den,
        abdominal_pressure: o.abdominal_pressure - rest.abdominal_pressure,
        rib_cage: o.rib_cage_displaced - rest.rib_cage_displaced,
        dome: o.thorax - rest.thorax - (o.rib_cage_displaced - rest.rib_cage_displaced),
        insertion_pull: (outward, cranial),
        dome_load,
        transdiaphragmatic: (o.abdominal_pressure - o.pleural_pressure)
            - (rest.abdominal_pressure - rest.pleural_pressure),
    }
}

fn geometry(anatomy: &Anatomy, params: &Params) {
    let ab = &anatomy.abdomen;
    let rest = |v: u32| anatomy.rest(ab.anchor[v as usize]);
    let rim: f64 = (0..ab.rim.len())
        .map(|i| (rest(ab.rim[(i + 1) % ab.rim.len()]) - rest(ab.rim[i])).norm())
        .sum();
    let pos: Vec<_> = anatomy.anchors.iter().map(|a| a.rest).collect();
    let (mut fl, mut fs, mut ftot, mut n) = (0.0, 0.0, 0.0, 0);
    for m in anatomy
        .muscles
        .iter()
        .filter(|m| m.group == MuscleGroup::Diaphragm)
    {
        fl += m.max_force * path_length(&pos, &m.path);
        fs += m.max_force
            * m.tissue_length
                .unwrap_or_else(|| path_length(&pos, &m.path));
        ftot += m.max_force;
        n += 1;
    }
    // projected (horizontal) area and cap volume of the dome above the rim's mean height
    let rim_y = ab.rim.iter().map(|&v| rest(v).y).sum::<f64>() / ab.rim.len() as f64;
    let (mut area, mut cap) = (0.0, 0.0);
    let mut muscular = 0.0;
    for t in ab.dome_triangles() {
        let [p, q, r] = t.map(|a| anatomy.rest(a));
        let n = (q - p).cross(&(r - p)) * 0.5;
        area += n.y.abs();
        cap += n.y * ((p.y + q.y + r.y) / 3.0 - rim_y);
        muscular += n.norm();
    }
    // the dome support's area: each free dome vertex's third of its triangles' areas
    let mut vertex_area = vec![0.0; ab.len()];
    for t in &ab.triangles {
        let [p, q, r] = t.map(rest);
        let a = 0.5 * (q - p).cross(&(r - p)).norm();
        for v in t {
            vertex_area[*v as usize] += a / 3.0;
        }
    }
    // membrane edges of the dome (muscular) and of the tendon: sum of l^2 per area, the
    // energy of a uniform strain in units of k / 2 (an equilateral net has 2 sqrt 3 = 3.46)
    let mut edges = std::collections::BTreeSet::new();
    for t in &ab.triangles {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            edges.insert((u.min(v), u.max(v)));
        }
    }
    let tendon = |v: u32| ab.sphere[v as usize].y > breathing_torso::anatomy::CENTRAL_TENDON;
    let domish = |v: u32| {
        matches!(
            ab.roles[v as usize],
            VertexRole::Dome | VertexRole::Insertion
        )
    };
    let (mut l2_dome, mut l2_tendon, mut a_tendon) = (0.0, 0.0, 0.0);
    for &(u, v) in &edges {
        if ab.roles[u as usize] != VertexRole::Dome && ab.roles[v as usize] != VertexRole::Dome {
            continue;
        }
        let l2 = (rest(u) - rest(v)).norm_squared();
        if tendon(u) && tendon(v) {
            l2_tendon += l2;
        } else if domish(u) && domish(v) {
            l2_dome += l2;
        }
    }
    for t in &ab.triangles {
        if t.iter().all(|&v| tendon(v)) {
            let [p, q, r] = t.map(rest);
            a_tendon += 0.5 * (q - p).cross(&(r - p)).norm();
        }
    }
    println!(
        "  membrane sum l^2 per area: dome {:.2}, tendon {:.2} (tendon area {:.4} m^2)",
        l2_dome / (muscular - a_tendon),
        l2_tendon / a_tendon,
        a_tendon
    );
    let supported: f64 = ab
        .with_role(VertexRole::Dome)
        .map(|v| vertex_area[v as usize])
        .sum();
    let dome_vertices = ab.with_role(VertexRole::Dome).count();

    println!(
        "  rim {:.3} m ({} vertices), {} diaphragm elements, force-weighted fibre length: chords \
         {:.4} m, smooth dome {:.4} m (element forces sum {:.0} N), dome vertices {}, projected dome area {:.4} m^2, cap above rim mean {:.3} L, \
         faceting volume {:.3} L, beta {:.2}, dome area {:.4} m^2, supported {:.4} m^2",
        rim,
        ab.rim.len(),
        n,
        fl / breathing_torso::anatomy::DIAPHRAGM_FORCE,
        fs / breathing_torso::anatomy::DIAPHRAGM_FORCE,
        ftot,
        dome_vertices,
        area,
        1e3 * cap.abs(),
        1e3 * ab.dome_faceting_volume,
        params.beta_max_diaphragm,
        muscular,
        supported
    );
}

fn main() {
    let a: f64 = std::env::args()
        .nth(1)
        .map(|s| s.parse().expect("activation"))
        .unwrap_or(0.24);
    let config = Config::default();
    // the third argument `hill`: the passive-and-active law's constants (without its
    // standing tone, which these equilibria do not apply), otherwise the thesis law's
    let law = match std::env::args().nth(3).as_deref() {
        Some("hill") => dynamics::muscle::MuscleLaw::Hill,
        _ => dynamics::muscle::MuscleLaw::Thesis,
    };
    let base = Params::for_posture_and_law(config.subject.posture, law);
    type Variant = (&'static str, fn(&mut Params));
    let only = std::env::args().nth(2).filter(|v| v != "all");
    let variants: [Variant; 13] = [
        ("as is", |_| {}),
        ("fibre chords", |_| {}),
        ("insertions fixed", |_| {}),
        ("apposed insertions", |_| {}),
        ("dome membrane 0", |p| p.dome_membrane_stiffness = 0.0),
        ("tendon / 2", |p| p.tendon_stiffness *= 0.5),
        ("dome support 0", |p| p.dome_support = 0.0),
        ("dome support / 2", |p| p.dome_support *= 0.5),
        ("dome support x2", |p| p.dome_support *= 2.0),
        ("wall compliance x2", |p| p.abdominal_wall_compliance *= 2.0),
        ("abdominal membrane / 2", |p| p.membrane_stiffness *= 0.5),
        ("bulk modulus x10", |p| p.bulk_modulus *= 10.0),
        ("tension toe / 10", |p| p.tension_toe *= 0.1),
    ];
    let anatomies: Vec<Anatomy> = (0..3)
        .map(|lod| Anatomy::build(&config.subject, lod).unwrap())
        .collect();
    for (lod, an) in anatomies.iter().enumerate() {
        println!("level {lod}:");
        geometry(an, &base);
    }
    println!("diaphragm activation {a} alone, static equilibrium; level 0 / 1 / 2");
    // The fibres' insertions moved off the ribs onto fixed anchors at the same places: the
    // ribs no longer feel the fibres' pull (the abdominal pressure on the rim still acts).
    let grounded: Vec<Anatomy> = anatomies
        .iter()
        .map(|an| {
            let mut an = an.clone();
            for m in 0..an.muscles.len() {
                if an.muscles[m].group != MuscleGroup::Diaphragm {
                    continue;
                }
                for k in 0..an.muscles[m].path.len() {
                    let n = an.muscles[m].path[k] as usize;
                    if matches!(an.anchors[n].body, Body::Rib(_) | Body::Sternum) {
                        an.anchors.push(Anchor {
                            body: Body::Ground,
                            rest: an.anchors[n].rest,
                        });
                        an.muscles[m].path[k] = (an.anchors.len() - 1) as u32;
                    }
                }
            }
            an
        })
        .collect();
    // Each fibre leaves its insertion straight up, along the rib cage's wall (the smooth
    // dome's tangent at the margin), to a point carried by the rib at the insertion's height
    // below the first dome vertex, then to that vertex.
    let apposed: Vec<Anatomy> = anatomies
        .iter()
        .map(|an| {
            let mut an = an.clone();
            for m in 0..an.muscles.len() {
                if an.muscles[m].group != MuscleGroup::Diaphragm {
                    continue;
                }
                let path = an.muscles[m].path.clone();
                let r = path[0] as usize;
                let body = an.anchors[r].body;
                if !matches!(body, Body::Rib(_) | Body::Sternum) {
                    continue;
                }
                let v = an.anchors[path[1] as usize].rest;
                let rest = nalgebra::Point3::new(v.x, an.anchors[r].rest.y, v.z);
                an.anchors.push(Anchor { body, rest });
                let z = (an.anchors.len() - 1) as u32;
                an.muscles[m].path.insert(1, z);
            }
            an
        })
        .collect();
    for (name, change) in variants {
        if only.as_deref().is_some_and(|o| !name.starts_with(o)) {
            continue;
        }
        // the hill law's fibres take their chords' lengths already (their gain is 0)
        if name == "fibre chords" && law == dynamics::muscle::MuscleLaw::Hill {
            continue;
        }
        let anatomies = if name == "insertions fixed" {
            &grounded
        } else if name == "apposed insertions" {
            &apposed
        } else {
            &anatomies
        };
        let mut p = base.clone();
        change(&mut p);
        let f: Vec<Figures> = anatomies
            .iter()
            .map(|an| solve(an, p.clone(), a, name == "fibre chords"))
            .collect();
        println!(
            "{name:>24}: dV {:.4} / {:.4} / {:.4} L ({:+.1} / {:+.1} % of level 2), descent \
             {:.2} / {:.2} / {:.2} cm, fibre strain {:.4} / {:.4} / {:.4} (target {:.4}), dV per \
             strain {:.2} / {:.2} / {:.2} L, P_ab {:.0} / {:.0} / {:.0} Pa",
            1e3 * f[0].volume,
            1e3 * f[1].volume,
            1e3 * f[2].volume,
            100.0 * (f[0].volume / f[2].volume - 1.0),
            100.0 * (f[1].volume / f[2].volume - 1.0),
            100.0 * f[0].descent,
            100.0 * f[1].descent,
            100.0 * f[2].descent,
            f[0].strain,
            f[1].strain,
            f[2].strain,
            -p.beta_max_diaphragm * a,
            -1e3 * f[0].volume / f[0].strain,
            -1e3 * f[1].volume / f[1].strain,
            -1e3 * f[2].volume / f[2].strain,
            f[0].abdominal_pressure,
            f[1].abdominal_pressure,
            f[2].abdominal_pressure,
        );
        println!(
            "{:>24}  rib cage displaced {:.4} / {:.4} / {:.4} L, the rest (dome) {:.4} / {:.4} / {:.4} L, \
             fibres' pull on the ribs outward {:.1} / {:.1} / {:.1} N, cranial {:.1} / {:.1} / {:.1} N",
            "",
            1e3 * f[0].rib_cage,
            1e3 * f[1].rib_cage,
            1e3 * f[2].rib_cage,
            1e3 * f[0].dome,
            1e3 * f[1].dome,
            1e3 * f[2].dome,
            f[0].insertion_pull.0,
            f[1].insertion_pull.0,
            f[2].insertion_pull.0,
            f[0].insertion_pull.1,
            f[1].insertion_pull.1,
            f[2].insertion_pull.1,
        );
        let area = |g: &Figures| g.dome_load[2] / g.transdiaphragmatic;
        println!(
            "{:>24}  on the dome's free vertices, vertical, change from rest: diaphragm {:.2} / \
             {:.2} / {:.2} N, dome membrane {:.2} / {:.2} / {:.2} N, the rest {:.2} / {:.2} / \
             {:.2} N; Pdi {:.0} / {:.0} / {:.0} Pa, the rest over Pdi {:.4} / {:.4} / {:.4} m^2, \
             volume over Pdi {:.3} / {:.3} / {:.3} mL/Pa",
            "",
            f[0].dome_load[0],
            f[1].dome_load[0],
            f[2].dome_load[0],
            f[0].dome_load[1],
            f[1].dome_load[1],
            f[2].dome_load[1],
            f[0].dome_load[2],
            f[1].dome_load[2],
            f[2].dome_load[2],
            f[0].transdiaphragmatic,
            f[1].transdiaphragmatic,
            f[2].transdiaphragmatic,
            area(&f[0]),
            area(&f[1]),
            area(&f[2]),
            1e6 * f[0].volume / f[0].transdiaphragmatic,
            1e6 * f[1].volume / f[1].transdiaphragmatic,
            1e6 * f[2].volume / f[2].transdiaphragmatic,
        );
    }
}
