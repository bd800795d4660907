//! The rows of the variable table: every variable of the FMU, in `<ModelVariables>` order,
//! with its value reference, attributes, range, start value, description and role
//! ([`build`]); the marker outputs of a grid or of a named marker set ([`marker_rows`],
//! named by [`marker_label_name`]); and the compact row builder they are written with.

use super::mapping::{Family, Input, Parameter, Value, start_config};
use super::types::{Causality, Initial, Role, ScalarType, Start, Variability, Variable};
use super::{VR_AIRWAY_OCCLUDED, VR_AIRWAY_OPENING, VR_TIME, activation_vr, marker_vr};
use crate::anatomy::skin::MarkerSet;
use crate::anatomy::{MuscleGroup, SUBJECT_RANGES, Side};
use crate::model::{Config, Quantity};
use crate::solver::Method;
use std::f64::consts::PI;

const AXES: [&str; 3] = ["x", "y", "z"];

/// Which markers a table has as outputs.
#[derive(Clone, Copy, Debug)]
pub(super) enum MarkerOutputs<'a> {
    /// The first `n` markers of the grid, `marker[1]` .. `marker[n]`, row-major.
    Grid(u16),
    /// A named marker set's markers in its order, `marker.<label>`.
    Named(&'a MarkerSet),
}

/// The structured FMI name of a marker set's label: the label itself when it is an FMI
/// identifier (a letter or `_`, then letters, digits and `_`), otherwise quoted (`'...'`, with
/// `\` and `'` escaped), as the structured naming convention's q-names are (FMI 2.0
/// standard, section 2.2.9).
pub fn marker_label_name(label: &str) -> String {
    let plain = label
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && label.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if plain {
        label.to_string()
    } else {
        let escaped = label.replace('\\', "\\\\").replace('\'', "\\'");
        format!("'{escaped}'")
    }
}

/// The marker outputs' rows: `marker[<i>].<axis>` of the grid, `marker.<label>.<axis>` of a
/// named set, value references `2000 + 3 i + axis` (i 0-based) in both cases.
pub(super) fn marker_rows(markers: &MarkerOutputs) -> Vec<Variable> {
    let count = match *markers {
        MarkerOutputs::Grid(n) => n,
        MarkerOutputs::Named(set) => set.len() as u16,
    };
    // (name stem, description) of marker `index`.
    let name = |index: u16| match *markers {
        MarkerOutputs::Grid(_) => (
            format!("marker[{}]", index + 1),
            format!(
                "Marker {} of the grid (row-major from the top row, column 1 on the subject's right; reads 0 when {} > grid.rows x grid.cols)",
                index + 1,
                index + 1
            ),
        ),
        MarkerOutputs::Named(set) => {
            let label = &set.labels[usize::from(index)];
            (
                format!("marker.{}", marker_label_name(label)),
                format!(
                    "Marker `{label}` of the subject's marker set `{}` (bound to the skin at barycentric coordinates of a skin triangle)",
                    set.name
                ),
            )
        }
    };
    let mut rows = Vec::with_capacity(3 * usize::from(count));
    for index in 0..count {
        let (stem, what) = name(index);
        for (axis, a) in AXES.iter().enumerate() {
            let axis = axis as u8;
            let row = Row::new(
                format!("{stem}.{a}"),
                marker_vr(index, axis),
                ScalarType::Real,
                Role::Output(Quantity::Marker { index, axis }),
                format!("{what}, {a} coordinate"),
            )
            .output(Variability::Continuous)
            .unit("m")
            .display("mm");
            rows.push(row.0);
        }
    }
    rows
}

/// A compact builder for table rows.
struct Row(Variable);

