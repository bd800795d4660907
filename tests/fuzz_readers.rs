//! Property tests of the file readers on hostile input: the SLP recording reader
//! (`Recording::parse`) and the mesh readers (OBJ, STL binary and ASCII, OFF, VTK). Inputs are
//! random bytes, and valid files (written by the crate's own writers) mutated: truncated,
//! bytes flipped, lines deleted or duplicated, a number replaced by a huge count, a negative
//! number, NaN, infinity or garbage. Every reader must return `Ok` or `Err`, never panic, and
//! never ask for an allocation out of proportion to the input (a header count is not trusted:
//! the largest single allocation is checked against the input's size by a counting allocator).

use breathing_torso::mesh::TriMesh;
use breathing_torso::mesh::io;
use breathing_torso::recording::Recording;
use breathing_torso::recording::Units;
use nalgebra::Point3;
use proptest::prelude::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// The system allocator, recording the largest single request of the current thread.
struct Counting;

thread_local! {
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: forwards to the system allocator; the bookkeeping allocates nothing.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = LARGEST.try_with(|l| l.set(l.get().max(layout.size())));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = LARGEST.try_with(|l| l.set(l.get().max(new_size)));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Largest allocation a reader may make for `input_len` bytes of input: parsed data is at
/// most a few dozen bytes per input byte (a 2-byte OBJ face `f 1 2 3` is a 12-byte
/// triangle, a vertex of 6 bytes is 24), plus a fixed allowance.
fn allowance(input_len: usize) -> usize {
    64 * input_len + (1 << 16)
}

/// Runs `read` on `input`, checking the largest allocation it made.
fn bounded<T>(input_len: usize, read: impl FnOnce() -> T) -> T {
    LARGEST.with(|l| l.set(0));
    let out = read();
    let largest = LARGEST.with(Cell::get);
    assert!(
        largest <= allowance(input_len),
        "an allocation of {largest} bytes for {input_len} bytes of input"
    );
    out
}

fn all_mesh_readers(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    let n = bytes.len();
    let _ = bounded(n, || io::parse_obj(&text, "fuzz.obj"));
    let _ = bounded(n, || io::parse_off(&text, "fuzz.off"));
    let _ = bounded(n, || io::parse_vtk(&text, "fuzz.vtk"));
    for tolerance in [0.0, 1e-9, 1e-3] {
        let _ = bounded(n, || io::parse_stl(bytes, "fuzz.stl", tolerance));
    }
}

/// A small closed surface (an octahedron scaled and shifted by `s`).
fn mesh(s: f64) -> TriMesh {
    let v = |x: f64, y: f64, z: f64| Point3::new(s * x + 0.1, s * y - 0.2, s * z + 0.3);
    TriMesh {
        vertices: vec![
            v(1.0, 0.0, 0.0),
            v(-1.0, 0.0, 0.0),
            v(0.0, 1.0, 0.0),
            v(0.0, -1.0, 0.0),
            v(0.0, 0.0, 1.0),
            v(0.0, 0.0, -1.0),
        ],
        triangles: vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ],
    }
}

/// Valid files of every mesh format.
fn mesh_files(s: f64) -> Vec<Vec<u8>> {
    let m = mesh(s);
    vec![
        io::to_obj(&m).into_bytes(),
        io::to_off(&m).into_bytes(),
        io::to_vtk(&m).into_bytes(),
        io::to_stl_ascii(&m).into_bytes(),
        io::to_stl_binary(&m),
    ]
}

/// A valid recording file: a 2 x 2 grid over `frames` frames, one point untracked.
fn recording_file(frames: usize, mm: bool) -> String {
    let rec = Recording {
        grid: (2, 2),
        times: (0..frames).map(|i| i as f64 / 56.0).collect(),
        frames: (0..frames)
            .map(|i| {
                (0..4)
                    .map(|k| {
                        (k != 3 || i % 2 == 0).then(|| {
                            Point3::new(0.1 * k as f64, 1.2 + 0.001 * i as f64, -0.05 * k as f64)
                        })
                    })
                    .collect()
            })
            .collect(),
        units: if mm {
            Units::Millimetres
        } else {
            Units::Metres
        },
        provenance: Vec::new(),
    };
    rec.to_csv().expect("a valid recording writes")
}

