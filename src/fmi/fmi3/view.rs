//! The FMI 3.0 view of the one variable table ([`crate::fmi::variables`]): which FMI 3.0 type
//! each variable has, the enumerations (sex, posture, solver method) and the marker array.
//!
//! The table's 180 scalar marker outputs `marker[i].<axis>` (value references
//! `2000 + 3 (i - 1) + axis`, the default 10 x 6 grid's 60 markers) become one `Float64`
//! array output `marker` of dimensions (60 x 3), value reference 2000, whose row-major
//! elements are those scalars in table order. The dimensions are fixed start values, not a
//! structural parameter: the marker count is `grid.rows x grid.cols`, a product, while an FMI
//! 3.0 `<Dimension>` names a single structural parameter; and a fixed size keeps the array
//! element for element equal to the FMI 2.0 scalars (a smaller grid's markers beyond
//! `rows x cols` read 0 in both, a larger grid is refused by both). Every other variable
//! keeps its name and value reference.

use crate::anatomy::{Posture, Sex};
use crate::fmi::variables::{
    MARKER_SLOTS, Parameter, Role, ScalarType, VR_MARKER, Variable, marker_vr, table,
};
use crate::model::Quantity;
use crate::solver::Method;

/// Name of the marker array output.
pub const MARKER_ARRAY: &str = "marker";
/// Value reference of the marker array (the table's `marker[1].x`).
pub const VR_MARKER_ARRAY: u32 = VR_MARKER;
/// Dimensions of the marker array: (markers, 3).
pub const MARKER_DIMENSIONS: [usize; 2] = [MARKER_SLOTS as usize, 3];

/// An enumeration type declared in `<TypeDefinitions>`.
#[derive(Clone, Debug, PartialEq)]
pub struct Enumeration {
    /// Type name (`declaredType` of its variable).
    pub name: &'static str,
    /// The parameter that has this type.
    pub parameter: Parameter,
    /// Items: (name, value), values being the model's codes.
    pub items: Vec<(String, i64)>,
}

/// The three enumerations, their items read off the model's own code tables.
pub fn enumerations() -> Vec<Enumeration> {
    let codes = |f: &dyn Fn(i64) -> Option<String>| -> Vec<(String, i64)> {
        (0..).map_while(|c| f(c).map(|name| (name, c))).collect()
    };
    vec![
        Enumeration {
            name: "Sex",
            parameter: Parameter::Sex,
            items: codes(&|c| {
                Sex::from_code(c)
                    .ok()
                    .map(|s| format!("{s:?}").to_lowercase())
            }),
        },
        Enumeration {
            name: "Posture",
            parameter: Parameter::Posture,
            items: codes(&|c| {
                Posture::from_code(c)
                    .ok()
                    .map(|p| format!("{p:?}").to_lowercase())
            }),
        },
        Enumeration {
            name: "SolverMethod",
            parameter: Parameter::SolverMethod,
            items: codes(&|c| Method::from_code(c).map(|m| m.name().to_string())),
        },
    ]
}

/// The FMI 3.0 type of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Type3 {
    /// `Float64` (the table's Real).
    Float64,
    /// `Int32` (the table's Integer, but for the enumerations).
    Int32,
    /// `Enumeration` (accessed with `fmi3GetInt64`/`fmi3SetInt64`), by index in
    /// [`enumerations`].
    Enumeration(usize),
    /// `Boolean`.
    Boolean,
    /// `String`.
    String,
}

impl Type3 {
    /// The element name in `modelDescription.xml`, also used in messages.
    pub fn name(self) -> &'static str {
        match self {
            Type3::Float64 => "Float64",
            Type3::Int32 => "Int32",
            Type3::Enumeration(_) => "Enumeration",
            Type3::Boolean => "Boolean",
            Type3::String => "String",
        }
    }
}

/// `name` with its indefinite article: "an Int32", "an Enumeration", "a Float64".
pub fn with_article(name: &str) -> String {
    let vowel = name.starts_with(['A', 'E', 'I', 'O']);
    format!("{} {name}", if vowel { "an" } else { "a" })
}

/// Whether the variable is one of the scalar markers folded into the marker array.
pub fn is_marker_scalar(v: &Variable) -> bool {
    matches!(v.role, Role::Output(Quantity::Marker { .. }))
}

/// The FMI 3.0 type of a table variable.
pub fn type_of(v: &Variable) -> Type3 {
    match (v.ty, v.role) {
        (ScalarType::Integer, Role::Parameter(p)) => {
            match enumerations().iter().position(|e| e.parameter == p) {
                Some(i) => Type3::Enumeration(i),
                None => Type3::Int32,
            }
        }
        (ScalarType::Integer, _) => Type3::Int32,
        (ScalarType::Real, _) => Type3::Float64,
        (ScalarType::Boolean, _) => Type3::Boolean,
        (ScalarType::String, _) => Type3::String,
    }
}

