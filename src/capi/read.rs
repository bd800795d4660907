//! Reading a handle's outputs: any numeric FMI variable by value reference or name
//! (including grid markers beyond the generic FMU's slots), the marker positions, and the
//! whole skin mesh.

use super::guard::{Failure, put, text, with_handle};
use super::{BT_ERR_BUFFER, BT_ERR_INVALID, BT_ERR_NULL, BtTorso};
use crate::fmi::variables::{Role, table};
use crate::{Error, Result};
use std::os::raw::{c_char, c_int};

fn read_variable(b: &mut BtTorso, var: &crate::fmi::variables::Variable) -> Result<f64> {
    match var.role {
        Role::Time => Ok(b.torso.time()),
        Role::Input(input) => Ok(input.value(&b.torso)),
        Role::Parameter(p) => match p.get(b.torso.config()) {
            crate::fmi::variables::Value::Real(x) => Ok(x),
            crate::fmi::variables::Value::Integer(i) => Ok(f64::from(i)),
            crate::fmi::variables::Value::Boolean(b) => Ok(f64::from(u8::from(b))),
            crate::fmi::variables::Value::String(_) => {
                Err(Error::invalid(&var.name, "(string)", "a numeric variable"))
            }
        },
        Role::Output(q) => b.torso.read_output(&var.name, q),
    }
}

/// A grid marker beyond the generic FMU's [`MARKER_SLOTS`](crate::fmi::variables::MARKER_SLOTS)
/// outputs, which the C library reads as well (its grid may have up to 16 x 16 markers):
/// `BT_VR_MARKER(i, axis)` or `marker[i].<axis>` for i up to 256, as (0-based index, axis).
fn extra_grid_marker(vr: Option<u32>, name: Option<&str>) -> Option<(u16, u8)> {
    use crate::fmi::variables::{MARKER_SLOTS, MAX_MARKER_OUTPUTS, VR_MARKER};
    let (index, axis) = match (vr, name) {
        (Some(vr), _) => {
            let k = vr.checked_sub(VR_MARKER)?;
            (u16::try_from(k / 3).ok()?, (k % 3) as u8)
        }
        (None, Some(name)) => {
            let rest = name.strip_prefix("marker[")?;
            let (i, a) = rest.split_once("].")?;
            let i: u16 = i.parse().ok().filter(|&i| i >= 1)?;
            let axis = ["x", "y", "z"].iter().position(|x| *x == a)? as u8;
            (i - 1, axis)
        }
        (None, None) => return None,
    };
    (MARKER_SLOTS..MAX_MARKER_OUTPUTS)
        .contains(&index)
        .then_some((index, axis))
}

/// Reads a grid marker that is not one of the table's outputs ([`extra_grid_marker`]).
fn read_extra_marker(b: &mut BtTorso, (index, axis): (u16, u8)) -> Result<f64> {
    let name = format!(
        "marker[{}].{}",
        index + 1,
        ["x", "y", "z"][usize::from(axis)]
    );
    b.torso
        .read_output(&name, crate::model::Quantity::Marker { index, axis })
}

/// Reads any numeric FMI variable by value reference (`BT_VR_*` constants): outputs, inputs,
/// parameters, time. `BT_VR_MARKER(i, axis)` takes any i up to 256 (the largest grid, 16 x
/// 16), beyond the FMU's `BT_MARKER_SLOTS`; markers beyond the grid read 0.
///
/// # Safety
/// `h` must be NULL or a live handle; `value` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_read(h: *mut BtTorso, vr: u32, value: *mut f64) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let v = match table().by_vr(vr) {
                Some(var) => read_variable(b, var)?,
                None => {
                    let marker = extra_grid_marker(Some(vr), None).ok_or_else(|| {
                        Failure(BT_ERR_INVALID, format!("unknown value reference {vr}"))
                    })?;
                    read_extra_marker(b, marker)?
                }
            };
            put(value, v, "value")
        })
    }
}

/// Reads any numeric FMI variable by name (`"volume.lung"`, `"marker[3].y"`, ...; grid
/// markers up to `marker[256]`, as [`bt_read`]).
///
/// # Safety
/// `h` must be NULL or a live handle; `name` NULL or NUL-terminated; `value` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_read_by_name(
    h: *mut BtTorso,
    name: *const c_char,
    value: *mut f64,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let name = text(name, "name")?;
            let v = match table().by_name(name) {
                Some(var) => read_variable(b, var)?,
                None => {
                    let marker = extra_grid_marker(None, Some(name)).ok_or_else(|| {
                        Failure(BT_ERR_INVALID, format!("unknown variable `{name}`"))
                    })?;
                    read_extra_marker(b, marker)?
                }
            };
            put(value, v, "value")
        })
    }
}

/// Number of markers of the scene (`grid_rows * grid_cols`).
///
/// # Safety
/// `h` must be NULL or a live handle; `count` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_marker_count(h: *mut BtTorso, count: *mut usize) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let s = &b.torso.config().scene;
            put(count, s.grid_rows * s.grid_cols, "count")
        })
    }
}

