//! What is read off a state: volumes of the trunk, abdomen, thorax and lungs, the volumes
//! displaced by the rib-cage wall and by the abdominal wall (the compartments of
//! optoelectronic plethysmography), the abdominal pressure, the diaphragm dome's and the
//! sternum's displacements. Computed from anchor positions on demand, never inside the
//! right-hand side.
//!
//! Volumes use the divergence theorem over closed, outward-oriented triangle surfaces:
//! V = 1/6 sum_t a . (b x c). The trunk's surface is the rib-cage lining plus the abdominal
//! surface without the dome; splitting that sum (taken about the thorax's rest centroid) by
//! the horizontal plane through the lowest point of the costal margin (triangles the plane
//! crosses at rest cut along it, so that the split does not depend on the mesh's
//! resolution) gives the displaced compartments of optoelectronic plethysmography, rib cage
//! above and abdomen below, which add up to the trunk's volume change.
//! V_thorax = V_trunk - V_abdomen and V_lung = V_thorax - V_non-lung, the heart's, great
//! vessels' and mediastinum's volume, constant over a breath ([`Model::non_lung_volume`](crate::dynamics::Structure::non_lung_volume): the
//! thesis's 0.75 lung split at rest, section 4.2), so that lung volume changes are thoracic
//! ones, as optoelectronic plethysmography measures them against spirometry. The thorax and
//! abdomen are corrected by the constant volume the faceted dome cuts off the smooth one
//! (computed when the anatomy is built), so that the levels of detail agree.

mod envelope;
pub mod markers;
pub mod skinning;

use crate::anatomy::{Side, rib_index};
use crate::dynamics::{Activations, Model, volume};
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
    /// Airflow into the lungs through the airway [m^3/s], the rate of the thoracic volume
    /// (positive in inspiration); 0 with the airway occluded, where a change of the lung
    /// volume is the gas's compression, not a flow.
    pub airway_flow: f64,
    /// Alveolar pressure relative to the body surface [Pa]: the airway opening's less the
    /// drop R V' across the airway resistance; with the airway occluded, Boyle's law on the
    /// lungs' gas ([`crate::dynamics::airway`]).
    pub alveolar_pressure: f64,
    /// Pressure at the mouth relative to the body surface [Pa]: the airway opening's with
    /// the airway open; behind an occlusion (between the lips and the shutter), the alveolar
    /// pressure, since no gas flows.
    pub mouth_pressure: f64,
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

/// Barycentric corners of a whole triangle.
const WHOLE: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Distance [m] from a cutting plane below which a rest point counts as lying in it.
const ON_PLANE: f64 = 1e-12;

/// A part of a surface triangle cut off by planes through the rest pose: the triangle's
/// anchors, the barycentric coordinates of the part's corners in it (the part's points move
/// with the triangle's material), and the part's weight, 1, or 1/2 for a triangle lying in a
/// cutting plane, shared by the two sides.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Piece {
    tri: [u32; 3],
    corners: [[f64; 3]; 3],
    weight: f64,
}

impl Piece {
    /// The whole triangle `tri`.
    fn whole(tri: [u32; 3]) -> Piece {
        Piece {
            tri,
            corners: WHOLE,
            weight: 1.0,
        }
    }

    /// The part's corners at the anchor positions `pos`.
    fn points(&self, pos: &[Point3<f64>]) -> [Point3<f64>; 3] {
        let [a, b, c] = self.tri.map(|i| pos[i as usize].coords);
        self.corners
            .map(|[u, v, w]| Point3::from(a * u + b * v + c * w))
    }
}

/// A cutting plane through the rest pose: coordinate `axis` (1 = y, 2 = z) equal to `level`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Plane {
    axis: usize,
    level: f64,
}

