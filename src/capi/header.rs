//! The block of FMI value references appended to the generated header
//! `include/breathing_torso.h` (the rest of the header cbindgen writes from the C ABI's
//! items).

use crate::fmi::variables::table;

/// The value-reference block appended to `include/breathing_torso.h`: one `BT_VR_*` constant
/// per FMI variable (name upper-cased, `.` as `_`), a macro for the markers, the GUID and the
/// marker slot count, all generated from [`crate::fmi::variables`]. `bt_read` takes these.
pub fn header_value_references() -> String {
    use crate::fmi::variables::{MARKER_SLOTS, Role, VR_MARKER};
    use std::fmt::Write;
    let t = table();
    let mut s = String::from(
        "/* FMI value references (generated from the variable table), for bt_read(). */\n",
    );
    let _ = writeln!(s, "#define BT_FMI_GUID \"{}\"", t.guid());
    let _ = writeln!(s, "#define BT_MARKER_SLOTS {MARKER_SLOTS}");
    for v in t.variables() {
        if matches!(v.role, Role::Output(crate::model::Quantity::Marker { .. })) {
            continue;
        }
        let name: String = v
            .name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() {
                    c.to_ascii_uppercase()
                } else {
                    '_'
                }
            })
            .collect();
        let _ = writeln!(s, "#define BT_VR_{name} {}u", v.vr);
    }
    let _ = writeln!(
        s,
        "/* marker[i].x|y|z, axis 0 = x, 1 = y, 2 = z: i = 1..BT_MARKER_SLOTS are the FMU's outputs (the\n   \
         default 10 x 6 grid); bt_read takes i up to 256 (a grid of up to 16 x 16) */\n\
         #define BT_VR_MARKER(i, axis) ({VR_MARKER}u + 3u * ((unsigned)(i) - 1u) + (unsigned)(axis))"
    );
    s
}
