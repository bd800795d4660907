//! The compiled structure: the part of the compiled model read straight from an [`Anatomy`]
//! (geometry, carriers, elements, springs, cavity triangles, true masses and inertias, rest
//! volumes, the pleural law, index tables), the first phase of
//! [`Model::compile`](super::Model::compile). Nothing here depends on the mass matrix or the
//! preloads, which [`super::inertia`] and [`super::accelerations::Preload::at_rest`] derive
//! from it before [`super::Model`] is assembled.

use super::muscle::MuscleLaw;
use super::params::{
    ABDOMINAL_CONTENTS_DENSITY, GRAVITY, GravityLoads, Params, WALL_LOAD_FLOOR, wall_load_at_lowest,
};
use super::pleural::{PleuralLaw, capacity_ratios};
use crate::anatomy::{Anatomy, Body, MuscleGroup, Side, VertexRole};
use nalgebra::{Matrix3, Point3, Vector3};

/// Number of rib bodies.
pub const RIBS: usize = 24;

/// Rest lung volume as a fraction of the thoracic cavity volume, the thesis's split (Maldonado
/// 2011, section 4.2: lung volume 0.75 x thoracic volume). Only the rest split: the rest of the
/// cavity (heart, great vessels, mediastinum) keeps its volume over a breath, so lung volume
/// changes equal thoracic volume changes, as optoelectronic plethysmography shows against
/// spirometry (Aliverti et al. 2001, Am J Respir Crit Care Med 164:1016: chest-wall displaced
/// volume within -4.2 +- 6.2 % of spirometry in quiet breathing). For the default man the split
/// leaves 1.13 L of non-lung volume (rest thorax 4.51 L, `torso simulate`: end-expiratory lung
/// volume 3.385 L at 0.75).
pub const REST_LUNG_FRACTION: f64 = 0.75;

/// Code of an element's group when it is passive (membrane), and the slot of a membrane edge
/// of the abdominal wall when it is a linear spring (without
/// [`super::Params::abdominal_wall_tension_only`]).
pub const PASSIVE: u8 = u8::MAX;

/// Slot of a membrane edge of the diaphragm's dome (group [`PASSIVE`]): tension only, like a
/// muscle, since a membrane wrinkles rather than carry compression (`dynamics::forces`).
/// With linear edges the dome's flat top went into compression at the end of a quiet
/// expiration and their negative transverse stiffness -|f| / L made its static equilibrium
/// a saddle (measured: +0.03 to +0.41 N/m at level 1, `examples/quasi_static`), which the
/// quasi-static mode could not follow. The abdominal wall's edges take this slot too when
/// [`super::Params::abdominal_wall_tension_only`] says so (the passive-and-active law's soft
/// wall, whose foundation no longer holds them); otherwise they stay linear, the stiff wall's
/// foundation holding its vertices in every direction.
pub const PASSIVE_SLACK: u8 = u8::MAX - 1;

/// Axial spring-damper elements (muscles and membrane), structure of arrays. Element e runs
/// along the anchors `path[start[e]..start[e + 1]]`; its length is the path's length.
#[derive(Clone, Debug)]
pub struct Elements {
    /// Offsets into `path`, one more than the number of elements.
    pub start: Vec<u32>,
    /// Anchors of all paths, concatenated.
    pub path: Vec<u32>,
    /// Rest length l0 [m].
    pub rest_length: Vec<f64>,
    /// Stiffness c [N/m].
    pub stiffness: Vec<f64>,
    /// Damping gamma [N s/m].
    pub damping: Vec<f64>,
    /// Muscle group index, or [`PASSIVE`].
    pub group: Vec<u8>,
    /// Side code: 0 right, 1 left, 2 midline.
    pub side: Vec<u8>,
    /// Contraction per unit activation, beta_max g s (g: the regional gain; s: the tissue's
    /// rest length over the path's, [`crate::anatomy::MuscleElement::tissue_length`], 1 for
    /// most elements).
    pub gain: Vec<f64>,
    /// Index of the element's activation in [`Activations::table`](super::Activations::table):
    /// 3 group + side for a muscle, [`PASSIVE`] (whose entry is 0) for the membrane.
    pub slot: Vec<u8>,
    /// Anchors of a two-point element (most of them), or [`VIA`] twice for a path with via
    /// points: the force loop reads them without going through `start` and `path`.
    pub ends: Vec<[u32; 2]>,
    /// Largest isometric force F_max [N] of a muscle under the passive-and-active law
    /// ([`super::muscle::MuscleLaw::Hill`]); 0 for an element whose force is the linear
    /// spring of `stiffness` and `rest_length` (the membrane, and muscles under the thesis's
    /// law).
    pub max_force: Vec<f64>,
    /// Optimal length l_opt [m] of a Hill muscle (0 elsewhere).
    pub optimal_length: Vec<f64>,
    /// Slack length l_s [m] of a Hill muscle's passive tissue (0 elsewhere).
    pub slack_length: Vec<f64>,
    /// Regional gain g of a Hill muscle's activation, a g (0 elsewhere).
    pub drive: Vec<f64>,
}

/// The `ends` of an element whose path has via points.
pub const VIA: u32 = u32::MAX;

