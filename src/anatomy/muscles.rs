//! Muscle groups and their element layouts.

use serde::{Deserialize, Serialize};

/// The respiratory muscle groups of the model: the thesis's eight (thesis chapter 2) and the
/// sternocleidomastoids, the accessory inspiratory muscles of maximal efforts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
pub enum MuscleGroup {
    /// The diaphragm: 500 elements from the dome to insertions on ribs 7-12.
    Diaphragm,
    /// External intercostals: 250 elements, inspiratory, strongest dorsally.
    ExternalIntercostals,
    /// Internal intercostals: 250 elements, expiratory, strongest ventrally.
    InternalIntercostals,
    /// Scalenes: 12 elements from C6 to rib 1.
    Scalenes,
    /// Transversus abdominis: 100 elements.
    TransversusAbdominis,
    /// Rectus abdominis: 50 elements.
    RectusAbdominis,
    /// External obliques: 60 elements.
    ExternalObliques,
    /// Internal obliques: 60 elements.
    InternalObliques,
    /// Sternocleidomastoids: 4 elements, a sternal and a clavicular head per side, from the
    /// mastoid process to the manubrium and the sternal end of rib 1. Accessory inspiratory
    /// muscles: silent in quiet breathing, recruited in maximal inspiratory efforts (Raper et
    /// al. 1966); no drive moves them, only their activation input.
    Sternocleidomastoids,
}

impl MuscleGroup {
    /// Number of groups.
    pub const COUNT: usize = 9;

    /// All groups, in FMI input order (the sternocleidomastoids, added after the thesis's
    /// eight, last, so that the others' indices stay as they were).
    pub const ALL: [MuscleGroup; MuscleGroup::COUNT] = [
        MuscleGroup::Diaphragm,
        MuscleGroup::ExternalIntercostals,
        MuscleGroup::InternalIntercostals,
        MuscleGroup::Scalenes,
        MuscleGroup::TransversusAbdominis,
        MuscleGroup::RectusAbdominis,
        MuscleGroup::ExternalObliques,
        MuscleGroup::InternalObliques,
        MuscleGroup::Sternocleidomastoids,
    ];

    /// Index of the group in [`MuscleGroup::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// Snake-case name used in FMI variable names (`activation.<name>`) and on the CLI.
    pub fn name(self) -> &'static str {
        match self {
            MuscleGroup::Diaphragm => "diaphragm",
            MuscleGroup::ExternalIntercostals => "external_intercostals",
            MuscleGroup::InternalIntercostals => "internal_intercostals",
            MuscleGroup::Scalenes => "scalenes",
            MuscleGroup::TransversusAbdominis => "transversus_abdominis",
            MuscleGroup::RectusAbdominis => "rectus_abdominis",
            MuscleGroup::ExternalObliques => "external_obliques",
            MuscleGroup::InternalObliques => "internal_obliques",
            MuscleGroup::Sternocleidomastoids => "sternocleidomastoids",
        }
    }

    /// Parses [`MuscleGroup::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|g| g.name() == name)
    }

    /// The default element count for this group at full detail (thesis 2.2-2.3; the
    /// sternocleidomastoids, which the thesis does not model, have one element per head).
    pub fn default_count(self) -> usize {
        match self {
            MuscleGroup::Diaphragm => 500,
            MuscleGroup::ExternalIntercostals | MuscleGroup::InternalIntercostals => 250,
            MuscleGroup::Scalenes => 12,
            MuscleGroup::TransversusAbdominis => 100,
            MuscleGroup::RectusAbdominis => 50,
            MuscleGroup::ExternalObliques | MuscleGroup::InternalObliques => 60,
            MuscleGroup::Sternocleidomastoids => 4,
        }
    }
}