/// Splits `piece` by `plane` at the rest positions `rest`: its parts at or above the plane
/// (the coordinate at least the level), then those at or below, each a fan of triangles of
/// the clipped polygon (Sutherland-Hodgman), so that the parts tile the piece exactly and
/// keep its orientation. A piece lying in the plane goes to both sides with half its weight.
fn split(piece: &Piece, rest: &[Point3<f64>], plane: Plane) -> (Vec<Piece>, Vec<Piece>) {
    let d = piece.points(rest).map(|p| {
        let d = p[plane.axis] - plane.level;
        if d.abs() < ON_PLANE { 0.0 } else { d }
    });
    if d.iter().all(|&x| x == 0.0) {
        let half = Piece {
            weight: 0.5 * piece.weight,
            ..*piece
        };
        return (vec![half], vec![half]);
    }
    if d.iter().all(|&x| x >= 0.0) {
        return (vec![*piece], Vec::new());
    }
    if d.iter().all(|&x| x <= 0.0) {
        return (Vec::new(), vec![*piece]);
    }
    let side = |sign: f64| {
        let mut polygon: Vec<[f64; 3]> = Vec::with_capacity(4);
        for k in 0..3 {
            let (j, dk, dj) = ((k + 1) % 3, sign * d[k], sign * d[(k + 1) % 3]);
            if dk >= 0.0 {
                polygon.push(piece.corners[k]);
            }
            if (dk > 0.0 && dj < 0.0) || (dk < 0.0 && dj > 0.0) {
                let t = dk / (dk - dj);
                let (a, b) = (piece.corners[k], piece.corners[j]);
                polygon.push([0, 1, 2].map(|m| a[m] + t * (b[m] - a[m])));
            }
        }
        (1..polygon.len().saturating_sub(1))
            .map(|k| Piece {
                corners: [polygon[0], polygon[k], polygon[k + 1]],
                ..*piece
            })
            .collect::<Vec<_>>()
    };
    (side(1.0), side(-1.0))
}

/// A wall region: whole triangles (weight 1), and the pieces of triangles cut by the planes
/// that bound it.
#[derive(Clone, Debug, Default, PartialEq)]
struct Region {
    whole: Vec<[u32; 3]>,
    pieces: Vec<Piece>,
}

impl Region {
    /// The region made of `pieces`.
    fn new(pieces: Vec<Piece>) -> Region {
        let (whole, pieces): (Vec<Piece>, Vec<Piece>) = pieces
            .into_iter()
            .partition(|p| p.corners == WHOLE && p.weight == 1.0);
        Region {
            whole: whole.into_iter().map(|p| p.tri).collect(),
            pieces,
        }
    }

    /// The region split by `plane` at the rest positions `rest`: above, then below.
    fn split(&self, rest: &[Point3<f64>], plane: Plane) -> (Region, Region) {
        let (mut above, mut below) = (Vec::new(), Vec::new());
        for p in self
            .whole
            .iter()
            .map(|&t| Piece::whole(t))
            .chain(self.pieces.iter().copied())
        {
            let (a, b) = split(&p, rest, plane);
            above.extend(a);
            below.extend(b);
        }
        (Region::new(above), Region::new(below))
    }

    /// Divergence-theorem sum of the region about `origin` at the anchor positions `pos`.
    fn volume(&self, pos: &[Point3<f64>], origin: &Point3<f64>) -> f64 {
        partial_volume(pos, &self.whole, origin)
            + self
                .pieces
                .iter()
                .map(|p| {
                    let [a, b, c] = p.points(pos).map(|q| q - origin);
                    p.weight * a.dot(&b.cross(&c))
                })
                .sum::<f64>()
                / 6.0
    }

    /// Projected (horizontal) area of the region at `pos`, positive where its normals point
    /// cranially [m^2].
    fn projected_area(&self, pos: &[Point3<f64>]) -> f64 {
        let area = |[a, b, c]: [Point3<f64>; 3]| 0.5 * (b - a).cross(&(c - a)).y;
        self.whole
            .iter()
            .map(|t| area(t.map(|i| pos[i as usize])))
            .sum::<f64>()
            + self
                .pieces
                .iter()
                .map(|p| p.weight * area(p.points(pos)))
                .sum::<f64>()
    }
}