/// Core radius [m] of a muscle band wrapping over via points: each segment d of a path with
/// via points counts sqrt(|d|^2 + c^2) towards the element's length, as a band of that
/// half-thickness would (transversus abdominis and the diaphragm are a few millimetres
/// thick). A string through points has no such core: under tension it drags a via vertex
/// onto its neighbour, where the pull T (n_k - n_{k-1}) flips direction and its transverse
/// stiffness T / |d| has no bound, and the solver stalls (maximal abdominal effort pulled the
/// transversus's first via vertex onto its origin 1 cm away: 1.4 us steps). With the core the
/// stiffness stays below T / c and the force is smooth; on segments of a few centimetres the
/// lengths change by a fraction of a percent, rest lengths included (same formula).
pub const PATH_CORE: f64 = 0.003;

/// The length a segment `d` of a path with via points counts: sqrt(|d|^2 + [`PATH_CORE`]^2).
#[inline]
pub fn via_segment_length(d: &Vector3<f64>) -> f64 {
    (d.norm_squared() + PATH_CORE * PATH_CORE).sqrt()
}

/// Length of the path through `points` (anchor indices into `pos`): plain for two points,
/// with [`via_segment_length`] when the path has via points.
pub fn path_length(pos: &[Point3<f64>], path: &[u32]) -> f64 {
    let segment = |w: &[u32]| pos[w[1] as usize] - pos[w[0] as usize];
    if path.len() == 2 {
        segment(path).norm()
    } else {
        path.windows(2)
            .map(|w| via_segment_length(&segment(w)))
            .sum()
    }
}

impl Default for Elements {
    fn default() -> Self {
        Elements {
            start: vec![0],
            path: Vec::new(),
            rest_length: Vec::new(),
            stiffness: Vec::new(),
            damping: Vec::new(),
            group: Vec::new(),
            side: Vec::new(),
            gain: Vec::new(),
            slot: Vec::new(),
            ends: Vec::new(),
            max_force: Vec::new(),
            optimal_length: Vec::new(),
            slack_length: Vec::new(),
            drive: Vec::new(),
        }
    }
}

/// Turns the element just pushed for muscle `m` (rest length `l0` at FRC in `posture`) into
/// a passive-and-active element ([`super::muscle`]): its optimal and slack lengths, its
/// largest force and regional gain, no activation-shortened rest length, and, for the damping
/// and the mass scaling that read `stiffness`, a stiffness scale: the tangent stiffness at
/// rest under full activation as the law had it before k_A was confined to stretch beyond the
/// optimal length (the passive slope plus (f_L' + k_A) F_max / l_opt). It is an upper bound on
/// the present law's slope (for the standing diaphragm at x = 0.917, 1.64 against 0.36
/// F_max / l_opt in its active part), kept so that the dynamics' numerics did not change with
/// the law; damped like every element.
fn hill_element(
    elements: &mut Elements,
    m: &crate::anatomy::MuscleElement,
    l0: f64,
    posture: crate::anatomy::Posture,
    rayleigh: f64,
) {
    use super::muscle::{RestLengths, active, active_stiffness, stiffness};
    use crate::anatomy::{MuscleGroup, Posture};
    let lengths = if m.group == MuscleGroup::Diaphragm {
        let ratio =
            super::diaphragm_length_ratio(posture) / super::diaphragm_length_ratio(Posture::Supine);
        RestLengths::diaphragm(l0, ratio)
    } else {
        RestLengths::at_rest(l0)
    };
    let f = m.max_force * super::muscle::hill_force_factor(m.group);
    // the passive slope, plus f_L's slope and k_A at full activation: the scale of the stiffness
    // an active element can have, whichever side of its optimal length it stands
    // Thelen's f_L's own slope: the active curve without its k_A term
    let (_, f_l_slope) = active(l0 / lengths.optimal, 0.0);
    let k = stiffness(l0, lengths.optimal, lengths.slack, f, 0.0, 0.0)
        + f * (f_l_slope + active_stiffness()) / lengths.optimal;
    let e = elements.len() - 1;
    elements.max_force[e] = f;
    elements.optimal_length[e] = lengths.optimal;
    elements.slack_length[e] = lengths.slack;
    elements.drive[e] = m.gain;
    elements.gain[e] = 0.0;
    elements.stiffness[e] = k;
    elements.damping[e] = rayleigh * k;
}

impl Elements {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.rest_length.len()
    }
    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.rest_length.is_empty()
    }
    /// Anchors along element `e`.
    pub fn path_of(&self, e: usize) -> &[u32] {
        &self.path[self.start[e] as usize..self.start[e + 1] as usize]
    }
    #[allow(clippy::too_many_arguments)]
    fn push(&mut self, path: &[u32], l0: f64, k: f64, c: f64, group: u8, side: u8, gain: f64) {
        self.path.extend_from_slice(path);
        self.start.push(self.path.len() as u32);
        self.rest_length.push(l0);
        self.stiffness.push(k);
        self.damping.push(c);
        self.group.push(group);
        self.side.push(side);
        self.gain.push(gain);
        self.max_force.push(0.0);
        self.optimal_length.push(0.0);
        self.slack_length.push(0.0);
        self.drive.push(0.0);
        self.ends.push(match path {
            [a, b] => [*a, *b],
            _ => [VIA, VIA],
        });
        self.slot.push(if group == PASSIVE {
            PASSIVE
        } else {
            3 * group + side
        });
    }
}

