//! What is read off a state: volumes of the trunk, abdomen, thorax and lungs, the volumes
//! displaced by the rib-cage wall and by the abdominal wall (the compartments of
//! optoelectronic plethysmography), the abdominal pressure, the diaphragm dome's and the
//! sternum's displacements. Computed from anchor positions on demand, never inside the
//! right-hand side.
//!
//! Volumes use the divergence theorem over closed, outward-oriented triangle surfaces:
//! V = 1/6 sum_t a . (b x c). The trunk's surface is the rib-cage lining plus the abdominal
//! surface without the dome; splitting that sum (taken about the thorax's rest centroid) by
//! the horizontal plane through the lowest point of the costal margin gives the displaced
//! compartments of optoelectronic plethysmography, rib cage above and abdomen below, which
//! add up to the trunk's volume change.
//! V_thorax = V_trunk - V_abdomen and V_lung = V_thorax - V_non-lung, the heart's, great
//! vessels' and mediastinum's volume, constant over a breath ([`Model::non_lung_volume`]: the
//! thesis's 0.75 lung split at rest, section 4.2), so that lung volume changes are thoracic
//! ones, as optoelectronic plethysmography measures them against spirometry. The thorax and
//! abdomen are corrected by the constant volume the faceted dome cuts off the smooth one
//! (computed when the anatomy is built), so that the levels of detail agree.

mod envelope;
pub mod markers;
pub mod skinning;

use crate::anatomy::{Side, rib_index};
use crate::dynamics::{Model, volume};
use nalgebra::{Point3, Vector3};

/// Volumes and displacements of one state (SI units: m^3, Pa, m).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Observation {
    /// Thoracic cavity volume [m^3].
    pub thorax: f64,
    /// Lung volume [m^3]: the thorax less the non-lung volume.
    pub lung: f64,
    /// Abdominal cavity volume [m^3].
    pub abdomen: f64,
    /// Trunk cavity volume [m^3].
    pub trunk: f64,
    /// Volume displaced by the rib-cage wall since rest [m^3].
    pub rib_cage_displaced: f64,
    /// Volume displaced by the abdominal wall since rest [m^3].
    pub abdomen_displaced: f64,
    /// Abdominal pressure above rest [Pa] (thesis eq. 2.5).
    pub abdominal_pressure: f64,
    /// Cranial displacement of the diaphragm since rest [m]: the dome's piston-equivalent
    /// displacement, volume swept by the dome divided by its projected (horizontal) area.
    pub diaphragm_displacement: f64,
    /// Displacement of the middle of the sternum since rest [m].
    pub sternum_displacement: Vector3<f64>,
    /// Airflow into the lungs [m^3/s], the rate of the thoracic volume (positive in
    /// inspiration).
    pub airway_flow: f64,
    /// Alveolar pressure relative to the body surface [Pa]: the airway opening's less the
    /// drop R V' across the airway resistance.
    pub alveolar_pressure: f64,
    /// Pleural pressure relative to the body surface [Pa]: the alveolar pressure less the
    /// lungs' elastic recoil, -[`crate::dynamics::Params::lung_recoil_at_frc`] at rest.
    pub pleural_pressure: f64,
}

/// Rate of change of the volume enclosed by the closed surface `tris` [m^3/s]: the time
/// derivative of the divergence-theorem sum, 1/6 sum_t (a' . (b x c) + a . (b' x c) +
/// a . (b x c')).
fn volume_rate(pos: &[Point3<f64>], vel: &[Vector3<f64>], tris: &[[u32; 3]]) -> f64 {
    tris.iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| pos[i as usize].coords);
            let [va, vb, vc] = t.map(|i| vel[i as usize]);
            va.dot(&b.cross(&c)) + a.dot(&vb.cross(&c)) + a.dot(&b.cross(&vc))
        })
        .sum::<f64>()
        / 6.0
}

/// Sum of the divergence-theorem terms of `tris` about `origin` (not closed: a wall region).
fn partial_volume(pos: &[Point3<f64>], tris: &[[u32; 3]], origin: &Point3<f64>) -> f64 {
    tris.iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| pos[i as usize] - origin);
            a.dot(&b.cross(&c))
        })
        .sum::<f64>()
        / 6.0
}

/// Right lung's share of the lungs' volume: 53.3 +- 1.3 % standing, 53.6 +- 1.5 % supine (CT
/// volumetry of 32 healthy volunteers; Yamada et al. 2020, Respiration 99:598, Table 3; PMC7490509). It
/// splits the rest lung volume between the sides; the changes are each side's own.
pub const RIGHT_LUNG_FRACTION: f64 = 0.533;

