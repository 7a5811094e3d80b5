//! OBJ reader and writer: messy real-world text, malformed input with line numbers, exact
//! write/read round trips, UV handling and file-level behaviour.

use geom_core::graph::Ragged;
use geom_core::io::{obj, MeshOut, ReadOptions};
use geom_core::math::{Pt2, Pt3, Vec3};
use geom_core::mesh::Uv;
use geom_core::Error;

fn rows(f: &Ragged<u32>) -> Vec<Vec<u32>> {
    f.rows().map(|r| r.to_vec()).collect()
}

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("io_obj");
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// The line and message of an OBJ parse error (panics on anything else: a test failure).
fn parse_err(text: &str) -> (usize, String) {
    match obj::read_str(text) {
        Err(Error::Parse { format: "OBJ", line, msg }) => {
            assert!(!msg.is_empty());
            (line, msg)
        }
        other => panic!("expected an OBJ parse error for {text:?}, got {other:?}"),
    }
}

// ---------------------------------------------------------------------------------------------
// Messy but valid files

#[test]
fn crlf_tabs_comments_and_no_final_newline() {
    let text = "# a unit square\r\n\r\nv 0 0 0\r\nv\t1  0\t0   # trailing comment\r\nv 1 1 0\r\nv 0 1 0\r\n  f 1 2 3 4";
    let m = obj::read_str(text).unwrap();
    assert_eq!(m.positions.len(), 4);
    assert_eq!(m.positions[1], Pt3::new(1.0, 0.0, 0.0));
    assert_eq!(rows(&m.faces), vec![vec![0, 1, 2, 3]]);
    assert!(m.uv.is_none());
    let t = obj::read_tri_str(text, &ReadOptions::default()).unwrap();
    assert_eq!(t.faces, vec![[0, 1, 2], [0, 2, 3]]);
}

#[test]
fn negative_indices_are_relative_to_what_is_defined_so_far() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 1 1 0\nf -3 -1 -2\n";
    let m = obj::read_str(text).unwrap();
    assert_eq!(rows(&m.faces), vec![vec![0, 1, 2], vec![1, 3, 2]]);
}

#[test]
fn quads_and_pentagons_are_fan_triangulated() {
    let text = "v 0 0 0\nv 1 0 0\nv 2 0.5 0\nv 1 1 0\nv 0 1 0\nv 3 0 0\nf 1 2 3 4 5\nf 2 6 3\n";
    let m = obj::read_str(text).unwrap();
    assert_eq!(rows(&m.faces), vec![vec![0, 1, 2, 3, 4], vec![1, 5, 2]]);
    let t = obj::read_tri_str(text, &ReadOptions::default()).unwrap();
    assert_eq!(t.faces, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [1, 5, 2]]);
}

#[test]
fn all_corner_forms_with_texture_and_normal_indices() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nvn 0 0 1\n\
                f 1/1/1 2/2/1 3/3/1\nf 2/2 4/4 3/3\n";
    let d = obj::parse(text.as_bytes()).unwrap();
    assert_eq!(d.texcoords.len(), 4);
    assert_eq!(d.normals, vec![Vec3::new(0.0, 0.0, 1.0)]);
    assert_eq!(d.corner_texcoord.as_deref(), Some(&[0, 1, 2, 1, 3, 2][..]));
    assert_eq!(d.corner_normal.as_deref(), Some(&[0, 0, 0, u32::MAX, u32::MAX, u32::MAX][..]));
    // One consistent vt per vertex: per-vertex UVs.
    let m = obj::read_str(text).unwrap();
    assert_eq!(m.uv.unwrap()[3], Pt2::new(1.0, 1.0));
    let t = obj::read_tri_str(text, &ReadOptions::default()).unwrap();
    assert!(matches!(t.uv, Some(Uv::PerVertex(ref v)) if v[1] == Pt2::new(1.0, 0.0)));

    let normals_only = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n";
    let d = obj::parse(normals_only.as_bytes()).unwrap();
    assert!(d.corner_texcoord.is_none());
    assert_eq!(d.corner_normal.as_deref(), Some(&[0, 0, 0][..]));
}