/// Zero-length vector springs (cartilage joints, wall foundation, dome support), structure of
/// arrays.
#[derive(Clone, Debug, Default)]
pub struct VectorSprings {
    /// Whether the spring acts in the horizontal plane only (the model's y is free): the
    /// dome's support by the lungs and the rib cage, which lets it slide cranio-caudally.
    pub horizontal: Vec<bool>,
    /// First anchor.
    pub a: Vec<u32>,
    /// Second anchor.
    pub b: Vec<u32>,
    /// Stiffness [N/m].
    pub stiffness: Vec<f64>,
    /// Damping [N s/m].
    pub damping: Vec<f64>,
    /// Outward unit normal of the wall at a foundation spring's vertex, at rest (zero for the
    /// other springs).
    pub normal: Vec<Vector3<f64>>,
    /// Unloading length lambda [m] of a wall foundation spring along `normal`: its rest load
    /// over its stiffness per area, over which it softens as the wall moves inwards
    /// (`Params::abdominal_wall_unloading`, [`super::forces::unloading_force`]); 0: linear.
    pub unloading: Vec<f64>,
}

/// Where an anchor's position comes from, compiled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Carrier {
    /// Fixed point.
    Ground,
    /// Rib body index.
    Rib(u16),
    /// The sternum.
    Sternum,
    /// Free vertex index.
    Vertex(u32),
}

/// The compiled structure (module doc): everything of the model that never changes during a
/// run except the mass matrix and the preloads.
#[derive(Clone, Debug)]
pub struct Structure {
    /// Constants used.
    pub params: Params,
    /// Carrier of each anchor.
    pub carrier: Vec<Carrier>,
    /// Rest position of each anchor.
    pub rest: Vec<Point3<f64>>,
    /// Anchors carried by each rib.
    pub rib_anchors: Vec<Vec<u32>>,
    /// Anchors carried by the sternum.
    pub sternum_anchors: Vec<u32>,
    /// Anchor of each free vertex.
    pub vertex_anchor: Vec<u32>,
    /// Rest arm p0 - h of each anchor of `rib_anchors[r]` about its rib's hinge point,
    /// precomputed for the kinematics.
    pub rib_arm: Vec<Vec<Vector3<f64>>>,
    /// Rest arm p0 - x0 of each anchor of `sternum_anchors` about the sternum's centre of mass.
    pub sternum_arm: Vec<Vector3<f64>>,
    /// Rib hinge points.
    pub rib_head: Vec<Point3<f64>>,
    /// Rib hinge axes (unit).
    pub rib_axis: Vec<Vector3<f64>>,
    /// Rib moments of inertia about their axes [kg m^2] (true; the dynamics integrates with
    /// [`Model::mass`](super::Model::mass)).
    pub rib_inertia: Vec<f64>,
    /// Rib masses [kg] (true masses: gravity acts on them).
    pub rib_mass: Vec<f64>,
    /// Rib centres of mass at rest.
    pub rib_com: Vec<Point3<f64>>,
    /// Joint stiffness per rib [N m/rad].
    pub rib_stiffness: Vec<f64>,
    /// Joint damping per rib [N m s/rad].
    pub rib_damping: Vec<f64>,
    /// Sternum mass [kg] (true).
    pub sternum_mass: f64,
    /// Sternum inertia about its centre of mass, at rest orientation [kg m^2] (true).
    pub sternum_inertia: Matrix3<f64>,
    /// Sternum centre of mass at rest.
    pub sternum_com: Point3<f64>,
    /// Free vertex masses [kg] (true).
    pub vertex_mass: Vec<f64>,
    /// Nodal damping of each free vertex [N s/m] (thesis eq. 2.1, gamma_i).
    pub vertex_damping: Vec<f64>,
    /// Axial elements: muscles then membrane.
    pub elements: Elements,
    /// Number of muscle elements (the first ones in `elements`).
    pub muscle_count: usize,
    /// Cartilage joints and wall foundation springs.
    pub springs: VectorSprings,
    /// Closed abdominal surface (anchor indices).
    pub abdomen_triangles: Vec<[u32; 3]>,
    /// Whether each abdominal triangle belongs to the dome.
    pub abdomen_dome: Vec<bool>,
    /// Whether each abdominal triangle has a corner that moves: the pressure forces on a
    /// triangle fixed to the ground act on nothing and are not applied (its volume counts).
    pub abdomen_moving: Vec<bool>,
    /// Whether each thoracic triangle has a corner that moves.
    pub thorax_moving: Vec<bool>,
    /// Closed thoracic surface (anchor indices): lining then reversed dome.
    pub thorax_triangles: Vec<[u32; 3]>,
    /// Number of lining triangles at the start of `thorax_triangles`.
    pub lining_count: usize,
    /// For each thoracic triangle after the lining, the abdominal triangle [a, b, c] of
    /// which it is the reversal [a, c, b] (the dome seen from the thorax); its face vector and
    /// volume term are then exactly the negated abdominal ones and are not recomputed. Empty
    /// when the thoracic surface is not laid out that way.
    pub thorax_dome_source: Vec<u32>,
    /// Rest volume of the abdomen [m^3].
    pub abdomen_rest_volume: f64,
    /// Rest volume of the thorax [m^3].
    pub thorax_rest_volume: f64,
    /// Volume [m^3] the faceted dome falls short of the smooth dome it samples
    /// ([`crate::anatomy::abdomen::Abdomen::dome_faceting_volume`]): taken from the observed
    /// thorax and added to the observed abdomen, never used by the dynamics.
    pub dome_faceting_volume: f64,
    /// Pressure-volume law of the lungs: the pleural pressure is `-pleural.recoil(V_thorax)`
    /// (linear about rest with slope `params.lung_elastance`, bounded by the subject's
    /// residual volume and total lung capacity). Since the lung volume is the thoracic
    /// volume less the constant [`Structure::non_lung_volume`], the law is the lungs' own,
    /// expressed on the thoracic mesh: its slope is the lung elastance per litre of lung, and
    /// its asymptotes sit where the lungs reach the subject's RV and TLC.
    pub pleural: PleuralLaw,
    /// Rest lung volume as a fraction of the observed thoracic cavity's rest volume
    /// ([`REST_LUNG_FRACTION`] unless set by [`Structure::set_lung_fraction`]).
    pub lung_fraction: f64,
    /// Intrathoracic volume that is not lung [m^3]: heart, great vessels and the rest of the
    /// mediastinum, `(1 - lung_fraction)` x the observed thorax at rest, constant over a
    /// breath, so that a change of thoracic volume is the same change of lung volume.
    pub non_lung_volume: f64,
    /// The subject's RV/FRC and TLC/FRC ([`capacity_ratios`]), where the lungs meet the
    /// pleural law's asymptotes relative to their rest volume.
    pub capacity: (f64, f64),
    /// Gravity vector [m/s^2].
    pub gravity: Vector3<f64>,
    /// Gravity acting on the free vertices' lumped masses [m/s^2]: [`Structure::gravity`]
    /// when the abdominal contents are lumped on them ([`GravityLoads::Preloaded`]), zero when
    /// the contents' weight acts through their hydrostatic pressure instead.
    pub vertex_gravity: Vector3<f64>,
    /// Density of the abdominal contents whose hydrostatic pressure rho g . (x - x_c) acts on
    /// the abdominal surface [kg/m^3] ([`super::params::ABDOMINAL_CONTENTS_DENSITY`] under
    /// [`GravityLoads::Acting`], 0 otherwise).
    pub contents_density: f64,
    /// The reference point x_c of the hydrostatic pressure: the abdominal cavity's centroid
    /// at rest, so that the pressure's mean over the contents is zero at rest and the
    /// cavity's mean pressure stays the bulk modulus's.
    pub contents_centre: Point3<f64>,
    /// Anchor at the middle of the sternum (for its displacement).
    pub sternum_probe: u32,
    /// Airway resistance [Pa s/m^3] between the alveoli and the mouth: the pleural pressure
    /// carries -R dV/dt of the thoracic volume's rate (1 / (sGaw FRC),
    /// [`Params::specific_airway_conductance`]).
    pub airway_resistance: f64,
    /// Viscosity of the abdomen's volume [Pa s/m^3]: the abdominal pressure carries
    /// -mu dV/dt (stiffness-proportional damping of its bulk modulus).
    pub abdomen_viscosity: f64,
}