/// One side's share of the wall regions: triangles whose rest centroid lies on that side of
/// the midsagittal plane (z > 0 right) with weight 1, those on the plane with weight 1/2;
/// their divergence sums are taken about a point of the plane.
#[derive(Clone, Debug)]
struct SideRegions {
    /// Rib-cage wall, abdominal wall, dome and thorax, each as (triangle, weight).
    regions: [Vec<([u32; 3], f64)>; 4],
    /// Rest sums of the four, in that order.
    rest: [f64; 4],
    /// Projected (horizontal) area of the side's dome [m^2].
    dome_area: f64,
}

/// Weighted divergence-theorem sum of `tris` about `origin`.
fn weighted_volume(pos: &[Point3<f64>], tris: &[([u32; 3], f64)], origin: &Point3<f64>) -> f64 {
    tris.iter()
        .map(|(t, w)| {
            let [a, b, c] = t.map(|i| pos[i as usize] - origin);
            w * a.dot(&b.cross(&c))
        })
        .sum::<f64>()
        / 6.0
}

/// What one side contributes to an observation (changes since rest).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SideObservation {
    /// Volume displaced by this side's rib-cage wall [m^3].
    pub rib_cage_displaced: f64,
    /// Volume displaced by this side's abdominal wall [m^3].
    pub abdomen_displaced: f64,
    /// Change of this side's share of the thoracic volume, the change of its lung [m^3].
    pub lung_change: f64,
    /// Cranial displacement of this side's hemidiaphragm [m] (piston-equivalent).
    pub diaphragm_displacement: f64,
}

/// Precomputed wall regions of a model for the compartment split.
#[derive(Clone, Debug)]
pub struct Compartments {
    dome: Vec<[u32; 3]>,
    dome_rest: f64,
    dome_area: f64,
    rib_cage_wall: Vec<[u32; 3]>,
    abdominal_wall: Vec<[u32; 3]>,
    origin: Point3<f64>,
    rib_cage_rest: f64,
    wall_rest: f64,
    /// Right, then left.
    sides: [SideRegions; 2],
}

impl Compartments {
    /// Splits `model`'s trunk surface into the rib-cage wall and the abdominal wall as
    /// optoelectronic plethysmography does (Aliverti et al. 2001; Cala et al. 1996): by the
    /// horizontal plane through the lowest point of the costal margin. Above it lie the
    /// pulmonary rib cage and the abdominal (diaphragm-apposed) rib cage, whose wall inside
    /// the costal margin is the upper abdominal surface; below it, the abdomen. A surface
    /// triangle belongs to the side of its rest centroid.
    pub fn new(model: &Model) -> Compartments {
        let margin = costal_margin_height(model);
        let above =
            |t: &[u32; 3]| t.iter().map(|&i| model.rest[i as usize].y).sum::<f64>() / 3.0 >= margin;
        let lining = &model.thorax_triangles[..model.lining_count];
        let (dome, abdominal_surface): (Vec<_>, Vec<_>) = model
            .abdomen_triangles
            .iter()
            .zip(&model.abdomen_dome)
            .partition(|(_, d)| **d);
        let dome: Vec<[u32; 3]> = dome.into_iter().map(|(t, _)| *t).collect();
        let (rib_cage_wall, abdominal_wall): (Vec<[u32; 3]>, Vec<[u32; 3]>) = lining
            .iter()
            .chain(abdominal_surface.into_iter().map(|(t, _)| t))
            .partition(|t| above(t));
        // Projected area: the dome's outward (abdominal) normals point cranially.
        let dome_area = dome
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| model.rest[i as usize]);
                0.5 * (b - a).cross(&(c - a)).y
            })
            .sum::<f64>()
            .max(1e-9);
        let n = (lining.len() * 3) as f64;
        let origin = Point3::from(
            lining
                .iter()
                .flatten()
                .fold(Vector3::zeros(), |s, &i| s + model.rest[i as usize].coords)
                / n.max(1.0),
        );
        // The sides: the midsagittal plane z = 0 splits every region; the sums are taken about
        // the origin moved onto that plane, so that the two sides add up to the whole.
        let mid = Point3::new(origin.x, origin.y, 0.0);
        let centroid_z = |t: &[u32; 3]| t.iter().map(|&i| model.rest[i as usize].z).sum::<f64>();
        // Weight of a triangle on each side: whole on its own side, halved on the plane.
        let weight = |t: &[u32; 3], side: usize| {
            let z = centroid_z(t);
            if z.abs() < 1e-9 {
                0.5
            } else if (z > 0.0) == (side == 0) {
                1.0
            } else {
                0.0
            }
        };
        let sides = [0, 1].map(|side| {
            let regions = [
                rib_cage_wall.as_slice(),
                abdominal_wall.as_slice(),
                dome.as_slice(),
                model.thorax_triangles.as_slice(),
            ]
            .map(|tris| {
                tris.iter()
                    .map(|t| (*t, weight(t, side)))
                    .filter(|(_, w)| *w > 0.0)
                    .collect::<Vec<_>>()
            });
            let rest = regions
                .each_ref()
                .map(|r| weighted_volume(&model.rest, r, &mid));
            let dome_area = regions[2]
                .iter()
                .map(|(t, w)| {
                    let [a, b, c] = t.map(|i| model.rest[i as usize]);
                    w * 0.5 * (b - a).cross(&(c - a)).y
                })
                .sum::<f64>()
                .max(1e-9);
            SideRegions {
                regions,
                rest,
                dome_area,
            }
        });
        Compartments {
            sides,
            dome_rest: partial_volume(&model.rest, &dome, &origin),
            dome,
            dome_area,
            rib_cage_rest: partial_volume(&model.rest, &rib_cage_wall, &origin),
            wall_rest: partial_volume(&model.rest, &abdominal_wall, &origin),
            rib_cage_wall,
            abdominal_wall,
            origin,
        }
    }
}

