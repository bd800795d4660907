//! Muscle groups and their element layouts.

use serde::{Deserialize, Serialize};

/// The eight respiratory muscle groups of the model (thesis chapter 2).
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
}

impl MuscleGroup {
    /// All groups, in FMI input order.
    pub const ALL: [MuscleGroup; 8] = [
        MuscleGroup::Diaphragm,
        MuscleGroup::ExternalIntercostals,
        MuscleGroup::InternalIntercostals,
        MuscleGroup::Scalenes,
        MuscleGroup::TransversusAbdominis,
        MuscleGroup::RectusAbdominis,
        MuscleGroup::ExternalObliques,
        MuscleGroup::InternalObliques,
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
        }
    }

    /// Parses [`MuscleGroup::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|g| g.name() == name)
    }

    /// The thesis's default element count for this group (thesis 2.2-2.3).
    pub fn default_count(self) -> usize {
        match self {
            MuscleGroup::Diaphragm => 500,
            MuscleGroup::ExternalIntercostals | MuscleGroup::InternalIntercostals => 250,
            MuscleGroup::Scalenes => 12,
            MuscleGroup::TransversusAbdominis => 100,
            MuscleGroup::RectusAbdominis => 50,
            MuscleGroup::ExternalObliques | MuscleGroup::InternalObliques => 60,
        }
    }
}