#[test]
fn uv_seams_give_per_corner_uvs_and_partial_uvs_give_none() {
    // Vertex 2 (1-based 3) has vt 3 in the first face and vt 4 in the second: a seam.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 0.5 0.5\nvt 1 1\n\
                f 1/1 2/2 3/3\nf 2/2 4/5 3/4\n";
    let m = obj::read_str(text).unwrap();
    assert!(m.uv.is_none(), "a polygon mesh has no per-corner UVs");
    let t = obj::read_tri_str(text, &ReadOptions::default()).unwrap();
    match t.uv {
        Some(Uv::PerCorner(c)) => {
            assert_eq!(c.len(), 2);
            assert_eq!(c[0][2], Pt2::new(0.0, 1.0));
            assert_eq!(c[1][2], Pt2::new(0.5, 0.5));
            assert_eq!(c[1][1], Pt2::new(1.0, 1.0));
        }
        other => panic!("expected per-corner UVs, got {other:?}"),
    }
    // Seam inside a quad: per-corner UVs follow the fan triangles.
    let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 9 9\n\
                f 1/1 2/2 3/3 4/4\nf 4/5 3/3 5/1\nv 0 2 0\n";
    let t = obj::read_tri_str(quad, &ReadOptions::default()).unwrap();
    match t.uv {
        Some(Uv::PerCorner(c)) => {
            assert_eq!(t.faces[1], [0, 2, 3]);
            assert_eq!(c[1], [Pt2::new(0.0, 0.0), Pt2::new(1.0, 1.0), Pt2::new(0.0, 1.0)]);
            assert_eq!(c[2][0], Pt2::new(9.0, 9.0));
        }
        other => panic!("expected per-corner UVs, got {other:?}"),
    }
    // Only some corners have a vt: no mesh UVs, but ObjData keeps them.
    let partial = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2 3\n";
    let d = obj::parse(partial.as_bytes()).unwrap();
    assert_eq!(d.corner_texcoord.as_deref(), Some(&[0, u32::MAX, u32::MAX][..]));
    assert!(d.corner_uv().is_none());
    assert!(obj::read_tri_str(partial, &ReadOptions::default()).unwrap().uv.is_none());
}

#[test]
fn several_objects_groups_and_ignored_statements_merge_into_one_mesh() {
    let text = "mtllib scene.mtl\no first\ng body\nusemtl red\ns 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\
                o second\ng arm leg\nusemtl blue\ns off\nv 5 0 0\nv 6 0 0\nv 5 1 0\nf -3 -2 -1\n\
                l 1 2 3\np 4\nvp 0.5 0.5\ncstype bspline\ndeg 3\ncurv 0 1 1 2 3 4\nparm u 0 0 0 0 1 1 1 1\nend\n\
                mg 1 0.5\nlod 1\nbevel off\nc_interp off\nd_interp off\nshadow_obj s.obj\ntrace_obj t.obj\n";
    let m = obj::read_str(text).unwrap();
    assert_eq!(m.positions.len(), 6);
    assert_eq!(rows(&m.faces), vec![vec![0, 1, 2], vec![3, 4, 5]]);
}

#[test]
fn vertex_weights_colours_continuations_and_forward_references() {
    let text = "f 1 2 \\\n   3 4\nv 0 0 0 1\nv 1 0 0 0.25 0.5 0.75\nv 1 1 0 1 0.25 0.5 0.75\nv 0 1 \\\n 0\n\
                vt 0.5\nvt 0.25 0.75 0\n";
    let d = obj::parse(text.as_bytes()).unwrap();
    assert_eq!(d.positions.len(), 4);
    assert_eq!(d.positions[3], Pt3::new(0.0, 1.0, 0.0));
    assert_eq!(d.texcoords, vec![Pt2::new(0.5, 0.0), Pt2::new(0.25, 0.75)]);
    assert_eq!(rows(&d.faces), vec![vec![0, 1, 2, 3]]);
}