/// Centroid of the volume enclosed by triangles over points (the tetrahedra from the origin
/// to each triangle, weighted by their signed volumes).
pub fn centroid(points: &[Point3<f64>], tris: &[[u32; 3]]) -> Point3<f64> {
    let (mut v, mut m) = (0.0, Vector3::zeros());
    for t in tris {
        let (a, b, c) = (
            points[t[0] as usize].coords,
            points[t[1] as usize].coords,
            points[t[2] as usize].coords,
        );
        let vol = a.dot(&b.cross(&c)) / 6.0;
        v += vol;
        m += (a + b + c) * (vol / 4.0);
    }
    Point3::from(m / v)
}

/// Signed volume enclosed by triangles over points (divergence theorem).
pub fn volume(points: &[Point3<f64>], tris: &[[u32; 3]]) -> f64 {
    tris.iter()
        .map(|t| {
            // Indexed rather than `t.map(..)`, which the optimiser leaves as a call here.
            let (a, b, c) = (
                &points[t[0] as usize].coords,
                &points[t[1] as usize].coords,
                &points[t[2] as usize].coords,
            );
            a.dot(&b.cross(c))
        })
        .sum::<f64>()
        / 6.0
}

impl Structure {
    /// Compiles the structure of `anatomy` with constants `params`.
    pub fn compile(anatomy: &Anatomy, params: Params) -> Structure {
        let posture = anatomy.subject.posture;
        let g = Params::gravity_direction(posture);
        let gravity = Vector3::new(g[0], g[1], g[2]) * params.gravity;
        let n_anchor = anatomy.anchors.len();
        let rest: Vec<Point3<f64>> = anatomy.anchors.iter().map(|a| a.rest).collect();
        let carrier: Vec<Carrier> = anatomy
            .anchors
            .iter()
            .map(|a| match a.body {
                Body::Ground => Carrier::Ground,
                Body::Rib(i) => Carrier::Rib(i as u16),
                Body::Sternum => Carrier::Sternum,
                Body::Vertex(j) => Carrier::Vertex(j),
            })
            .collect();
        let mut rib_anchors = vec![Vec::new(); RIBS];
        let mut sternum_anchors = Vec::new();
        let n_free = carrier
            .iter()
            .filter(|c| matches!(c, Carrier::Vertex(_)))
            .count();
        let mut vertex_anchor = vec![0u32; n_free];
        for (i, c) in carrier.iter().enumerate() {
            match c {
                Carrier::Rib(r) => rib_anchors[*r as usize].push(i as u32),
                Carrier::Sternum => sternum_anchors.push(i as u32),
                Carrier::Vertex(j) => vertex_anchor[*j as usize] = i as u32,
                Carrier::Ground => {}
            }
        }
        let rib_inertia: Vec<f64> = anatomy
            .ribs
            .iter()
            .map(|r| r.inertia_about_axis())
            .collect();
        let ab = &anatomy.abdomen;
        let mut vertex_mass = vec![0.0; n_free];
        for (v, &anchor) in ab.anchor.iter().enumerate() {
            if let Carrier::Vertex(j) = carrier[anchor as usize] {
                vertex_mass[j as usize] = ab.mass[v];
            }
        }
        let sternum_mass = anatomy.sternum.mass;
        // Stiffness-proportional damping c = beta k (Rayleigh), beta = 2 zeta / omega_i: the
        // inertial modes near the inertia frequency are damped with the ratio zeta, every
        // element relaxes with the same time constant beta (6 ms for zeta = 1 at 25 Hz).
        let rayleigh =
            2.0 * params.damping_ratio / (2.0 * std::f64::consts::PI * params.inertia_frequency);
        let path_length = |path: &[u32]| path_length(&rest, path);

        // Muscles: c = F_max / (beta_max l0 s) so that a full isometric contraction gives F_max.
        let mut elements = Elements::default();
        for m in &anatomy.muscles {
            let l0 = path_length(&m.path).max(1e-4);
            let beta = params.beta_for(m.group);
            // The tissue's length l0 s (s: its rest length over the path's, the smooth dome's
            // arcs over the chords for the diaphragm) sets its contraction beta a l0 s and its
            // stiffness F_max / (beta l0 s); the path's chords l0 carry them, so a full
            // isometric contraction still gives F_max.
            let s = m.tissue_length.map_or(1.0, |t| t / l0);
            let k = m.max_force / (beta * l0 * s);
            let side = match m.side {
                Some(Side::Right) => 0,
                Some(Side::Left) => 1,
                None => 2,
            };
            let c = rayleigh * k;
            elements.push(
                &m.path,
                l0,
                k,
                c,
                m.group.index() as u8,
                side,
                beta * m.gain * s,
            );
            if params.muscle_law == MuscleLaw::Hill {
                hill_element(&mut elements, m, l0, posture, rayleigh);
            }
        }
        let muscle_count = elements.len();
        // Membrane: every edge of the abdominal surface with a free end.
        let mut edges = std::collections::BTreeSet::new();
        for t in &ab.triangles {
            for k in 0..3 {
                let (u, v) = (t[k], t[(k + 1) % 3]);
                edges.insert((u.min(v), u.max(v)));
            }
        }
        for (u, v) in edges {
            let (a, b) = (ab.anchor[u as usize], ab.anchor[v as usize]);
            if !matches!(carrier[a as usize], Carrier::Vertex(_))
                && !matches!(carrier[b as usize], Carrier::Vertex(_))
            {
                continue;
            }
            let l0 = (rest[b as usize] - rest[a as usize]).norm();
            let dome = |v: u32| {
                matches!(
                    ab.roles[v as usize],
                    VertexRole::Dome | VertexRole::Insertion
                )
            };
            let tendon = |v: u32| ab.sphere[v as usize].y > crate::anatomy::CENTRAL_TENDON;
            let k = if tendon(u) && tendon(v) {
                params.tendon_stiffness
            } else if dome(u) && dome(v) {
                params.dome_membrane_stiffness
            } else {
                params.membrane_stiffness
            };
            elements.push(&[a, b], l0, k, rayleigh * k, PASSIVE, 2, 0.0);
            let tension_only = (dome(u) && dome(v)) || params.abdominal_wall_tension_only;
            if let (true, Some(slot)) = (tension_only, elements.slot.last_mut()) {
                *slot = PASSIVE_SLACK;
            }
        }
        // Cartilage joints.
        let mut springs = VectorSprings::default();
        for j in &anatomy.joints {
            // the first rib's cartilage meets the manubrium in a synchondrosis
            // (`Params::first_cartilage_stiffness`)
            let k = if j.level == 1 && params.first_cartilage_stiffness > 0.0 {
                params.first_cartilage_stiffness
            } else {
                params.cartilage_stiffness
            };
            springs.horizontal.push(false);
            springs.a.push(j.a);
            springs.b.push(j.b);
            springs.stiffness.push(k);
            springs.damping.push(rayleigh * k);
            springs.normal.push(Vector3::zeros());
            springs.unloading.push(0.0);
        }
        // Wall foundation: each free wall vertex tied to its rest position with stiffness
        // kappa A_v, kappa = A_wall / C_wall, so a uniform pressure P displaces the wall by
        // P / kappa and its volume by P C_wall.
        let mut vertex_area = vec![0.0; ab.len()];
        let mut vertex_normal = vec![Vector3::zeros(); ab.len()];
        for t in &ab.triangles {
            let [p, q, r] = t.map(|v| rest[ab.anchor[v as usize] as usize]);
            let face = (q - p).cross(&(r - p));
            let a = 0.5 * face.norm();
            for v in t {
                vertex_area[*v as usize] += a / 3.0;
                vertex_normal[*v as usize] += face;
            }
        }
        let wall: Vec<usize> = (0..ab.len())
            .filter(|&v| ab.roles[v] == VertexRole::Wall)
            .collect();
        let wall_area: f64 = wall.iter().map(|&v| vertex_area[v]).sum();
        let kappa = wall_area / params.abdominal_wall_compliance;

        // the wall's tissue resistance R_w, spread like its compliance: a uniform pressure
        // P = R_w dV/dt moves the wall at P / (R_w A_wall), so each vertex's damper is
        // R_w A_wall A_v (`Params::abdominal_wall_resistance`)
        let eta = params.abdominal_wall_resistance * wall_area;
        let mut ground_anchors = Vec::new();
        let mut wall_normal = Vec::new();
        for &v in &wall {
            let a = ab.anchor[v];
            let k = kappa * vertex_area[v];
            let c = rayleigh * k + eta * vertex_area[v];
            ground_anchors.push((a, rest[a as usize], k, c, false));
            wall_normal.push(vertex_normal[v].try_normalize(1e-12).unwrap_or_default());
        }
        // Dome support: the dome slides within the rib cage (zone of apposition) and under the
        // lungs; its horizontal motion is held by a foundation of stiffness kappa_h per area.
        for v in (0..ab.len()).filter(|&v| ab.roles[v] == VertexRole::Dome) {
            let a = ab.anchor[v];
            let k = params.dome_support * vertex_area[v];
            ground_anchors.push((a, rest[a as usize], k, rayleigh * k, true));
        }
        let mut rest = rest;
        let mut carrier = carrier;
        // The wall's unloading lengths: the load each wall vertex carries at rest, the
        // contents' pressure at the lowest wall vertex less their hydrostatic fall above it,
        // over the foundation's stiffness per area (`Params::abdominal_wall_unloading`). The
        // rest's gravity: under gravity acting the standing reference's, standard gravity
        // whatever the run's (`model::reference_loads`); preloaded, the run's own (at gravity
        // 0 the wall carries no load and its foundation stays linear).
        let mut unloading = vec![0.0; wall.len()];
        let rest_gravity = match params.gravity_loads {
            GravityLoads::Acting => GRAVITY,
            GravityLoads::Preloaded => params.gravity,
        };
        if params.abdominal_wall_unloading && rest_gravity > 0.0 {
            let down = Vector3::new(g[0], g[1], g[2]) * rest_gravity;
            let height = |v: usize| -down.dot(&rest[ab.anchor[v] as usize].coords);
            let low = wall
                .iter()
                .map(|&v| height(v))
                .fold(f64::INFINITY, f64::min);
            let bottom = wall_load_at_lowest(posture, rest_gravity);
            for (l, &v) in unloading.iter_mut().zip(&wall) {
                // `height` carries |g|: rho |g| h
                let load = bottom - ABDOMINAL_CONTENTS_DENSITY * (height(v) - low);
                *l = load.max(WALL_LOAD_FLOOR) / kappa;
            }
        }
        for (i, (a, p, k, c, horizontal)) in ground_anchors.into_iter().enumerate() {
            springs
                .normal
                .push(wall_normal.get(i).copied().unwrap_or_default());
            springs
                .unloading
                .push(unloading.get(i).copied().unwrap_or(0.0));
            springs.horizontal.push(horizontal);
            rest.push(p);
            carrier.push(Carrier::Ground);
            let g_idx = (rest.len() - 1) as u32;
            springs.a.push(a);
            springs.b.push(g_idx);
            springs.stiffness.push(k);
            springs.damping.push(c);
        }
        debug_assert!(rest.len() >= n_anchor);
        // Nodal damping: light tissue viscosity on free vertices (thesis eq. 2.1, gamma_i =
        // 2 m_i per second with the true masses).
        let vertex_damping: Vec<f64> = vertex_mass.iter().map(|m| 2.0 * m).collect();

        let abdomen_triangles: Vec<[u32; 3]> = ab.anchor_triangles().collect();
        let thorax_triangles = anatomy.thorax_triangles();
        let abdomen_rest_volume = volume(&rest, &abdomen_triangles);
        let contents_centre = centroid(&rest, &abdomen_triangles);
        let acting = params.gravity_loads == GravityLoads::Acting;
        let contents_density = if acting {
            ABDOMINAL_CONTENTS_DENSITY
        } else {
            0.0
        };
        let vertex_gravity = if acting { Vector3::zeros() } else { gravity };
        let thorax_rest_volume = volume(&rest, &thorax_triangles);
        let d = ab.dome_faceting_volume;
        let capacity = capacity_ratios(&anatomy.subject);
        let (pleural, non_lung_volume) =
            pleural_law(capacity, &params, thorax_rest_volume, d, REST_LUNG_FRACTION);
        let st = &anatomy.sternum;
        let sternum_com = st.centre_of_mass();
        rest.push(nalgebra::center(&st.angle, &st.xiphisternal));
        carrier.push(Carrier::Sternum);
        let sternum_probe = (rest.len() - 1) as u32;
        sternum_anchors.push(sternum_probe);

        let ribs = &anatomy.ribs;
        let rib_arm = rib_anchors
            .iter()
            .zip(ribs)
            .map(|(list, rib)| list.iter().map(|&a| rest[a as usize] - rib.head).collect())
            .collect();
        let sternum_arm = sternum_anchors
            .iter()
            .map(|&a| rest[a as usize] - sternum_com)
            .collect();
        let moving = |tris: &[[u32; 3]]| -> Vec<bool> {
            tris.iter()
                .map(|t| t.iter().any(|&a| carrier[a as usize] != Carrier::Ground))
                .collect()
        };
        let abdomen_moving = moving(&abdomen_triangles);
        let lining_count = anatomy.lining_triangles.len();
        let thorax_dome_source: Vec<u32> = (0..abdomen_triangles.len() as u32)
            .filter(|&i| ab.dome.get(i as usize).copied().unwrap_or(false))
            .collect();
        let mirrored = lining_count + thorax_dome_source.len() == thorax_triangles.len()
            && thorax_dome_source
                .iter()
                .zip(&thorax_triangles[lining_count.min(thorax_triangles.len())..])
                .all(|(&i, t)| {
                    let [a, b, c] = abdomen_triangles[i as usize];
                    *t == [a, c, b]
                });
        let thorax_dome_source = if mirrored {
            thorax_dome_source
        } else {
            Vec::new()
        };
        let thorax_moving = moving(&thorax_triangles);
        // the abdomen's volume mode is damped like every other stiffness: beta dP/dV
        let abdomen_viscosity = rayleigh * params.bulk_modulus / abdomen_rest_volume;
        Structure {
            carrier,
            rest,
            rib_anchors,
            sternum_anchors,
            vertex_anchor,
            rib_arm,
            sternum_arm,
            rib_head: ribs.iter().map(|r| r.head).collect(),
            rib_axis: ribs.iter().map(|r| r.axis.into_inner()).collect(),
            rib_mass: ribs.iter().map(|r| r.mass()).collect(),
            rib_com: ribs.iter().map(|r| r.centre_of_mass()).collect(),
            rib_stiffness: vec![params.rib_joint_stiffness; RIBS],
            rib_damping: vec![rayleigh * params.rib_joint_stiffness; RIBS],
            rib_inertia,
            sternum_mass,
            sternum_inertia: st.inertia(),
            sternum_com,
            vertex_mass,
            vertex_damping,
            elements,
            muscle_count,
            springs,
            abdomen_triangles,
            abdomen_dome: ab.dome.clone(),
            abdomen_moving,
            thorax_moving,
            lining_count,
            thorax_dome_source,
            thorax_triangles,
            abdomen_rest_volume,
            thorax_rest_volume,
            dome_faceting_volume: ab.dome_faceting_volume,
            pleural,
            lung_fraction: REST_LUNG_FRACTION,
            non_lung_volume,
            capacity,
            gravity,
            vertex_gravity,
            contents_density,
            contents_centre,
            sternum_probe,
            airway_resistance: 1.0
                / (params.specific_airway_conductance * anatomy.subject.frc_ecsc() * 1e-3),
            abdomen_viscosity,
            params,
        }
    }