/// Replacements for one token of a valid file.
const NASTY: [&str; 14] = [
    "18446744073709551615",
    "4294967295",
    "4294967296",
    "99999999999",
    "-1",
    "NaN",
    "inf",
    "-inf",
    "1e400",
    "",
    "x",
    "0",
    "3.5",
    "\u{0}",
];

#[derive(Clone, Debug)]
enum Mutation {
    Truncate(usize),
    Flip(usize, u8),
    DeleteLine(usize),
    DuplicateLine(usize),
    Token(usize, usize),
    Insert(usize, Vec<u8>),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), 1u8..=255).prop_map(|(i, b)| Mutation::Flip(i, b)),
        any::<usize>().prop_map(Mutation::DeleteLine),
        any::<usize>().prop_map(Mutation::DuplicateLine),
        (any::<usize>(), 0..NASTY.len()).prop_map(|(i, k)| Mutation::Token(i, k)),
        (
            any::<usize>(),
            proptest::collection::vec(any::<u8>(), 0..16)
        )
            .prop_map(|(i, b)| Mutation::Insert(i, b)),
    ]
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    if bytes.is_empty() {
        return;
    }
    let at = |i: usize, n: usize| i % n.max(1);
    match m {
        Mutation::Truncate(i) => bytes.truncate(at(*i, bytes.len())),
        Mutation::Flip(i, b) => {
            let k = at(*i, bytes.len());
            bytes[k] ^= b;
        }
        Mutation::DeleteLine(i) | Mutation::DuplicateLine(i) => {
            let mut lines: Vec<Vec<u8>> =
                bytes.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect();
            let k = at(*i, lines.len());
            if matches!(m, Mutation::DeleteLine(_)) {
                lines.remove(k);
            } else {
                let l = lines[k].clone();
                lines.insert(k, l);
            }
            *bytes = lines.join(&b'\n');
        }
        Mutation::Token(i, k) => {
            // the i-th maximal run of non-separator bytes
            let is_sep = |b: u8| b.is_ascii_whitespace() || b == b',';
            let mut runs = Vec::new();
            let mut start = None;
            for (j, &b) in bytes.iter().enumerate() {
                match (is_sep(b), start) {
                    (false, None) => start = Some(j),
                    (true, Some(s)) => {
                        runs.push((s, j));
                        start = None;
                    }
                    _ => {}
                }
            }
            if let Some(s) = start {
                runs.push((s, bytes.len()));
            }
            if let Some(&(s, e)) = runs.get(at(*i, runs.len())) {
                bytes.splice(s..e, NASTY[*k].bytes());
            }
        }
        Mutation::Insert(i, b) => {
            let k = at(*i, bytes.len());
            bytes.splice(k..k, b.iter().copied());
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn mesh_readers_survive_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..2048)) {
        all_mesh_readers(&bytes);
    }

    #[test]
    fn mesh_readers_survive_random_text_with_keywords(
        words in proptest::collection::vec(
            prop_oneof![
                Just("v".to_string()), Just("f".to_string()), Just("OFF".to_string()),
                Just("POINTS".to_string()), Just("POLYGONS".to_string()),
                Just("TRIANGLE_STRIPS".to_string()), Just("OFFSETS".to_string()),
                Just("CONNECTIVITY".to_string()), Just("solid".to_string()),
                Just("facet".to_string()), Just("outer".to_string()), Just("vertex".to_string()),
                Just("endloop".to_string()), Just("\n".to_string()),
                Just("# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\n".to_string()),
                (0u64..20).prop_map(|v| v.to_string()),
                any::<u64>().prop_map(|v| v.to_string()),
                any::<f64>().prop_map(|v| v.to_string()),
                Just("-1".to_string()),
            ],
            0..200,
        )
    ) {
        all_mesh_readers(words.join(" ").as_bytes());
    }

    #[test]
    fn mesh_readers_survive_mutated_valid_files(
        scale in prop_oneof![Just(1.0), Just(1e-30), Just(1e30), Just(3.4e38)],
        which in 0usize..5,
        mutations in proptest::collection::vec(mutation(), 1..4),
    ) {
        let mut bytes = mesh_files(scale)[which].clone();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        all_mesh_readers(&bytes);
    }

    #[test]
    fn recording_reader_survives_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..2048)) {
        let text = String::from_utf8_lossy(&bytes);
        let _ = bounded(bytes.len(), || Recording::parse(&text, "fuzz.csv"));
    }

    #[test]
    fn recording_reader_survives_mutated_valid_files(
        frames in 2usize..6,
        mm in any::<bool>(),
        mutations in proptest::collection::vec(mutation(), 1..4),
    ) {
        let mut bytes = recording_file(frames, mm).into_bytes();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        let text = String::from_utf8_lossy(&bytes);
        if let Ok(rec) = bounded(bytes.len(), || Recording::parse(&text, "fuzz.csv")) {
            // whatever is accepted is a consistent recording
            prop_assert!(rec.validate().is_ok(), "{rec:?}");
        }
    }
}

