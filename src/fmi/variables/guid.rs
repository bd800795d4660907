//! The GUID of a variable table: a 128-bit FNV-1a hash of the interface part of the model
//! description (identifier, capability flags, units and every variable's attributes, not its
//! description), formatted `{8-4-4-4-12}`, so that it changes exactly when the interface
//! changes.

use super::MODEL_IDENTIFIER;
use super::types::{UNITS, Variable};

/// flags, units, and every variable's name, reference, type, causality, variability, initial,
/// unit, range, start and input dependencies (descriptions excluded).
pub(super) fn interface_text(variables: &[Variable]) -> String {
    use std::fmt::Write;
    let mut s = format!(
        "fmi2|{MODEL_IDENTIFIER}|cs|{}\n",
        crate::fmi::xml::CAPABILITY_FLAGS.join(",")
    );
    for u in UNITS {
        let _ = writeln!(
            s,
            "unit|{}|{:?}|{:?}|{:?}",
            u.name, u.base, u.factor, u.display
        );
    }
    for v in variables {
        let _ = writeln!(
            s,
            "{}|{}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}",
            v.name,
            v.vr,
            v.ty,
            v.causality,
            v.variability,
            v.initial,
            v.unit,
            v.display_unit,
            v.min,
            v.max,
            v.start,
            v.input_dependencies
        );
    }
    s
}

/// 128-bit FNV-1a (Fowler-Noll-Vo) hash.
pub fn fnv1a_128(bytes: &[u8]) -> u128 {
    const OFFSET: u128 = 0x6c62272e07bb014262b821756295c58d;
    const PRIME: u128 = 0x0000000001000000000000000000013B;
    bytes
        .iter()
        .fold(OFFSET, |h, &b| (h ^ u128::from(b)).wrapping_mul(PRIME))
}

/// `{8-4-4-4-12}` hexadecimal form of a 128-bit hash.
pub(super) fn format_guid(h: u128) -> String {
    let x = format!("{h:032x}");
    format!(
        "{{{}-{}-{}-{}-{}}}",
        &x[0..8],
        &x[8..12],
        &x[12..16],
        &x[16..20],
        &x[20..32]
    )
}