    /// Turns gravity to `posture`'s direction (its magnitude stays `params.gravity`): under
    /// [`GravityLoads::Acting`] every posture is the standing anatomy with gravity turned.
    pub fn turn_gravity(&mut self, posture: crate::anatomy::Posture) {
        let g = Params::gravity_direction(posture);
        self.gravity = Vector3::new(g[0], g[1], g[2]) * self.params.gravity;
        if self.params.gravity_loads == GravityLoads::Preloaded {
            self.vertex_gravity = self.gravity;
        }
    }

    /// Number of free abdominal vertices.
    pub fn free_vertices(&self) -> usize {
        self.vertex_anchor.len()
    }

    /// Sets the rest split of the thoracic cavity: the lungs fill `fraction` of it at rest
    /// and the non-lung volume (heart, great vessels, mediastinum) the rest, constant over a
    /// breath. The pleural law's asymptotes follow (the lungs meet the subject's RV and TLC, [`Structure::capacity`]);
    /// its slope, the lung elastance, does not depend on the split.
    pub fn set_lung_fraction(&mut self, fraction: f64) {
        let (pleural, non_lung) = pleural_law(
            self.capacity,
            &self.params,
            self.thorax_rest_volume,
            self.dome_faceting_volume,
            fraction,
        );
        self.pleural = pleural;
        self.non_lung_volume = non_lung;
        self.lung_fraction = fraction;
    }