/// Writes the marker positions [m] as x, y, z triples, row-major from the top row, column 1 on
/// the subject's right, into `xyz` (capacity `capacity` doubles: at least 3 x the marker
/// count, else `BT_ERR_BUFFER`). `count` (may be NULL) receives the number of markers.
///
/// # Safety
/// `h` must be NULL or a live handle; `xyz` NULL or `capacity` writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_read_markers(
    h: *mut BtTorso,
    xyz: *mut f64,
    capacity: usize,
    count: *mut usize,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let s = &b.torso.config().scene;
            let n = s.grid_rows * s.grid_cols;
            if !count.is_null() {
                *count = n;
            }
            if capacity < 3 * n {
                return Err(Failure(
                    BT_ERR_BUFFER,
                    format!("marker buffer holds {capacity} doubles, {} needed", 3 * n),
                ));
            }
            if xyz.is_null() {
                return Err(Failure(BT_ERR_NULL, "argument `xyz` is NULL".into()));
            }
            let out = std::slice::from_raw_parts_mut(xyz, 3 * n);
            // the markers of the state once (not 3 n reads by name); those past the marker
            // count read 0, as in `bt_read`
            let count = b.torso.marker_count().min(n);
            let time = b.torso.time();
            let markers = b
                .torso
                .markers()
                .map_err(|e| crate::Error::State(format!("cannot read the markers: {e}")))?;
            out.fill(0.0);
            for (i, (o, p)) in out.chunks_exact_mut(3).zip(&markers[..count]).enumerate() {
                for (axis, (o, x)) in o.iter_mut().zip(p.coords.iter()).enumerate() {
                    if !x.is_finite() {
                        let name = format!("marker[{}].{}", i + 1, ["x", "y", "z"][axis]);
                        return Err(crate::Error::Numerical {
                            time,
                            reason: format!("`{name}` is not finite ({x})"),
                        }
                        .into());
                    }
                    *o = *x;
                }
            }
            Ok(())
        })
    }
}

/// Sizes of the whole skin mesh (the surface the markers sit on): its vertex and triangle
/// counts, fixed for the handle's life. The first skin or marker call builds the skin model (a
/// few tenths of a second, shared with the markers). Either output may be NULL.
///
/// # Safety
/// `h` must be NULL or a live handle; the outputs NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_skin_sizes(
    h: *mut BtTorso,
    vertices: *mut usize,
    triangles: *mut usize,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            let model = b.torso.marker_model()?;
            let skin = model.skin();
            if !vertices.is_null() {
                *vertices = skin.vertices.len();
            }
            if !triangles.is_null() {
                *triangles = skin.triangles.len();
            }
            Ok(())
        })
    }
}

/// Writes the skin mesh of the current state: vertex positions [m] as x, y, z triples into
/// `vertices` (`vertex_capacity` doubles, at least 3 x the vertex count of `bt_skin_sizes`),
/// in the markers' frame (the recording's when the grid is registered, else the model's),
/// and the triangles as vertex-index triples, counter-clockwise seen from outside, into
/// `triangles` (`triangle_capacity` indices, at least 3 x the triangle count). Either buffer
/// may be NULL and is then skipped: the triangles never change, so read them once and the
/// vertices every frame. Both NULL is `BT_ERR_NULL`; a buffer too small is `BT_ERR_BUFFER`
/// and nothing is written.
///
/// # Safety
/// `h` must be NULL or a live handle; buffers NULL or writable for their capacities.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bt_read_skin(
    h: *mut BtTorso,
    vertices: *mut f64,
    vertex_capacity: usize,
    triangles: *mut u32,
    triangle_capacity: usize,
) -> c_int {
    unsafe {
        with_handle(h, |b| {
            if vertices.is_null() && triangles.is_null() {
                return Err(Failure(
                    BT_ERR_NULL,
                    "arguments `vertices` and `triangles` are both NULL".into(),
                ));
            }
            let model = b.torso.marker_model()?;
            let skin = model.skin();
            let (nv, nt) = (3 * skin.vertices.len(), 3 * skin.triangles.len());
            if !vertices.is_null() && vertex_capacity < nv {
                return Err(Failure(
                    BT_ERR_BUFFER,
                    format!("skin vertex buffer holds {vertex_capacity} doubles, {nv} needed"),
                ));
            }
            if !triangles.is_null() && triangle_capacity < nt {
                return Err(Failure(
                    BT_ERR_BUFFER,
                    format!("skin triangle buffer holds {triangle_capacity} indices, {nt} needed"),
                ));
            }
            if !vertices.is_null() {
                b.torso.skin_vertices(&mut b.skin)?;
                let out = std::slice::from_raw_parts_mut(vertices, nv);
                for (o, p) in out.chunks_exact_mut(3).zip(&b.skin) {
                    o.copy_from_slice(&[p.x, p.y, p.z]);
                }
            }
            if !triangles.is_null() {
                let out = std::slice::from_raw_parts_mut(triangles, nt);
                for (o, t) in out.chunks_exact_mut(3).zip(&skin.triangles) {
                    o.copy_from_slice(t);
                }
            }
            Ok(())
        })
    }
}
