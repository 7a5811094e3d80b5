//! OFF reader: header variants, counts, comments, ignored colours; malformed files name the line.

use geom_core::graph::Ragged;
use geom_core::io::{off, ReadOptions};
use geom_core::math::Pt3;
use geom_core::Error;

fn rows(f: &Ragged<u32>) -> Vec<Vec<u32>> {
    f.rows().map(|r| r.to_vec()).collect()
}

fn parse_err(text: &str) -> (usize, String) {
    match off::parse(text.as_bytes()) {
        Err(Error::Parse { format: "OFF", line, msg }) => {
            assert!(!msg.is_empty());
            (line, msg)
        }
        other => panic!("expected an OFF parse error for {text:?}, got {other:?}"),
    }
}

#[test]
fn header_variants_comments_and_ignored_extras() {
    let plain = "OFF\n# a square and a triangle\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n4 0 1 2 3\n3 1 4 2\n";
    let same_line = "OFF 5 2 7\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n4 0 1 2 3\n3 1 4 2";
    let coff = "COFF\r\n5\t2\t0\r\n0 0 0 255 0 0 255\r\n1 0 0 0 255 0 255\r\n1 1 0 0 0 255 255\r\n\
                0 1 0 1 1 1 1\r\n2 0 0 0.5 0.5 0.5 1\r\n4 0 1 2 3 255 0 0\r\n3 1 4 2 0.1 0.2 0.3 0.4\r\n";
    let noff = "NOFF\n\n5 2 0 # counts\n0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n2 0 0 0 0 1 # last\n\
                4 0 1 2 3\n\n3 1 4 2\n\n";
    let stcnoff = "STCNOFF\n5 2 0\n0 0 0 0 0 1 1 1 1 0 0\n1 0 0 0 0 1 1 1 1 1 0\n1 1 0 0 0 1 1 1 1 1 1\n\
                   0 1 0 0 0 1 1 1 1 0 1\n2 0 0 0 0 1 1 1 1 0 0\n4 0 1 2 3\n3 1 4 2\n";
    let bom = "\u{feff}OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n4 0 1 2 3\n3 1 4 2\n";
    for text in [plain, same_line, coff, noff, stcnoff, bom] {
        let m = off::parse(text.as_bytes()).unwrap_or_else(|e| panic!("{text:?}: {e}"));
        assert_eq!(m.positions.len(), 5);
        assert_eq!(m.positions[2], Pt3::new(1.0, 1.0, 0.0));
        assert_eq!(rows(&m.faces), vec![vec![0, 1, 2, 3], vec![1, 4, 2]]);
        assert!(m.uv.is_none());
    }
}

#[test]
fn file_reader_triangulates() {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("io_off");
    std::fs::create_dir_all(&d).unwrap();
    let path = d.join("square.off");
    std::fs::write(&path, "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n").unwrap();
    assert_eq!(off::read(&path).unwrap().faces.len(), 1);
    let t = off::read_tri_with(&path, &ReadOptions::default()).unwrap();
    assert_eq!(t.faces, vec![[0, 1, 2], [0, 2, 3]]);
}

#[test]
fn malformed_files_name_the_line() {
    let cases: &[(&str, usize, &str)] = &[
        ("", 1, "empty file"),
        ("# only a comment\n", 1, "empty file"),
        ("PLY\n3 1 0\n", 1, "expected an OFF header"),
        ("4OFF\n3 1 0\n", 1, "only 3-D"),
        ("OFF BINARY\n3 1 0\n", 1, "binary OFF"),
        ("OFF\n", 1, "file ends before the vertex/face counts"),
        ("OFF\n3\n", 2, "expected 'n_vertices n_faces"),
        ("OFF\n3 x 0\n", 2, "bad face count 'x'"),
        ("OFF\n-3 1 0\n", 2, "bad vertex count '-3'"),
        ("OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n", 4, "vertex 1 has 2 numbers"),
        ("OFF\n3 1 0\n0 0 0\n1 0 q\n0 1 0\n3 0 1 2\n", 4, "bad number 'q'"),
        ("OFF\n3 1 0\n0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n", 4, "bad number 'inf'"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n", 4, "file ends at vertex 2 of 3"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n", 5, "file ends at face 0 of 1"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", 6, "vertex index 3 out of range"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", 6, "bad vertex index '-1'"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", 6, "face 0 has 2 vertices"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", 6, "declares 4 vertices but lists 3"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n18446744073709551615 0 1 2\n", 6, "declares"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", 7, "data after the last face"),
    ];
    for &(text, line, what) in cases {
        let (l, msg) = parse_err(text);
        assert_eq!(l, line, "{text:?}: {msg}");
        assert!(msg.contains(what), "{text:?}: {msg}");
    }
}

#[test]
fn huge_declared_counts_fail_without_allocating() {
    let text = "OFF\n18446744073709551615 18446744073709551615 0\n0 0 0\n";
    assert!(off::parse(text.as_bytes()).is_err());
    let text = "OFF\n3 18446744073709551615 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    assert!(off::parse(text.as_bytes()).is_err());
}