/// Height [m] of the lowest point of the costal margin at rest: the lowest anchor carried by
/// either tenth rib (the costal margin's lowest point lies on the tenth costal cartilage), or
/// the lowest lining vertex if the model has no ribs.
pub fn costal_margin_height(model: &Model) -> f64 {
    let tenth = [Side::Right, Side::Left].map(|side| rib_index(10, side));
    let lowest = tenth
        .iter()
        .filter_map(|&r| model.rib_anchors.get(r))
        .flatten()
        .map(|&i| model.rest[i as usize].y)
        .fold(f64::INFINITY, f64::min);
    if lowest.is_finite() {
        lowest
    } else {
        model.thorax_triangles[..model.lining_count]
            .iter()
            .flatten()
            .map(|&i| model.rest[i as usize].y)
            .fold(f64::INFINITY, f64::min)
    }
}

/// Observes the state whose anchor positions are `pos` and velocities `vel`, with the airway
/// opening at `airway_opening` [Pa] (0 breathing air).
pub fn observe(
    model: &Model,
    compartments: &Compartments,
    pos: &[Point3<f64>],
    vel: &[Vector3<f64>],
    airway_opening: f64,
) -> Observation {
    // The mesh's volumes (the dynamics' own), then corrected for the dome's faceting so
    // that every level of detail reports the volumes of the smooth surfaces.
    let abdomen_mesh = volume(pos, &model.abdomen_triangles);
    let thorax_mesh = volume(pos, &model.thorax_triangles);
    let thorax = thorax_mesh - model.dome_faceting_volume;
    let abdomen = abdomen_mesh + model.dome_faceting_volume;
    let airway_flow = volume_rate(pos, vel, &model.thorax_triangles);
    let alveolar_pressure = airway_opening - model.airway_resistance * airway_flow;
    let pleural_pressure =
        alveolar_pressure - model.params.lung_recoil_at_frc - model.pleural.recoil(thorax_mesh);
    let o = &compartments.origin;
    let rib_cage_displaced =
        partial_volume(pos, &compartments.rib_cage_wall, o) - compartments.rib_cage_rest;
    let abdomen_displaced =
        partial_volume(pos, &compartments.abdominal_wall, o) - compartments.wall_rest;
    let diaphragm_displacement = (partial_volume(pos, &compartments.dome, o)
        - compartments.dome_rest)
        / compartments.dome_area;
    let probe = model.sternum_probe as usize;
    Observation {
        thorax,
        lung: thorax - model.non_lung_volume,
        abdomen,
        trunk: thorax + abdomen,
        rib_cage_displaced,
        abdomen_displaced,
        abdominal_pressure: model.params.bulk_modulus
            * (model.abdomen_rest_volume / abdomen_mesh - 1.0),
        diaphragm_displacement,
        sternum_displacement: pos[probe] - model.rest[probe],
        airway_flow,
        alveolar_pressure,
        pleural_pressure,
    }
}

/// Each side's share of the observation of the state whose anchor positions are `pos`:
/// right, then left (kept apart from [`observe`], so that only readers of a side pay for it).
pub fn observe_sides(compartments: &Compartments, pos: &[Point3<f64>]) -> [SideObservation; 2] {
    let o = &compartments.origin;
    let mid = Point3::new(o.x, o.y, 0.0);
    compartments.sides.each_ref().map(|s| {
        let now = s.regions.each_ref().map(|r| weighted_volume(pos, r, &mid));
        SideObservation {
            rib_cage_displaced: now[0] - s.rest[0],
            abdomen_displaced: now[1] - s.rest[1],
            diaphragm_displacement: (now[2] - s.rest[2]) / s.dome_area,
            lung_change: now[3] - s.rest[3],
        }
    })
}