#[test]
fn valid_files_read_back() {
    for (k, bytes) in mesh_files(1.0).iter().enumerate() {
        let text = String::from_utf8_lossy(bytes);
        let m = match k {
            0 => io::parse_obj(&text, "a.obj"),
            1 => io::parse_off(&text, "a.off"),
            2 => io::parse_vtk(&text, "a.vtk"),
            _ => io::parse_stl(bytes, "a.stl", 0.0),
        }
        .expect("a valid file reads");
        assert_eq!((m.vertices.len(), m.triangles.len()), (6, 8), "format {k}");
    }
    let rec = Recording::parse(&recording_file(3, true), "a.csv").expect("valid");
    assert_eq!((rec.grid, rec.times.len()), ((2, 2), 3));
}

#[test]
fn huge_header_counts_are_errors_without_huge_allocations() {
    let cases: [(&str, &str); 6] = [
        ("off", "OFF\n18446744073709551615 1 0\n0 0 0\n"),
        ("off", "OFF\n1 4000000000000 0\n0 0 0\n3 0 0 0\n"),
        (
            "vtk",
            "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 18446744073709551615 float\n0 0 0\n",
        ),
        (
            "vtk",
            "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 9999999999999 4\n3 0 1 2\n",
        ),
        (
            "vtk",
            "# vtk DataFile Version 5.1\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 9999999999999 3\nOFFSETS vtktypeint64\n0 3\nCONNECTIVITY vtktypeint64\n0 1 2\n",
        ),
        (
            "vtk",
            "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 18446744073709551615\n18446744073709551615 0 1 2\n",
        ),
    ];
    for (format, text) in cases {
        let r = bounded(text.len(), || match format {
            "off" => io::parse_off(text, "huge.off"),
            _ => io::parse_vtk(text, "huge.vtk"),
        });
        let e = r.expect_err(text);
        println!("{format}: {e}");
    }
    // a binary STL whose header announces more triangles than the file holds
    let mut stl = io::to_stl_binary(&mesh(1.0));
    stl[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = bounded(stl.len(), || io::parse_stl(&stl, "huge.stl", 0.0)).expect_err("truncated");
    assert!(e.to_string().contains("truncated"), "{e}");
}

#[test]
fn welding_extreme_coordinates_does_not_overflow() {
    // cells of 1e-9 over coordinates near f32::MAX saturate the grid index
    let m = mesh(3.4e38);
    let stl = io::to_stl_binary(&m);
    let r = io::parse_stl(&stl, "far.stl", 1e-9);
    assert!(r.is_ok(), "{r:?}");
}
