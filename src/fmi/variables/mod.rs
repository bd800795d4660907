//! The one table of every FMI variable of the BreathingTorso FMU: name, value reference, type,
//! causality, variability, initial, unit, range, start value, description and the model
//! quantity or configuration field it maps to.
//!
//! Everything else is generated from this table: `modelDescription.xml` (and the FMU's copy),
//! `documentation/index.html`, the value-reference constants of `include/breathing_torso.h`,
//! the range checks of `fmi2SetReal`/`fmi2SetInteger`, and the GUID (a hash of the interface
//! part of the table, so that it changes exactly when the interface changes).
//!
//! Value references are unique across types and grouped: 0 time, 1-8 activation inputs, 9 the
//! airway-opening pressure input, 100-199 Real parameters, 200-299 Integer parameters, 300 the String parameter, 1000-1099
//! Real outputs, 2000-2767 markers (`2000 + 3 (i - 1) + axis`; the generic FMU's 60 use
//! 2000-2179), 3000-3002 Integer outputs.
//!
//! Ranges: the table's min/max are what the FMI layer checks first (and what masters see);
//! [`crate::Config::validate`] stays the final check. A test checks that both agree at every
//! bound.
//!
//! The table's vocabulary is in `types`, what each variable maps to in the model (the
//! parameters' configuration fields, the inputs) in `mapping`, the rows in `rows`, the
//! table of a personalised FMU in `personalise` and the GUID in `guid`; this module
//! holds the value-reference layout and the indexed [`Table`]. Their items are re-exported
//! here, so every path `crate::fmi::variables::<item>` names them.

mod guid;
mod mapping;
mod personalise;
mod rows;
mod types;

pub use guid::fnv1a_128;
pub use mapping::{Family, Input, Parameter, Value, start_config};
pub use personalise::{Personalisation, personalised_table};
pub use rows::marker_label_name;
pub use types::{
    Causality, Initial, LOG_CATEGORIES, PA_PER_CMH2O, Role, SECONDS_PER_YEAR, ScalarType, Start,
    UNITS, Unit, Variability, Variable,
};

use crate::model::Quantity;
use rows::{MarkerOutputs, build};
use std::collections::HashMap;
use std::sync::OnceLock;

/// The FMU's model identifier (name of the shared library and of the `.fmu`).
pub const MODEL_IDENTIFIER: &str = "BreathingTorso";
/// Number of marker outputs of the generic FMU (`marker[1]` .. `marker[60]`): the markers of
/// the default SLP grid, 10 rows x 6 columns (the model's default `grid_rows` x `grid_cols`,
/// the grid of the thesis's SLP recordings). A grid with more markers is refused by the generic
/// FMU; a personalised FMU ([`Table::personalised`]) has its own grid's or marker set's
/// markers, up to [`MAX_MARKER_OUTPUTS`].
pub const MARKER_SLOTS: u16 = 60;
/// Most marker outputs an FMU can have (the largest grid, 16 x 16, and any marker set):
/// value references 2000-2767.
pub const MAX_MARKER_OUTPUTS: u16 = crate::observe::markers::MAX_MARKERS as u16;
/// Value reference of `time`.
pub const VR_TIME: u32 = 0;
/// First value reference of the activation inputs (in [`MuscleGroup::ALL`](crate::anatomy::MuscleGroup::ALL) order):
/// the thesis's eight groups at 1-8 ([`activation_vr`]).
pub const VR_ACTIVATION: u32 = 1;
/// Value reference of the first activation input added after the airway inputs (the
/// sternocleidomastoids' at 11), so that the references of the older inputs stay as they were.
pub const VR_ACTIVATION_ADDED: u32 = 11;
/// Groups whose activation references run from [`VR_ACTIVATION`]; later ones from
/// [`VR_ACTIVATION_ADDED`].
const THESIS_GROUPS: usize = 8;