#[test]
fn latin1_comments_and_names_do_not_break_parsing() {
    let mut bytes = b"# caf\xe9\no \xe9t\xe9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\xe9tal\nf 1 2 3\n".to_vec();
    bytes.extend_from_slice(b"# end");
    let d = obj::parse(&bytes).unwrap();
    assert_eq!(d.faces.len(), 1);
    // A UTF-8 byte-order mark before the first statement.
    let m = obj::read_str("\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert_eq!(m.positions.len(), 3);
}

#[test]
fn fixture_file_loads() {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/io/messy_cube.obj");
    let m = obj::read(&p).unwrap();
    assert_eq!(m.positions.len(), 8);
    assert_eq!(m.faces.len(), 6);
    let t = obj::read_tri(&p).unwrap();
    assert_eq!(t.n_faces(), 12);
    assert!(t.topology().is_closed());
}

// ---------------------------------------------------------------------------------------------
// Malformed input: each error names the line

#[test]
fn malformed_statements_name_their_line() {
    let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let cases: &[(&str, usize, &str)] = &[
        ("v 0 0 0\nv 1 2 x\n", 2, "bad number 'x'"),
        ("v 0 0 0\nv 1 2 nan\n", 2, "non-finite"),
        ("v 1 2\n", 1, "'v' needs"),
        ("v 1 2 3 4 5\n", 1, "got 5"),
        ("vn 1 2\n", 1, "'vn' needs 3"),
        ("vt\n", 1, "'vt' needs 1 to 3"),
        ("vt 1 2 3 4\n", 1, "'vt' needs 1 to 3"),
        ("foo 1 2\n", 1, "unknown statement 'foo'"),
    ];
    for &(text, line, what) in cases {
        let (l, msg) = parse_err(text);
        assert_eq!(l, line, "{text:?}: {msg}");
        assert!(msg.contains(what), "{text:?}: {msg}");
    }
    let face_cases: &[(&str, usize, &str)] = &[
        ("f 0 1 2\n", 4, "index 0"),
        ("f 1 2 9\n", 4, "vertex index 9 out of range"),
        ("# c\nf 1 2 3\nf 1 2 4\n", 6, "vertex index 4 out of range"),
        ("f -4 -2 -1\n", 4, "relative vertex index -4"),
        ("f 1 2\n", 4, "face has 2 vertices"),
        ("f 1\n", 4, "face has 1 vertices"),
        ("f 1/a 2 3\n", 4, "bad texture coordinate index 'a'"),
        ("f 1/1/1/1 2 3\n", 4, "more than 3"),
        ("f /1 2 3\n", 4, "no vertex index"),
        ("f 1/2 2/2 3/2\n", 4, "texture coordinate index 2 out of range"),
        ("f 1//7 2 3\n", 4, "normal index 7 out of range"),
        ("f 1 2 \\\n 99\n", 4, "vertex index 99 out of range"),
        ("f 1 2 3.5\n", 4, "bad vertex index '3.5'"),
        ("f 1 2 99999999999\n", 4, "out of range"),
    ];
    for &(tail, line, what) in face_cases {
        let text = format!("{head}{tail}");
        let (l, msg) = parse_err(&text);
        assert_eq!(l, line, "{text:?}: {msg}");
        assert!(msg.contains(what), "{text:?}: {msg}");
    }
}

#[test]
fn strict_triangle_validation_errors_pass_through() {
    // A fan over a polygon that repeats a vertex is refused by TriMesh::new, not repaired.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2\n";
    assert!(obj::read_str(text).is_ok());
    assert!(matches!(obj::read_tri_str(text, &ReadOptions::default()), Err(Error::IndexOutOfRange { face: 0, .. })));
}

// ---------------------------------------------------------------------------------------------
// Writer and round trips

fn awkward_positions() -> Vec<Pt3> {
    vec![
        Pt3::new(0.0, -0.0, 1.0 / 3.0),
        Pt3::new(1e-300, -2.5e-7, 123456789.12345679),
        Pt3::new(0.1, 0.2, 0.30000000000000004),
        Pt3::new(-1e20, 5e-324, std::f64::consts::PI),
        Pt3::new(1.0, 1.0, 1.0),
    ]
}

fn same_bits(a: &[Pt3], b: &[Pt3]) {
    assert_eq!(a.len(), b.len());
    for (p, q) in a.iter().zip(b) {
        for k in 0..3 {
            assert_eq!(p[k].to_bits(), q[k].to_bits(), "{p:?} vs {q:?}");
        }
    }
}

#[test]
fn triangles_round_trip_exactly() {
    let p = awkward_positions();
    let f = vec![[0u32, 1, 2], [2, 3, 4]];
    let text = obj::to_string(&MeshOut::tri(&p, &f)).unwrap();
    let d = obj::parse(text.as_bytes()).unwrap();
    same_bits(&p, &d.positions);
    assert_eq!(rows(&d.faces), vec![vec![0, 1, 2], vec![2, 3, 4]]);
}

#[test]
fn polygons_uvs_and_normals_round_trip() {
    let p = awkward_positions();
    let f = Ragged::from_rows([vec![0u32, 1, 2, 3], vec![3, 4, 0]]);
    let uv = Uv::PerVertex((0..5).map(|i| Pt2::new(i as f64 / 7.0, 1.0 - i as f64 / 3.0)).collect());
    let n: Vec<Vec3> = (0..5).map(|i| Vec3::new(0.0, (i as f64).sin(), (i as f64).cos())).collect();
    let text = obj::to_string(&MeshOut::poly(&p, &f).with_uv(&uv).with_normals(&n)).unwrap();
    let d = obj::parse(text.as_bytes()).unwrap();
    same_bits(&p, &d.positions);
    assert_eq!(d.faces, f);
    assert_eq!(Some(Uv::PerVertex(d.vertex_uv().unwrap())), Some(uv));
    assert_eq!(d.normals, n);
    assert_eq!(d.corner_normal.unwrap(), f.items);
}

#[test]
fn per_corner_uvs_round_trip_through_a_file() {
    let p = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(1.0, 1.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
    let f = vec![[0u32, 1, 2], [0, 2, 3]];
    let uv = Uv::PerCorner(vec![
        [Pt2::new(0.0, 0.0), Pt2::new(1.0, 0.0), Pt2::new(1.0, 1.0)],
        [Pt2::new(5.0, 5.0), Pt2::new(1.0, 1.0), Pt2::new(0.0, 1.0)],
    ]);
    let path = tmp("corner_uv.obj");
    obj::write(&path, &MeshOut::tri(&p, &f).with_uv(&uv)).unwrap();
    let t = obj::read_tri(&path).unwrap();
    assert_eq!(t.positions, p);
    assert_eq!(t.faces, f);
    assert_eq!(t.uv, Some(uv));
}

#[test]
fn f32_positions_read_back_as_their_exact_f64_value() {
    let p = vec![[0.1f32, -3.4e38, 1.4e-45], [7.0, 1e-6, 0.3], [1.0, 2.0, 3.0]];
    let f = vec![[0u32, 1, 2]];
    let d = obj::parse(obj::to_string(&MeshOut::tri_f32(&p, &f)).unwrap().as_bytes()).unwrap();
    for (a, b) in p.iter().zip(&d.positions) {
        for k in 0..3 {
            assert_eq!(a[k] as f64, b[k]);
            assert_eq!((b[k] as f32).to_bits(), a[k].to_bits());
        }
    }
}

#[test]
fn writer_refuses_what_the_reader_would_refuse() {
    let p = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
    assert!(matches!(
        obj::to_string(&MeshOut::tri(&p, &[[0, 1, 3]])),
        Err(Error::IndexOutOfRange { face: 0, vertex: 3 })
    ));
    let bad = vec![Pt3::new(0.0, f64::NAN, 0.0)];
    assert!(matches!(obj::to_string(&MeshOut::tri(&bad, &[])), Err(Error::NonFiniteVertex { vertex: 0 })));
    let uv = Uv::PerVertex(vec![Pt2::origin(); 2]);
    assert!(matches!(
        obj::to_string(&MeshOut::tri(&p, &[[0, 1, 2]]).with_uv(&uv)),
        Err(Error::DimensionMismatch { .. })
    ));
    let short = Ragged::from_rows([vec![0u32, 1]]);
    assert!(matches!(obj::to_string(&MeshOut::poly(&p, &short)), Err(Error::InvalidParameter(_))));
    let corner = Uv::PerCorner(vec![[Pt2::origin(); 3]]);
    let quad = Ragged::from_rows([vec![0u32, 1, 2]]);
    assert!(matches!(obj::to_string(&MeshOut::poly(&p, &quad).with_uv(&corner)), Err(Error::InvalidParameter(_))));
}

#[test]
fn file_errors_name_the_path() {
    let missing = tmp("does_not_exist.obj");
    let _ = std::fs::remove_file(&missing);
    match obj::read(&missing) {
        Err(Error::Io(e)) => {
            assert_eq!(e.kind(), std::io::ErrorKind::NotFound);
            assert!(e.to_string().contains("does_not_exist.obj"), "{e}");
        }
        other => panic!("expected an I/O error, got {other:?}"),
    }
    let bad = tmp("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 x 0\n").unwrap();
    match obj::read(&bad) {
        Err(Error::Parse { line: 2, msg, .. }) => assert!(msg.contains("bad.obj"), "{msg}"),
        other => panic!("expected a parse error, got {other:?}"),
    }
    let p = vec![Pt3::origin()];
    let in_missing_dir = tmp("no/such/dir/x.obj");
    match obj::write(&in_missing_dir, &MeshOut::tri(&p, &[])) {
        Err(Error::Io(e)) => assert!(e.to_string().contains("no/such/dir"), "{e}"),
        other => panic!("expected an I/O error, got {other:?}"),
    }
}
