//! The quantities that can be read off a [`super::Torso`].

use serde::{Deserialize, Serialize};

/// A readable quantity. Volumes in litres, pressure in pascal, lengths in metres.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Quantity {
    /// Simulated time [s].
    Time,
    /// Lung volume = thoracic volume - the non-lung volume (heart, great vessels,
    /// mediastinum: `lung.ratio` sets the rest split, thesis 4.2), constant over a breath [L].
    LungVolume,
    /// Thoracic cavity volume = trunk - abdomen [L].
    ThoraxVolume,
    /// Abdominal cavity volume [L].
    AbdomenVolume,
    /// Trunk cavity volume (rib-cage lining plus abdominal wall) [L].
    TrunkVolume,
    /// Volume displaced by the trunk wall above the horizontal plane through the lowest point
    /// of the costal margin (the rib cage of optoelectronic plethysmography) since the start
    /// [L].
    RibCageDisplaced,
    /// Volume displaced by the trunk wall below that plane (the abdomen of optoelectronic
    /// plethysmography) since the start [L].
    AbdomenDisplaced,
    /// Abdominal pressure above rest [Pa] (thesis eq. 2.5).
    AbdominalPressure,
    /// Cranial displacement of the diaphragm dome since the start [m] (positive cranial).
    DiaphragmDisplacement,
    /// Pleural pressure relative to the body surface [Pa]: the alveolar pressure less the
    /// lungs' elastic recoil (about -5 cmH2O at rest).
    PleuralPressure,
    /// Alveolar pressure relative to the body surface [Pa]: the airway opening's less the
    /// drop across the airway resistance; with the airway occluded, Boyle's law on the
    /// lungs' gas.
    AlveolarPressure,
    /// Pressure at the mouth relative to the body surface [Pa]: the airway opening's with
    /// the airway open, the alveolar pressure behind an occlusion (no gas flows).
    MouthPressure,
    /// Airflow into the lungs through the airway [L/s], positive in inspiration (0 with the
    /// airway occluded).
    AirwayFlow,
    /// One lung's volume [L], side 0 right, 1 left: the right lung's rest share of the lungs
    /// (`observe::RIGHT_LUNG_FRACTION`) plus the change of its side's share of the thorax.
    LungVolumeSide(u8),
    /// Volume displaced by one side's rib-cage wall since the start [L] (0 right, 1 left).
    RibCageDisplacedSide(u8),
    /// Volume displaced by one side's abdominal wall since the start [L] (0 right, 1 left).
    AbdomenDisplacedSide(u8),
    /// Cranial displacement of one hemidiaphragm since the start [m] (0 right, 1 left).
    DiaphragmDisplacementSide(u8),
    /// Sternum displacement since the start along axis 0 = x, 1 = y, 2 = z [m].
    SternumDisplacement(u8),
    /// Marker `index` (0-based, row-major from the top row, column 0 on the subject's right),
    /// coordinate `axis` (0 = x, 1 = y, 2 = z) [m], in the recording's frame when the grid is
    /// registered (`scene.slp_reference`); of a marker set ([`crate::Torso::set_marker_set`])
    /// in the set's order. Indices from the marker count up to 255 (the most markers a grid
    /// or an FMU has) read 0.0.
    Marker {
        /// 0-based marker index.
        index: u16,
        /// 0 = x, 1 = y, 2 = z.
        axis: u8,
    },
    /// Applied activation (input + drive + tone, clamped) of a muscle group, by index in
    /// [`crate::anatomy::MuscleGroup::ALL`].
    Activation(u8),
    /// Accepted integration steps since the start.
    SolverSteps,
    /// Rejected integration steps since the start.
    SolverRejectedSteps,
    /// Right-hand-side evaluations since the start.
    SolverRhsEvaluations,
}
