//! The compiled model: everything that never changes during a run, built once from an
//! [`Anatomy`] and shared between instances (`Arc`), as MuJoCo splits `mjModel` from `mjData`.
//!
//! It is compiled in one pass of three phases, each reading only what the previous ones made:
//!
//! 1. the [`Structure`] (`structure.rs`): geometry, carriers, elements, springs, cavity
//!    triangles, true masses, rest volumes, the pleural law;
//! 2. from the structure alone, the mass matrix the dynamics integrates with
//!    ([`MassMatrix::new`], `inertia.rs`) and the preloads that hold the rest pose
//!    ([`Preload::at_rest`], the force pass of `kinematics.rs`, `forces.rs` and
//!    `accelerations.rs` run on the structure at rest); under [`GravityLoads::Acting`] the
//!    tissues' rest lengths are first shortened to carry what they can of the reference's
//!    loads ([`pretension::carry`]), and the preloads hold the rest;
//! 3. the [`Model`], assembled once from the three and the state's [`Layout`].
//!
//! A [`Model`] dereferences to its [`Structure`], so `model.elements` or `model.rest` read the
//! structure's fields; it cannot be changed through that, since the mass matrix and the
//! preloads are derived from it. To compile a changed structure, change a [`Structure`] and
//! pass it to [`Model::new`].

use super::accelerations::Preload;
use super::inertia::MassMatrix;
use super::params::{GRAVITY, GravityLoads, Params};
use super::pretension;
use super::state::Layout;
use super::structure::Structure;
use crate::anatomy::Anatomy;
use std::ops::Deref;

/// The reference whose rest tensions the tissues keep under [`GravityLoads::Acting`]: the
/// structure's own anatomy (the generated standing one) standing under standard gravity
/// ([`GRAVITY`]), its abdominal contents' hydrostatic pressure included. Its loads are
/// carried there by tension in the tissues as far as they can be ([`pretension::carry`]
/// shortens their rest lengths) and the rest by preloads that make it an equilibrium; every
/// other posture and gravity only changes the loads, and its rest is the equilibrium under
/// them.
fn reference_loads(structure: &Structure) -> Structure {
    let mut reference = structure.clone();
    let g = Params::gravity_direction(crate::anatomy::Posture::Standing);
    reference.gravity = nalgebra::Vector3::new(g[0], g[1], g[2]) * GRAVITY;
    reference
}

/// The compiled model (module doc): the structure, the state's layout, the mass matrix and
/// the preloads.
#[derive(Clone, Debug)]
pub struct Model {
    /// What the anatomy compiles to (read through `Deref`; private, so that the mass matrix
    /// and the preloads always are those of the structure).
    structure: Structure,
    /// Offsets into the state vector.
    pub layout: Layout,
    /// The mass matrix the dynamics integrates with: the true masses plus the selective
    /// mass scaling of [`super::inertia`].
    pub mass: MassMatrix,
    /// The constant generalised loads that make the rest pose an equilibrium.
    pub preload: Preload,
    /// Under [`GravityLoads::Acting`], the tensions the tissues took over from the
    /// preloads at the reference ([`pretension::carry`]); `None` otherwise.
    pub carried: Option<pretension::Carried>,
}

impl Deref for Model {
    type Target = Structure;
    fn deref(&self) -> &Structure {
        &self.structure
    }
}

impl Model {
    /// Compiles `anatomy` with constants `params`.
    pub fn compile(anatomy: &Anatomy, params: Params) -> Model {
        Model::new(Structure::compile(anatomy, params))
    }

    /// The model of `structure`: its mass matrix (scaled unless `params.true_masses`) and its
    /// preloads, derived from it, and its state's layout.
    pub fn new(mut structure: Structure) -> Model {
        let (preload, carried) = match structure.params.gravity_loads {
            GravityLoads::Preloaded => (Preload::at_rest(&structure), None),
            GravityLoads::Acting => {
                let loads = Preload::at_rest(&reference_loads(&structure));
                let carried = pretension::carry(&mut structure, &loads);
                (
                    Preload::at_rest(&reference_loads(&structure)),
                    Some(carried),
                )
            }
        };
        let params = &structure.params;
        let scaling = if params.true_masses {
            f64::INFINITY // nothing added: the true masses
        } else {
            params.inertia_frequency
        };
        let mass = MassMatrix::new(
            &structure,
            scaling,
            [
                params.bulk_modulus / structure.abdomen_rest_volume,
                structure.pleural.slope(structure.thorax_rest_volume),
            ],
            structure.airway_resistance,
        );
        Model {
            layout: Layout::new(&structure),
            structure,
            mass,
            preload,
            carried,
        }
    }

    /// Length of the state vector.
    pub fn state_len(&self) -> usize {
        self.layout.len
    }

    /// Compiles `anatomy` (built standing) with constants `params` under
    /// [`GravityLoads::Acting`], with gravity turned to `posture` ([`Structure::turn_gravity`]).
    pub fn compile_in(
        anatomy: &Anatomy,
        params: Params,
        posture: crate::anatomy::Posture,
    ) -> Model {
        let mut structure = Structure::compile(anatomy, params);
        structure.turn_gravity(posture);
        Model::new(structure)
    }

    /// [`Structure::set_lung_fraction`]. The mass matrix and the preloads stay as compiled
    /// (at the rest split [`REST_LUNG_FRACTION`](super::REST_LUNG_FRACTION)).
    pub fn set_lung_fraction(&mut self, fraction: f64) {
        self.structure.set_lung_fraction(fraction);
    }
}