/// One side's share of the wall regions: their parts on that side of the midsagittal plane
/// z = 0 at rest (z > 0 right), triangles cut exactly by the plane, those lying in it shared
/// half and half; their divergence sums are taken about a point of the plane.
#[derive(Clone, Debug)]
struct SideRegions {
    /// Rib-cage wall, abdominal wall, dome and thorax.
    regions: [Region; 4],
    /// Rest sums of the four, in that order.
    rest: [f64; 4],
    /// Projected (horizontal) area of the side's dome [m^2].
    dome_area: f64,
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
    rib_cage_wall: Region,
    abdominal_wall: Region,
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
    /// triangle the plane crosses at rest is cut along it, each part following the
    /// triangle's material, so that the split does not depend on the mesh's resolution (a
    /// triangle assigned whole by its centroid moved up to half a triangle's height of wall
    /// across the plane: 16 times the area at level of detail 0 as at 2).
    pub fn new(model: &Model) -> Compartments {
        let margin = costal_margin_height(model);
        let lining = &model.thorax_triangles[..model.lining_count];
        let (dome, abdominal_surface): (Vec<_>, Vec<_>) = model
            .abdomen_triangles
            .iter()
            .zip(&model.abdomen_dome)
            .partition(|(_, d)| **d);
        let dome: Vec<[u32; 3]> = dome.into_iter().map(|(t, _)| *t).collect();
        let wall = Region::new(
            lining
                .iter()
                .chain(abdominal_surface.into_iter().map(|(t, _)| t))
                .map(|&t| Piece::whole(t))
                .collect(),
        );
        let (rib_cage_wall, abdominal_wall) = wall.split(
            &model.rest,
            Plane {
                axis: 1,
                level: margin,
            },
        );
        let dome_region = Region::new(dome.iter().map(|&t| Piece::whole(t)).collect());
        // Projected area: the dome's outward (abdominal) normals point cranially.
        let dome_area = dome_region.projected_area(&model.rest).max(1e-9);
        let n = (lining.len() * 3) as f64;
        let origin = Point3::from(
            lining
                .iter()
                .flatten()
                .fold(Vector3::zeros(), |s, &i| s + model.rest[i as usize].coords)
                / n.max(1.0),
        );
        // The sides: the midsagittal plane z = 0 cuts every region; the sums are taken about
        // the origin moved onto that plane, so that the two sides add up to the whole.
        let mid = Point3::new(origin.x, origin.y, 0.0);
        let thorax = Region::new(
            model
                .thorax_triangles
                .iter()
                .map(|&t| Piece::whole(t))
                .collect(),
        );
        let midsagittal = Plane {
            axis: 2,
            level: 0.0,
        };
        let halves = [&rib_cage_wall, &abdominal_wall, &dome_region, &thorax]
            .map(|r| r.split(&model.rest, midsagittal));
        let sides = [0, 1].map(|side| {
            let regions = halves
                .each_ref()
                .map(|(right, left)| if side == 0 { right } else { left }.clone());
            let rest = regions.each_ref().map(|r| r.volume(&model.rest, &mid));
            let dome_area = regions[2].projected_area(&model.rest).max(1e-9);
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
            rib_cage_rest: rib_cage_wall.volume(&model.rest, &origin),
            wall_rest: abdominal_wall.volume(&model.rest, &origin),
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

/// An observation of an equilibrium of the quasi-static mode
/// ([`crate::dynamics::statics`]) with the reduced system's airflow `flow` [m^3/s] and
/// pleural pressure relative to rest `pleural` [Pa] in place of those read off the positions'
/// velocities (zero at an equilibrium): P_alv = P_ao - R_aw flow, and the pleural pressure
/// P_pl - P_L(FRC) on the same absolute scale as [`observe`]'s.
pub fn with_flow(
    model: &Model,
    observation: Observation,
    flow: f64,
    pleural: f64,
    airway_opening: f64,
) -> Observation {
    Observation {
        airway_flow: flow,
        alveolar_pressure: airway_opening - model.airway_resistance * flow,
        mouth_pressure: airway_opening,
        pleural_pressure: pleural - model.params.lung_recoil_at_frc,
        ..observation
    }
}

/// Observes the state whose anchor positions are `pos` and velocities `vel`, with the airway
/// opening at `airway_opening` [Pa] (0 breathing air) and the airway occluded on the dry gas
/// content `occlusion` ([`crate::dynamics::Activations::occlusion`]; `None`: open).
pub fn observe(
    model: &Model,
    compartments: &Compartments,
    pos: &[Point3<f64>],
    vel: &[Vector3<f64>],
    airway_opening: f64,
    occlusion: Option<f64>,
) -> Observation {
    // The mesh's volumes (the dynamics' own), then corrected for the dome's faceting so
    // that every level of detail reports the volumes of the smooth surfaces.
    let abdomen_mesh = volume(pos, &model.abdomen_triangles);
    let thorax_mesh = volume(pos, &model.thorax_triangles);
    let thorax = thorax_mesh - model.dome_faceting_volume;
    let abdomen = abdomen_mesh + model.dome_faceting_volume;
    let airway_flow = volume_rate(pos, vel, &model.thorax_triangles);
    let alveolar = model.alveolar(
        &Activations::default()
            .with_airway_opening(airway_opening)
            .with_occlusion(occlusion),
        thorax_mesh,
        airway_flow,
    );
    let alveolar_pressure = alveolar.pressure;
    let (airway_flow, mouth_pressure) = match occlusion {
        None => (airway_flow, airway_opening),
        Some(_) => (0.0, alveolar_pressure),
    };
    let pleural_pressure =
        alveolar_pressure - model.params.lung_recoil_at_frc - model.pleural.recoil(thorax_mesh);
    let o = &compartments.origin;
    let rib_cage_displaced = compartments.rib_cage_wall.volume(pos, o) - compartments.rib_cage_rest;
    let abdomen_displaced = compartments.abdominal_wall.volume(pos, o) - compartments.wall_rest;
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
        mouth_pressure,
        pleural_pressure,
    }
}

/// Each side's share of the observation of the state whose anchor positions are `pos`:
/// right, then left (kept apart from [`observe`], so that only readers of a side pay for it).
pub fn observe_sides(compartments: &Compartments, pos: &[Point3<f64>]) -> [SideObservation; 2] {
    let o = &compartments.origin;
    let mid = Point3::new(o.x, o.y, 0.0);
    compartments.sides.each_ref().map(|s| {
        let now = s.regions.each_ref().map(|r| r.volume(pos, &mid));
        SideObservation {
            rib_cage_displaced: now[0] - s.rest[0],
            abdomen_displaced: now[1] - s.rest[1],
            diaphragm_displacement: (now[2] - s.rest[2]) / s.dome_area,
            lung_change: now[3] - s.rest[3],
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Divergence sum and area of a list of pieces at `pos` about `origin`.
    fn sums(pieces: &[Piece], pos: &[Point3<f64>], origin: &Point3<f64>) -> (f64, f64) {
        let region = Region::new(pieces.to_vec());
        let area = pieces
            .iter()
            .map(|p| {
                let [a, b, c] = p.points(pos);
                p.weight * 0.5 * (b - a).cross(&(c - a)).norm()
            })
            .sum();
        (region.volume(pos, origin), area)
    }

    #[test]
    fn a_clipped_triangles_parts_add_up_to_the_whole() {
        let rest = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.2),
            Point3::new(0.3, 1.0, -0.4),
        ];
        let whole = Piece::whole([0, 1, 2]);
        let (above, below) = split(
            &whole,
            &rest,
            Plane {
                axis: 1,
                level: 0.5,
            },
        );
        assert_eq!((above.len(), below.len()), (1, 2));
        // The part above y = 0.5 is the triangle similar to the whole with ratio 1/2: a
        // quarter of its area.
        let origin = Point3::new(0.1, -0.3, 0.7);
        let (v, a) = sums(&[whole], &rest, &origin);
        let (va, aa) = sums(&above, &rest, &origin);
        let (vb, ab) = sums(&below, &rest, &origin);
        assert!((aa - 0.25 * a).abs() < 1e-12, "{aa} of {a}");
        assert!((aa + ab - a).abs() < 1e-12);
        assert!((va + vb - v).abs() < 1e-12);
        // The parts follow the material: moved anywhere, they still add up to the whole.
        let moved = [
            Point3::new(0.2, 0.1, -0.3),
            Point3::new(1.4, -0.2, 0.5),
            Point3::new(0.1, 1.3, 0.2),
        ];
        let (v, a) = sums(&[whole], &moved, &origin);
        let (va, aa) = sums(&above, &moved, &origin);
        let (vb, ab) = sums(&below, &moved, &origin);
        assert!((aa + ab - a).abs() < 1e-12);
        assert!((va + vb - v).abs() < 1e-12);
        // A vertex on the plane: one part on each side; a triangle in the plane: halves.
        let (above, below) = split(
            &whole,
            &rest,
            Plane {
                axis: 1,
                level: 0.0,
            },
        );
        assert_eq!((above.len(), below.len()), (1, 0));
        let flat = [rest[0], rest[1], Point3::new(0.5, 0.0, 1.0)];
        let (above, below) = split(
            &whole,
            &flat,
            Plane {
                axis: 1,
                level: 0.0,
            },
        );
        assert_eq!((above[0].weight, below[0].weight), (0.5, 0.5));
    }

    /// The unit cube [0, 1]^3 as 12 outward triangles, each face cut into `n` x `n` squares.
    fn cube(n: usize) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
        let (mut pos, mut tris) = (Vec::new(), Vec::new());
        for axis in 0..3 {
            for high in [false, true] {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let base = pos.len() as u32;
                for i in 0..=n {
                    for j in 0..=n {
                        let mut p = [0.0; 3];
                        p[axis] = if high { 1.0 } else { 0.0 };
                        p[u] = i as f64 / n as f64;
                        p[v] = j as f64 / n as f64;
                        pos.push(Point3::from(p));
                    }
                }
                let at = |i: usize, j: usize| base + (i * (n + 1) + j) as u32;
                for i in 0..n {
                    for j in 0..n {
                        let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                        // u x v = axis: counter-clockwise in (u, v) faces +axis.
                        if high {
                            tris.extend([[a, b, c], [a, c, d]]);
                        } else {
                            tris.extend([[a, c, b], [a, d, c]]);
                        }
                    }
                }
            }
        }
        (pos, tris)
    }

    #[test]
    fn a_plane_splits_a_closed_surfaces_volume_exactly_at_every_resolution() {
        for n in [1, 2, 5] {
            let (pos, tris) = cube(n);
            let whole = Region::new(tris.iter().map(|&t| Piece::whole(t)).collect());
            assert!((whole.volume(&pos, &Point3::origin()) - 1.0).abs() < 1e-12);
            // About a point of the cutting plane, the plane's own cap adds nothing: each
            // part's sum is the volume of the solid on its side.
            let plane = Plane {
                axis: 1,
                level: 0.37,
            };
            let (above, below) = whole.split(&pos, plane);
            let o = Point3::new(0.2, 0.37, 0.9);
            assert!((above.volume(&pos, &o) - 0.63).abs() < 1e-12, "n = {n}");
            assert!((below.volume(&pos, &o) - 0.37).abs() < 1e-12, "n = {n}");
            // A cut through a layer of vertices (z = 0.4 at n = 5) and the faces lying in
            // the plane z = 0 shared half and half.
            let (right, left) = whole.split(
                &pos,
                Plane {
                    axis: 2,
                    level: 0.4,
                },
            );
            let o = Point3::new(0.5, 0.5, 0.4);
            assert!((right.volume(&pos, &o) - 0.6).abs() < 1e-12, "n = {n}");
            assert!((left.volume(&pos, &o) - 0.4).abs() < 1e-12, "n = {n}");
            let (right, left) = whole.split(
                &pos,
                Plane {
                    axis: 2,
                    level: 0.0,
                },
            );
            let o = Point3::origin();
            assert!((right.volume(&pos, &o) + left.volume(&pos, &o) - 1.0).abs() < 1e-12);
            // Deformed, the parts (which follow the material) still add up to the whole.
            let moved: Vec<Point3<f64>> = pos
                .iter()
                .map(|p| Point3::new(p.x * (1.0 + 0.1 * p.y), p.y, p.z))
                .collect();
            let (va, vb) = (above.volume(&moved, &o), below.volume(&moved, &o));
            assert!((va + vb - whole.volume(&moved, &o)).abs() < 1e-12);
        }
    }
}