impl Row {
    fn new(
        name: impl Into<String>,
        vr: u32,
        ty: ScalarType,
        role: Role,
        description: impl Into<String>,
    ) -> Row {
        Row(Variable {
            name: name.into(),
            vr,
            ty,
            causality: Causality::Output,
            variability: Variability::Continuous,
            initial: None,
            unit: None,
            display_unit: None,
            min: None,
            max: None,
            start: Start::None,
            description: description.into(),
            role,
            input_dependencies: None,
        })
    }
    fn unit(mut self, unit: &'static str) -> Row {
        self.0.unit = Some(unit);
        self
    }
    fn display(mut self, unit: &'static str) -> Row {
        self.0.display_unit = Some(unit);
        self
    }
    fn range(mut self, lo: f64, hi: f64) -> Row {
        self.0.min = Some(lo);
        self.0.max = Some(hi);
        self
    }
    /// The range the anatomy declares for this subject field ([`SUBJECT_RANGES`]).
    fn subject_range(self) -> Row {
        match SUBJECT_RANGES.iter().find(|r| r.0 == self.0.name) {
            Some(&(_, lo, hi)) => self.range(lo, hi),
            None => self,
        }
    }
    fn output(mut self, variability: Variability) -> Row {
        self.0.causality = Causality::Output;
        self.0.variability = variability;
        self.0.initial = Some(Initial::Calculated);
        // Read off the state: no direct feedthrough from any input.
        self.0.input_dependencies = Some(Vec::new());
        self
    }
    /// An output that the inputs `vrs` reach at once, without a step (direct feedthrough).
    fn depends_on(mut self, vrs: &[u32]) -> Row {
        self.0.input_dependencies = Some(vrs.to_vec());
        self
    }
    /// A parameter whose start value is read from the default configuration.
    fn parameter(mut self, defaults: &Config) -> Row {
        let Role::Parameter(p) = self.0.role else {
            unreachable!("parameter rows carry a parameter role")
        };
        self.0.causality = Causality::Parameter;
        self.0.variability = if p.is_tunable() {
            Variability::Tunable
        } else {
            Variability::Fixed
        };
        self.0.initial = Some(Initial::Exact);
        self.0.start = match p.get(defaults) {
            Value::Real(v) => Start::Real(v),
            Value::Integer(v) => Start::Integer(v),
            Value::Boolean(v) => Start::Boolean(v),
            Value::String(v) => Start::String(v),
        };
        self
    }
}