/// An FMI 3.0 variable: a table variable, or the marker array standing for the first
/// marker scalar and all that follow.
#[derive(Clone, Copy, Debug)]
pub enum Variable3 {
    /// A scalar variable of the table.
    Scalar(&'static Variable),
    /// The marker array; the variable is `marker[1].x`, whose unit and causality it has.
    MarkerArray(&'static Variable),
}

impl Variable3 {
    /// Value reference.
    pub fn vr(self) -> u32 {
        match self {
            Variable3::Scalar(v) => v.vr,
            Variable3::MarkerArray(_) => VR_MARKER_ARRAY,
        }
    }
    /// The table variable behind it.
    pub fn variable(self) -> &'static Variable {
        match self {
            Variable3::Scalar(v) | Variable3::MarkerArray(v) => v,
        }
    }
}

/// The FMI 3.0 variables in `<ModelVariables>` order: the table's, the marker array in place
/// of the scalar markers.
pub fn variables() -> Vec<Variable3> {
    let mut out = Vec::new();
    for v in table().variables() {
        if is_marker_scalar(v) {
            if v.vr == VR_MARKER_ARRAY {
                out.push(Variable3::MarkerArray(v));
            }
        } else {
            out.push(Variable3::Scalar(v));
        }
    }
    out
}

/// The table value references behind FMI 3.0 value references of type `ty`, flattened (the
/// marker array gives its 180 elements, row-major), or a message naming the first that is
/// unknown or of another type.
pub fn expand(vrs: &[u32], ty: Type3) -> Result<Vec<u32>, String> {
    let mut out = Vec::with_capacity(vrs.len());
    for &vr in vrs {
        let var = table().by_vr(vr);
        match var {
            Some(_) if vr == VR_MARKER_ARRAY => {
                if ty != Type3::Float64 {
                    return Err(format!(
                        "value reference {vr} is `{MARKER_ARRAY}`, a Float64 array, not {}",
                        with_article(ty.name())
                    ));
                }
                for index in 0..MARKER_SLOTS {
                    for axis in 0..3 {
                        out.push(marker_vr(index, axis));
                    }
                }
            }
            Some(v) if !is_marker_scalar(v) => {
                let found = type_of(v);
                let same = match (found, ty) {
                    (Type3::Enumeration(_), Type3::Enumeration(_)) => true,
                    (a, b) => a == b,
                };
                if !same {
                    let hint = match found {
                        Type3::Enumeration(_) => " (Enumerations are read and set as Int64)",
                        _ => "",
                    };
                    return Err(format!(
                        "value reference {vr} is `{}`, {}, not {}{hint}",
                        v.name,
                        with_article(found.name()),
                        with_article(ty.name())
                    ));
                }
                out.push(vr);
            }
            _ => return Err(format!("unknown value reference {vr}")),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_marker_array_is_the_scalar_markers_row_major() {
        let flat = expand(&[VR_MARKER_ARRAY], Type3::Float64).unwrap();
        assert_eq!(flat.len(), MARKER_DIMENSIONS[0] * MARKER_DIMENSIONS[1]);
        for (k, vr) in flat.iter().enumerate() {
            let v = table().by_vr(*vr).unwrap();
            let (i, axis) = (k / 3, k % 3);
            assert_eq!(
                v.name,
                format!("marker[{}].{}", i + 1, ["x", "y", "z"][axis])
            );
        }
        // A scalar marker other than the first is not an FMI 3.0 variable.
        assert!(expand(&[VR_MARKER_ARRAY + 1], Type3::Float64).is_err());
    }

    #[test]
    fn enumerations_follow_the_model_codes() {
        let e = enumerations();
        let names = |i: usize| -> Vec<&str> { e[i].items.iter().map(|x| x.0.as_str()).collect() };
        assert_eq!(names(0), ["male", "female"]);
        assert_eq!(names(1), ["standing", "sitting", "supine"]);
        assert_eq!(e[2].items.len(), Method::ALL.len());
        let posture = table().by_name("posture").unwrap();
        assert_eq!(type_of(posture), Type3::Enumeration(1));
        let err = expand(&[posture.vr], Type3::Int32).unwrap_err();
        assert!(err.contains("an Enumeration, not an Int32"), "{err}");
        assert!(err.contains("Int64"), "{err}");
        let rows = table().by_name("grid.rows").unwrap();
        assert_eq!(type_of(rows), Type3::Int32);
    }
}