/// The value reference of `activation.<group>`: [`VR_ACTIVATION`] + index for the thesis's
/// eight groups, [`VR_ACTIVATION_ADDED`] + (index - 8) for the groups added after them.
pub fn activation_vr(group: crate::anatomy::MuscleGroup) -> u32 {
    let k = group.index();
    if k < THESIS_GROUPS {
        VR_ACTIVATION + k as u32
    } else {
        VR_ACTIVATION_ADDED + (k - THESIS_GROUPS) as u32
    }
}
/// Value reference of `pressure.airway_opening`, the input after the activations.
pub const VR_AIRWAY_OPENING: u32 = 9;
/// Value reference of `airway.occluded`, the Boolean input after the airway opening.
pub const VR_AIRWAY_OCCLUDED: u32 = 10;
/// Value reference of `marker[1].x`; `marker[i].<axis>` is `VR_MARKER + 3 (i - 1) + axis`.
pub const VR_MARKER: u32 = 2000;

#[derive(Debug)]
pub struct Table {
    variables: Vec<Variable>,
    /// Position in `variables` of each value reference, indexed by the reference itself
    /// (`u32::MAX`: none). The references are a few thousand at most, and `fmi2GetReal` of
    /// the 60 markers looks up 184 of them per communication step: a direct index costs a
    /// load where a hash map's lookup cost some 40 ns.
    by_vr: Vec<u32>,
    by_name: HashMap<String, usize>,
    guid: String,
    personalisation: Option<Personalisation>,
}

impl Table {
    /// All variables, in `<ModelVariables>` order.
    pub fn variables(&self) -> &[Variable] {
        &self.variables
    }

    /// The variable with value reference `vr`.
    pub fn by_vr(&self, vr: u32) -> Option<&Variable> {
        self.position(vr).map(|i| &self.variables[i])
    }

    fn position(&self, vr: u32) -> Option<usize> {
        match self.by_vr.get(vr as usize) {
            Some(&i) if i != u32::MAX => Some(i as usize),
            _ => None,
        }
    }

    /// The variable called `name`.
    pub fn by_name(&self, name: &str) -> Option<&Variable> {
        self.by_name.get(name).map(|&i| &self.variables[i])
    }

    /// 1-based index of a variable in `<ModelVariables>`.
    pub fn index_of(&self, vr: u32) -> Option<usize> {
        self.position(vr).map(|i| i + 1)
    }

    /// The GUID: `{...}` formatted 128-bit FNV-1a hash of the interface.
    pub fn guid(&self) -> &str {
        &self.guid
    }
}

impl Table {
    /// Indexes `variables`; the GUID hashes their interface and `extra` (empty for the
    /// generic table).
    fn indexed(
        variables: Vec<Variable>,
        extra: &str,
        personalisation: Option<Personalisation>,
    ) -> Table {
        let size = variables
            .iter()
            .map(|v| v.vr as usize + 1)
            .max()
            .unwrap_or(0);
        let mut by_vr = vec![u32::MAX; size];
        for (i, v) in variables.iter().enumerate() {
            by_vr[v.vr as usize] = i as u32;
        }
        let by_name = variables
            .iter()
            .enumerate()
            .map(|(i, v)| (v.name.clone(), i))
            .collect();
        let text = guid::interface_text(&variables) + extra;
        let guid = guid::format_guid(fnv1a_128(text.as_bytes()));
        Table {
            variables,
            by_vr,
            by_name,
            guid,
            personalisation,
        }
    }

    /// Number of marker outputs (`marker[i]` or `marker.<label>`, three scalars each).
    pub fn marker_outputs(&self) -> usize {
        self.variables
            .iter()
            .filter(|v| matches!(v.role, Role::Output(Quantity::Marker { axis: 0, .. })))
            .count()
    }
}

/// The table (built once; immutable and shared by every instance and thread).
pub fn table() -> &'static Table {
    static TABLE: OnceLock<Table> = OnceLock::new();
    TABLE.get_or_init(|| Table::indexed(build(&MarkerOutputs::Grid(MARKER_SLOTS)), "", None))
}

/// Value reference of `marker[index + 1].<axis>` (index 0-based, axis 0 = x, 1 = y, 2 = z).
pub fn marker_vr(index: u16, axis: u8) -> u32 {
    VR_MARKER + 3 * u32::from(index) + u32::from(axis)
}