/// Every row of the table, with `markers` as its marker outputs.
pub(super) fn build(markers: &MarkerOutputs) -> Vec<Variable> {
    use Parameter as P;
    use ScalarType::{Boolean, Integer, Real, String as Str};
    let d = start_config();
    let mut rows: Vec<Variable> = Vec::with_capacity(900);

    rows.push(Variable {
        causality: Causality::Independent,
        initial: None,
        ..Row::new("time", VR_TIME, Real, Role::Time, "Simulated time")
            .unit("s")
            .0
    });

    for g in MuscleGroup::ALL {
        let mut r = Row::new(
            format!("activation.{}", g.name()),
            activation_vr(g),
            Real,
            Role::Input(Input::Activation(g)),
            format!(
                "Activation input of the {} (added to the drive, applied clamped to [0, 1])",
                g.name().replace('_', " ")
            ),
        )
        .range(0.0, 1.0)
        .0;
        r.causality = Causality::Input;
        r.start = Start::Real(0.0);
        rows.push(r);
    }
    let (lo, hi) = crate::model::AIRWAY_OPENING_RANGE;
    let mut r = Row::new(
        "pressure.airway_opening",
        VR_AIRWAY_OPENING,
        Real,
        Role::Input(Input::AirwayOpening),
        "Pressure at the airway opening relative to the body surface (0: breathing air; a ventilator's pressure); reaches the alveoli through the airway resistance",
    )
    .unit("Pa")
    .display("cmH2O")
    .range(lo, hi)
    .0;
    r.causality = Causality::Input;
    r.start = Start::Real(0.0);
    rows.push(r);
    let mut r = Row::new(
        "airway.occluded",
        VR_AIRWAY_OCCLUDED,
        Boolean,
        Role::Input(Input::AirwayOccluded),
        "The airway occluded at the mouth: no gas flows, the lungs' gas follows Boyle's law from its volume and pressure when it closed, the mouth pressure is the alveolar pressure (the maximal inspiratory pressure manoeuvre); refused by solver.method 4 (quasi-static)",
    )
    .0;
    r.causality = Causality::Input;
    r.variability = Variability::Discrete;
    r.start = Start::Boolean(false);
    rows.push(r);

    let methods = (Method::ALL.len() - 1) as f64;
    let par = |name: &str, vr: u32, ty: ScalarType, p: Parameter, desc: &str| {
        Row::new(name, vr, ty, Role::Parameter(p), desc)
    };
    let mut params: Vec<Row> = vec![
        par(
            "subject.sex",
            200,
            Integer,
            P::Sex,
            "Sex of the subject: 0 male, 1 female",
        )
        .range(0.0, 1.0),
        par("subject.age", 100, Real, P::Age, "Age of the subject")
            .unit("y")
            .subject_range(),
        par(
            "subject.stature",
            101,
            Real,
            P::Stature,
            "Stature of the subject",
        )
        .unit("m")
        .subject_range(),
        par(
            "subject.mass",
            102,
            Real,
            P::Mass,
            "Body mass of the subject (body mass index 13-60 kg/m2)",
        )
        .unit("kg")
        .subject_range(),
        par(
            "subject.breast_size",
            103,
            Real,
            P::BreastSize,
            "Breast size, 0 (none) to 1 (large)",
        )
        .subject_range(),
        par(
            "posture",
            201,
            Integer,
            P::Posture,
            "Posture: 0 standing, 1 sitting, 2 supine",
        )
        .range(0.0, 2.0),
        par(
            "drive.enabled",
            400,
            Boolean,
            P::DriveEnabled,
            "The built-in drive (drive.*, thesis eq. 2.4) runs; false: the muscles follow the activation inputs alone",
        ),
        par(
            "drive.frequency",
            110,
            Real,
            P::DriveFrequency,
            "Breathing frequency of the built-in drive",
        )
        .unit("Hz")
        .range(0.05, 2.0),
        par(
            "drive.inspiratory_fraction",
            401,
            Real,
            P::DriveInspiratoryFraction,
            "Inspiratory fraction Ti/Ttot of the built-in drive's waves (raised-cosine rise and fall, docs/drive.md); 0.5 is the sine of thesis eq. 2.4",
        )
        .range(0.2, 0.8),
    ];
    for (k, f) in Family::ALL.into_iter().enumerate() {
        let vr = 111 + 2 * k as u32;
        params.push(
            par(
                &format!("drive.{}.amplitude", f.name()),
                vr,
                Real,
                P::DriveAmplitude(f),
                &format!("Drive amplitude of the {} family (fraction of the maximal activation; thesis eq. 2.4)", f.name()),
            )
            .range(0.0, 1.0),
        );
        params.push(
            par(
                &format!("drive.{}.phase", f.name()),
                vr + 1,
                Real,
                P::DrivePhase(f),
                &format!("Drive phase of the {} family", f.name()),
            )
            .unit("rad")
            .range(-2.0 * PI, 2.0 * PI),
        );
    }
    params.extend([
        par("lung.ratio", 120, Real, P::LungRatio, "Lung volume as a fraction of the thoracic cavity volume at rest (thesis 4.2); the rest, heart and mediastinum, is constant over a breath")
            .range(0.3, 1.0),
        par("gain.left", 121, Real, P::GainLeft, "Activation gain of the subject's left side (1: healthy)").range(0.0, 2.0),
        par("gain.right", 122, Real, P::GainRight, "Activation gain of the subject's right side (1: healthy)").range(0.0, 2.0),
        par("scene.level_of_detail", 202, Integer, P::LevelOfDetail, "Level of detail: 0 coarse, 1 default, 2 the thesis's element counts")
            .range(0.0, 2.0),
        par("grid.rows", 203, Integer, P::GridRows, "Marker grid rows").range(1.0, 16.0),
        par("grid.cols", 204, Integer, P::GridCols, "Marker grid columns").range(1.0, 16.0),
        par(
            "slp.reference",
            300,
            Str,
            P::SlpReference,
            "SLP recording whose first frame registers the marker grid (absolute, or relative to the FMU's resources/); empty: default grid",
        ),
        par(
            "subject.mesh_dir",
            301,
            Str,
            P::MeshDir,
            "Subject mesh directory written by `torso mesh prepare` (skin.obj, optional abdomen.obj) replacing the generated skin and cavity; empty: generated geometry",
        ),
        par(
            "solver.method",
            205,
            Integer,
            P::SolverMethod,
            "Integration method: 0 Dormand-Prince 5(4), 1 Bogacki-Shampine 3(2), 2 high-order pair, 3 Rosenbrock-W (stiff), 4 quasi-static (chest wall in equilibrium, the lung volume integrated by Dormand-Prince 5(4))",
        )
        .range(0.0, methods),
        par(
            "muscle_law",
            206,
            Integer,
            P::MuscleLaw,
            "Muscle law: 0 the seed thesis's shortening linear spring (default), 1 passive and active parts (Thelen 2003 force-length curves) with the passive wall fitted to the adult chest wall's compliance",
        )
        .range(0.0, 1.0),
        par(
            "gravity",
            207,
            Real,
            P::Gravity,
            "Gravitational acceleration acting on the torso's masses, in the posture's direction (0: weightless)",
        )
        .unit("m/s2")
        .range(0.0, crate::dynamics::GRAVITY_MAX),
        par(
            "gravity_loads",
            208,
            Integer,
            P::GravityLoads,
            "How gravity loads the model: 0 preloads cancel it at each posture's generated rest (default; posture effects from tables), 1 it acts (the abdominal contents' hydrostatic pressure, tissue tensions from the standing anatomy, each posture's rest the equilibrium under the loads)",
        )
        .range(0.0, 1.0),
        par(
            "postural_tone",
            209,
            Integer,
            P::PosturalTone,
            "The posture's tonic muscle activity: 1 on (default; standing under muscle_law 1 the abdominal wall's tone, 0.017 of the maximal force added to its activation, Cholewicki et al. 1997, scaled with gravity), 0 off (a relaxed subject, as in a relaxation manoeuvre: the passive respiratory system)",
        )
        .range(0.0, 1.0),
        par("solver.rtol", 130, Real, P::SolverRtol, "Relative tolerance of the integrator").range(1e-12, 1e-2),
        par("solver.atol", 131, Real, P::SolverAtol, "Absolute tolerance of the integrator on the state").range(1e-14, 1e-2),
        par("solver.max_step", 132, Real, P::SolverMaxStep, "Largest internal integration step").unit("s").range(1e-5, 1.0),
    ]);
    // 140 + 2 k (right) and 141 + 2 k (left) for the k-th group of MuscleGroup::ALL.
    for (k, g) in MuscleGroup::ALL.into_iter().enumerate() {
        for (s, side) in [Side::Right, Side::Left].into_iter().enumerate() {
            let side_name = match side {
                Side::Right => "right",
                Side::Left => "left",
            };
            params.push(
                par(
                    &format!("gain.{}.{side_name}", g.name()),
                    140 + 2 * k as u32 + s as u32,
                    Real,
                    P::GroupGain(g, side),
                    &format!(
                        "Activation gain of the {} on the subject's {side_name} side, times gain.{side_name} (1: healthy, 0: paralysed)",
                        g.name().replace('_', " ")
                    ),
                )
                .range(0.0, 2.0),
            );
        }
    }
    rows.extend(params.into_iter().map(|r| r.parameter(&d).0));

    use Quantity as Q;
    let out = |name: &str, vr: u32, q: Quantity, unit: &'static str, desc: &str| {
        Row::new(name, vr, Real, Role::Output(q), desc)
            .unit(unit)
            .output(Variability::Continuous)
    };
    rows.extend([
        out(
            "volume.lung",
            1000,
            Q::LungVolume,
            "L",
            "Lung volume = thoracic volume - the constant non-lung volume (heart, mediastinum; lung.ratio of the thorax at rest)",
        )
        .0,
        out(
            "volume.thorax",
            1001,
            Q::ThoraxVolume,
            "L",
            "Thoracic cavity volume = trunk - abdomen",
        )
        .0,
        out(
            "volume.abdomen",
            1002,
            Q::AbdomenVolume,
            "L",
            "Abdominal cavity volume",
        )
        .0,
        out(
            "volume.trunk",
            1003,
            Q::TrunkVolume,
            "L",
            "Trunk cavity volume (rib-cage lining plus abdominal wall)",
        )
        .0,
        out(
            "volume.rib_cage_displaced",
            1004,
            Q::RibCageDisplaced,
            "L",
            "Volume displaced by the trunk wall above the lowest point of the costal margin (rib cage, as in optoelectronic plethysmography) since the start",
        )
        .0,
        out(
            "volume.abdomen_displaced",
            1005,
            Q::AbdomenDisplaced,
            "L",
            "Volume displaced by the trunk wall below the lowest point of the costal margin (abdomen, as in optoelectronic plethysmography) since the start",
        )
        .0,
        out(
            "pressure.abdomen",
            1006,
            Q::AbdominalPressure,
            "Pa",
            "Abdominal pressure above rest (thesis eq. 2.5)",
        )
        .display("cmH2O")
        .0,
        out(
            "diaphragm.displacement",
            1007,
            Q::DiaphragmDisplacement,
            "m",
            "Displacement of the diaphragm dome since the start, positive cranial",
        )
        .display("mm")
        .0,
        out(
            "pressure.pleural",
            1011,
            Q::PleuralPressure,
            "Pa",
            "Pleural pressure relative to the body surface: alveolar pressure less the lungs' elastic recoil (about -5 cmH2O at rest)",
        )
        .display("cmH2O")
        .depends_on(&[VR_AIRWAY_OPENING, VR_AIRWAY_OCCLUDED])
        .0,
        out(
            "pressure.alveolar",
            1012,
            Q::AlveolarPressure,
            "Pa",
            "Alveolar pressure relative to the body surface: the airway opening's less the drop across the airway resistance; with the airway occluded, Boyle's law on the lungs' gas",
        )
        .display("cmH2O")
        .depends_on(&[VR_AIRWAY_OPENING, VR_AIRWAY_OCCLUDED])
        .0,
        out(
            "flow.airway",
            1013,
            Q::AirwayFlow,
            "L/s",
            "Airflow into the lungs through the airway (rate of the lung volume), positive in inspiration; 0 with the airway occluded",
        )
        .depends_on(&[VR_AIRWAY_OCCLUDED])
        .0,
        out(
            "pressure.mouth",
            1022,
            Q::MouthPressure,
            "Pa",
            "Pressure at the mouth relative to the body surface: the airway opening's with the airway open; behind an occlusion the alveolar pressure (no gas flows), the maximal inspiratory pressure's reading",
        )
        .display("cmH2O")
        .depends_on(&[VR_AIRWAY_OPENING, VR_AIRWAY_OCCLUDED])
        .0,
    ]);
    // 1014 + 2 k + side (0 right, 1 left) for lung, rib-cage and abdominal displaced
    // volumes and the hemidiaphragm.
    type Sided = (&'static str, fn(u8) -> Quantity, &'static str, &'static str);
    let sided: [Sided; 4] = [
        (
            "volume.lung",
            Q::LungVolumeSide,
            "L",
            "Volume of the {side} lung: its rest share of the lungs (right 53.3 %, CT volumetry) plus the change of its side of the thorax",
        ),
        (
            "volume.rib_cage_displaced",
            Q::RibCageDisplacedSide,
            "L",
            "Volume displaced by the {side} half of the rib-cage wall since the start",
        ),
        (
            "volume.abdomen_displaced",
            Q::AbdomenDisplacedSide,
            "L",
            "Volume displaced by the {side} half of the abdominal wall since the start",
        ),
        (
            "diaphragm.displacement",
            Q::DiaphragmDisplacementSide,
            "m",
            "Displacement of the {side} hemidiaphragm since the start, positive cranial",
        ),
    ];
    for (k, (name, q, unit, desc)) in sided.into_iter().enumerate() {
        for (s, side) in ["right", "left"].into_iter().enumerate() {
            let mut row = out(
                &format!("{name}.{side}"),
                1014 + 2 * k as u32 + s as u32,
                q(s as u8),
                unit,
                &desc.replace("{side}", side),
            );
            if unit == "m" {
                row = row.display("mm");
            }
            rows.push(row.0);
        }
    }
    for (axis, a) in AXES.iter().enumerate() {
        rows.push(
            out(
                &format!("sternum.displacement.{a}"),
                1008 + axis as u32,
                Q::SternumDisplacement(axis as u8),
                "m",
                &format!("Displacement of the sternum since the start along {a} (x anterior, y cranial, z right)"),
            )
            .display("mm")
            .0,
        );
    }
    rows.extend(marker_rows(markers));
    let int_out = |name: &str, vr: u32, q: Quantity, desc: &str| {
        Row::new(name, vr, Integer, Role::Output(q), desc)
            .output(Variability::Discrete)
            .0
    };
    rows.extend([
        int_out(
            "solver.steps",
            3000,
            Q::SolverSteps,
            "Accepted integration steps since the start",
        ),
        int_out(
            "solver.rejected_steps",
            3001,
            Q::SolverRejectedSteps,
            "Rejected integration steps since the start",
        ),
        int_out(
            "solver.rhs_evaluations",
            3002,
            Q::SolverRhsEvaluations,
            "Right-hand-side evaluations since the start",
        ),
    ]);
    rows
}