    /// A fingerprint of the compiled model (FNV-1a over its defining numbers: rest positions,
    /// element, spring and joint stiffnesses, bulk modulus, lung elastance, rest volumes, the
    /// pleural law's asymptotes, barrier pressure and margin, gravity, under the
    /// passive-and-active muscle law its muscles' forces and lengths, the abdominal tone, the
    /// expiratory rib-cage drive, the abdominal wall's tension-only edges and its unloading
    /// lengths),
    /// so that a snapshot is only restored into the model it was taken from.
    pub fn fingerprint(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |x: f64| {
            for b in x.to_le_bytes() {
                h ^= b as u64;
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        for p in &self.rest {
            eat(p.x);
            eat(p.y);
            eat(p.z);
        }
        for k in &self.elements.stiffness {
            eat(*k);
        }
        for k in self.springs.stiffness.iter().chain(&self.rib_stiffness) {
            eat(*k);
        }
        eat(self.params.bulk_modulus);
        eat(self.params.lung_elastance);
        eat(self.abdomen_rest_volume);
        eat(self.thorax_rest_volume);
        eat(self.dome_faceting_volume);
        eat(self.pleural.lower);
        eat(self.pleural.upper);
        eat(self.params.pleural_barrier_pressure);
        eat(self.params.pleural_barrier_margin);
        eat(self.gravity.x);
        eat(self.gravity.y);
        // Gravity acting (the contents' hydrostatic pressure, the reference preloads) changes
        // the loads but not the fields above; a preloaded model's fingerprint is the one it
        // had before the choice existed.
        if self.params.gravity_loads == GravityLoads::Acting {
            eat(self.gravity.z);
            eat(self.contents_density);
            eat(1.0);
        }
        // The muscle law changes the forces but not the fields above; a thesis-law model's
        // fingerprint is the one it had before the law became a parameter.
        if self.params.muscle_law == MuscleLaw::Hill {
            for e in 0..self.elements.max_force.len() {
                eat(self.elements.max_force[e]);
                eat(self.elements.optimal_length[e]);
                eat(self.elements.slack_length[e]);
                eat(self.elements.drive[e]);
            }
        }
        // The abdominal wall's tone changes the applied activations; a model without it keeps
        // the fingerprint it had before the tone existed.
        if self.params.abdominal_tone != 0.0 {
            eat(self.params.abdominal_tone);
        }
        // So does the posture's expiratory rib-cage drive; a model without it keeps its
        // fingerprint too.
        if self.params.expiration_with_abdominals {
            eat(1.0);
        }
        // So do the abdominal wall's tension-only edges (the slots, not the fields above).
        if self.params.abdominal_wall_tension_only {
            eat(2.0);
        }
        // And the wall's unloading lengths.
        if self.params.abdominal_wall_unloading {
            for l in &self.springs.unloading {
                eat(*l);
            }
        }
        h
    }

    /// Group index of muscle element `e`.
    pub fn element_group(&self, e: usize) -> Option<MuscleGroup> {
        MuscleGroup::ALL
            .get(self.elements.group[e] as usize)
            .copied()
    }
}

/// The pleural law on the thoracic mesh and the non-lung volume, for a thorax whose mesh rest
/// volume is `mesh_rest` and whose faceted dome falls short of the smooth one by `faceting`
/// (the observed thorax is the mesh's less it), with lungs filling `fraction` of the observed
/// thorax at rest. The lungs' rest volume L0 is the model's functional residual capacity; the
/// subject's RV/FRC and TLC/FRC (`rv`, `tlc`: [`capacity_ratios`]) place the asymptotes at r L0 of lung,
/// that is at d + V_nl + r L0 on the mesh.
fn pleural_law(
    (rv, tlc): (f64, f64),
    params: &Params,
    mesh_rest: f64,
    faceting: f64,
    fraction: f64,
) -> (PleuralLaw, f64) {
    let observed = mesh_rest - faceting;
    let lung_rest = fraction * observed;
    let non_lung = observed - lung_rest;
    let on_mesh = |r: f64| (faceting + non_lung + r * lung_rest) / mesh_rest;
    let law = PleuralLaw::new(
        mesh_rest,
        params.lung_elastance,
        (on_mesh(rv), on_mesh(tlc)),
        params.pleural_barrier_pressure,
        params.pleural_barrier_margin,
    );
    (law, non_lung)
}

#[cfg(test)]
mod tests {
    use super::{PATH_CORE, path_length, via_segment_length};
    use nalgebra::{Point3, Vector3};

    /// Two-point elements keep their plain length; a path with via points counts each segment
    /// with the band's core, so a via point sitting on its neighbour still has a length, and
    /// the direction d / s that the force uses is the gradient of that length (central
    /// differences).
    #[test]
    fn via_paths_have_a_core_and_a_smooth_length() {
        let pos = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.05, 0.0, 0.0),
            Point3::new(0.08, 0.0, 0.0),
        ];
        assert_eq!(path_length(&pos, &[2, 3]), 0.03);
        let l = path_length(&pos, &[0, 1, 2]);
        let expected = PATH_CORE + (0.05f64 * 0.05 + PATH_CORE * PATH_CORE).sqrt();
        assert!((l - expected).abs() < 1e-15, "{l} vs {expected}");
        for d in [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1e-4, -2e-3, 5e-4),
            Vector3::new(0.03, 0.01, -0.02),
        ] {
            let s = via_segment_length(&d);
            let h = 1e-7;
            for k in 0..3 {
                let mut e = Vector3::zeros();
                e[k] = h;
                let numeric =
                    (via_segment_length(&(d + e)) - via_segment_length(&(d - e))) / (2.0 * h);
                assert!((numeric - d[k] / s).abs() < 1e-6, "{d:?}, axis {k}");
            }
        }
    }
}
