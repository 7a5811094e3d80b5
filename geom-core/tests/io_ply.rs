//! PLY reader and writer: every encoding and scalar type, named properties, unknown elements,
//! exact round trips, and malformed headers/bodies with line or byte positions.

use geom_core::graph::Ragged;
use geom_core::io::ply::{self, Encoding, PlyData};
use geom_core::io::{MeshOut, Positions, ReadOptions};
use geom_core::math::{Pt2, Pt3, Vec3};
use geom_core::mesh::Uv;
use geom_core::Error;

const ENCODINGS: [Encoding; 3] = [Encoding::Ascii, Encoding::BinaryLittleEndian, Encoding::BinaryBigEndian];

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("io_ply");
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn rows(f: &Ragged<u32>) -> Vec<Vec<u32>> {
    f.rows().map(|r| r.to_vec()).collect()
}

/// The line and message of a PLY parse error.
fn parse_err(data: &[u8]) -> (usize, String) {
    match ply::read_bytes(data) {
        Err(Error::Parse { format: "PLY", line, msg }) => {
            assert!(!msg.is_empty());
            (line, msg)
        }
        other => panic!("expected a PLY parse error for {:?}, got {other:?}", String::from_utf8_lossy(data)),
    }
}

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

// ---------------------------------------------------------------------------------------------
// Round trips

#[test]
fn mesh_with_properties_round_trips_exactly_in_every_encoding() {
    let p = awkward_positions();
    let f = Ragged::from_rows([vec![0u32, 1, 2, 3], vec![3, 4, 0], vec![1, 2, 4, 3, 0]]);
    let n: Vec<Vec3> = (0..5).map(|i| Vec3::new((i as f64).cos(), (i as f64).sin(), 0.0)).collect();
    let uv = Uv::PerVertex((0..5).map(|i| Pt2::new(i as f64 / 3.0, 0.1 * i as f64)).collect());
    let heat: Vec<f64> = (0..5).map(|i| (i as f64).exp() / 7.0).collect();
    let vel: Vec<Vec3> = (0..5).map(|i| Vec3::new(i as f64, -1.0 / (i as f64 + 1.0), 1e-9)).collect();
    let col: Vec<[u8; 3]> = (0..5).map(|i| [i * 50, 255 - i * 3, 7]).collect();
    let props = [("heat", PlyData::F64(&heat)), ("vel", PlyData::Vec3(&vel)), ("color", PlyData::Rgb(&col))];
    for enc in ENCODINGS {
        let m = MeshOut::poly(&p, &f).with_normals(&n).with_uv(&uv);
        let bytes = ply::to_bytes(&m, &props, enc).unwrap();
        let d = ply::read_bytes(&bytes).unwrap();
        same_bits(&p, &d.positions);
        assert_eq!(d.faces, f, "{enc:?}");
        let names: Vec<&str> = d.props.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(
            names,
            ["nx", "ny", "nz", "u", "v", "heat", "vel_x", "vel_y", "vel_z", "red", "green", "blue"],
            "{enc:?}"
        );
        assert_eq!(d.prop("heat").unwrap(), &heat[..]);
        assert_eq!(d.prop("vel_y").unwrap(), &vel.iter().map(|v| v.y).collect::<Vec<_>>()[..]);
        assert_eq!(d.prop("green").unwrap(), &col.iter().map(|c| c[1] as f64).collect::<Vec<_>>()[..]);
        assert_eq!(d.prop("nx").unwrap(), &n.iter().map(|v| v.x).collect::<Vec<_>>()[..]);
        assert_eq!(Uv::PerVertex(d.vertex_uv().unwrap()), uv);
        let poly = d.to_poly();
        assert_eq!(rows(&poly.faces)[2], vec![1, 2, 4, 3, 0]);
    }
}

#[test]
fn files_round_trip_as_validated_triangle_meshes() {
    let p = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(1.0, 1.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
    let f = vec![[0u32, 1, 2], [0, 2, 3]];
    let uv = Uv::PerCorner(vec![
        [Pt2::new(0.0, 0.0), Pt2::new(1.0, 0.0), Pt2::new(1.0, 1.0)],
        [Pt2::new(0.25, 0.0), Pt2::new(1.0, 1.0), Pt2::new(0.0, 1.0)],
    ]);
    let w = [0.5, 1.5, 2.5, 3.5];
    for (k, enc) in ENCODINGS.into_iter().enumerate() {
        let path = tmp(&format!("quad_{k}.ply"));
        ply::write(&path, &MeshOut::tri(&p, &f).with_uv(&uv), &[("w", PlyData::F64(&w))], enc).unwrap();
        let (t, props) = ply::read(&path).unwrap();
        assert_eq!(t.positions, p);
        assert_eq!(t.faces, f);
        assert_eq!(t.uv.as_ref(), Some(&uv), "{enc:?}");
        assert_eq!(props, vec![("w".to_string(), w.to_vec())]);
        let (poly, _) = ply::read_poly(&path).unwrap();
        assert!(poly.uv.is_none(), "seam: no per-vertex UVs");
    }
}

#[test]
fn f32_positions_round_trip_exactly_in_ascii_and_binary() {
    let p = vec![[0.1f32, -3.4e38, 1.4e-45], [7.0, 1e-6, 0.3], [1.0, 2.0, 3.0]];
    let f = vec![[0u32, 1, 2]];
    for enc in ENCODINGS {
        let bytes = ply::to_bytes(&MeshOut::tri_f32(&p, &f), &[], enc).unwrap();
        let d = ply::read_bytes(&bytes).unwrap();
        for (a, b) in p.iter().zip(&d.positions) {
            for k in 0..3 {
                assert_eq!(a[k] as f64, b[k], "{enc:?}");
            }
        }
    }
}

#[test]
fn point_sets_with_attributes() {
    let p: Vec<Pt3> = (0..10).map(|i| Pt3::new(i as f64 * 0.1, (i * i) as f64, -(i as f64))).collect();
    let r: Vec<f64> = (0..10).map(|i| 0.01 * i as f64).collect();
    let v: Vec<Vec3> = (0..10).map(|i| Vec3::new(1.0, i as f64, 0.5)).collect();
    for (k, enc) in ENCODINGS.into_iter().enumerate() {
        let path = tmp(&format!("points_{k}.ply"));
        ply::write_points(&path, Positions::F64(&p), &[("r", PlyData::F64(&r)), ("v", PlyData::Vec3(&v))], enc)
            .unwrap();
        let d = ply::read_data(&path).unwrap();
        assert_eq!(d.positions, p);
        assert!(d.faces.is_empty());
        assert_eq!(d.prop("r").unwrap(), &r[..]);
        assert_eq!(d.prop("v_z").unwrap(), &[0.5; 10][..]);
        assert!(d.comments.iter().any(|c| c.contains("geom-core")));
        // A point set is also a (face-less) triangle mesh.
        let (t, _) = ply::read(&path).unwrap();
        assert_eq!(t.n_faces(), 0);
    }
}

#[test]
fn writer_validates_properties() {
    let p = vec![Pt3::origin(); 3];
    let one = [1.0];
    assert!(matches!(
        ply::points_to_bytes(Positions::F64(&p), &[("a", PlyData::F64(&one))], Encoding::Ascii),
        Err(Error::DimensionMismatch { expected: 3, got: 1, .. })
    ));
    let three = [1.0, 2.0, 3.0];
    for bad in ["", "has space", "x"] {
        assert!(
            matches!(
                ply::points_to_bytes(Positions::F64(&p), &[(bad, PlyData::F64(&three))], Encoding::Ascii),
                Err(Error::InvalidParameter(_))
            ),
            "{bad:?}"
        );
    }
    let nan = [1.0, f64::NAN, 3.0];
    assert!(ply::points_to_bytes(Positions::F64(&p), &[("a", PlyData::F64(&nan))], Encoding::Ascii).is_err());
    let inf = vec![Pt3::new(f64::INFINITY, 0.0, 0.0)];
    assert!(matches!(
        ply::points_to_bytes(Positions::F64(&inf), &[], Encoding::BinaryLittleEndian),
        Err(Error::NonFiniteVertex { vertex: 0 })
    ));
}

// ---------------------------------------------------------------------------------------------
// Files written by other tools

#[test]
fn ascii_with_every_type_name_unknown_elements_and_crlf() {
    let text = "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nobj_info scanner 3\r\n\
        element vertex 4\r\nproperty float32 x\r\nproperty double y\r\nproperty int16 z\r\n\
        property uchar red\r\nproperty char c\r\nproperty ushort us\r\nproperty uint32 ui\r\nproperty int8 i8\r\n\
        property list uchar int junk\r\n\
        element edge 2\r\nproperty int vertex1\r\nproperty int vertex2\r\n\
        element face 2\r\nproperty uint8 flags\r\nproperty list uint8 uint32 vertex_index\r\nproperty float quality\r\n\
        element material 1\r\nproperty list int float ks\r\n\
        end_header\r\n\
        0.5 0 0 255 -128 65535 4294967295 127 2 9 9\r\n\
        1 0 0 0 0 0 0 0 0\r\n\
        \r\n\
        1 1.25e0 0 1 1 1 1 1 1 7\r\n0 1 -3 2 2 2 2 2 0\r\n\
        0 1\r\n1 2\r\n\
        1 3 0 1 2 0.5\r\n0 3 0 2 3 1e3\r\n\
        3 0.1 0.2 0.3\r\n";
    let d = ply::read_bytes(text.as_bytes()).unwrap();
    assert_eq!(
        d.positions,
        vec![Pt3::new(0.5, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(1.0, 1.25, 0.0), Pt3::new(0.0, 1.0, -3.0)]
    );
    assert_eq!(rows(&d.faces), vec![vec![0, 1, 2], vec![0, 2, 3]]);
    assert_eq!(d.prop("red").unwrap(), &[255.0, 0.0, 1.0, 2.0]);
    assert_eq!(d.prop("c").unwrap(), &[-128.0, 0.0, 1.0, 2.0]);
    assert_eq!(d.prop("ui").unwrap()[0], 4294967295.0);
    assert_eq!(d.comments, vec!["made by hand".to_string()]);
    assert_eq!(d.obj_info, vec!["scanner 3".to_string()]);
    assert!(d.prop("junk").is_none(), "list properties are not returned");
}

/// Big-endian or little-endian byte writer for hand-made binary files.
struct Bytes {
    v: Vec<u8>,
    big: bool,
}

impl Bytes {
    fn new(header: &str, big: bool) -> Self {
        Self { v: header.as_bytes().to_vec(), big }
    }
    fn put<const N: usize>(&mut self, le: [u8; N]) -> &mut Self {
        let mut b = le;
        if self.big {
            b.reverse();
        }
        self.v.extend_from_slice(&b);
        self
    }
    fn f32(&mut self, x: f32) -> &mut Self {
        self.put(x.to_le_bytes())
    }
    fn f64(&mut self, x: f64) -> &mut Self {
        self.put(x.to_le_bytes())
    }
    fn i16(&mut self, x: i16) -> &mut Self {
        self.put(x.to_le_bytes())
    }
    fn u16(&mut self, x: u16) -> &mut Self {
        self.put(x.to_le_bytes())
    }
    fn i32(&mut self, x: i32) -> &mut Self {
        self.put(x.to_le_bytes())
    }
    fn u32(&mut self, x: u32) -> &mut Self {
        self.put(x.to_le_bytes())
    }
    fn u8(&mut self, x: u8) -> &mut Self {
        self.v.push(x);
        self
    }
}

const BIN_HEADER: &str = "element vertex 3\nproperty float x\nproperty double y\nproperty short z\n\
    property uint id\nproperty list uchar float junk\n\
    element fixed 2\nproperty int a\nproperty uchar b\n\
    element face 2\nproperty list ushort int vertex_indices\nproperty char flag\n\
    element tail 1\nproperty list int short data\nend_header\n";

fn binary_file(big: bool) -> Vec<u8> {
    let fmt = if big { "binary_big_endian" } else { "binary_little_endian" };
    let mut b = Bytes::new(&format!("ply\nformat {fmt} 1.0\ncomment hand made\n{BIN_HEADER}"), big);
    // vertices: x (f32), y (f64), z (i16), id (u32), junk list
    b.f32(0.5).f64(0.0).i16(0).u32(10).u8(2).f32(1.0).f32(2.0);
    b.f32(1.0).f64(0.0).i16(-2).u32(11).u8(0);
    b.f32(0.0).f64(1.0 / 3.0).i16(3).u32(4_000_000_000).u8(1).f32(9.0);
    // fixed element, 5 bytes each
    b.i32(-1).u8(1).i32(7).u8(2);
    // faces: a quad, then a triangle; char flag after
    b.u16(4).i32(0).i32(1).i32(2).i32(0).u8(0xff);
    b.u16(3).i32(2).i32(1).i32(0).u8(1);
    // tail: list of shorts
    b.i32(3).i16(1).i16(2).i16(3);
    b.v
}

#[test]
fn binary_both_endians_with_unknown_elements_and_lists() {
    for big in [false, true] {
        let d = ply::read_bytes(&binary_file(big)).unwrap();
        assert_eq!(d.positions, vec![Pt3::new(0.5, 0.0, 0.0), Pt3::new(1.0, 0.0, -2.0), Pt3::new(0.0, 1.0 / 3.0, 3.0)]);
        assert_eq!(rows(&d.faces), vec![vec![0, 1, 2, 0], vec![2, 1, 0]]);
        assert_eq!(d.prop("id").unwrap(), &[10.0, 11.0, 4e9]);
        // A trailing newline after a binary body is tolerated.
        let mut nl = binary_file(big);
        nl.push(b'\n');
        assert!(ply::read_bytes(&nl).is_ok());
    }
}

#[test]
fn fixture_file_in_big_endian_loads() {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/io/tetra_be.ply");
    let (t, props) = ply::read(&p).unwrap();
    assert_eq!(t.n_vertices(), 4);
    assert_eq!(t.n_faces(), 4);
    assert!(t.topology().is_closed());
    assert_eq!(props.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(), ["confidence"]);
    assert_eq!(props[0].1, vec![0.25, 0.5, 0.75, 1.0]);
}

// ---------------------------------------------------------------------------------------------
// Malformed files

#[test]
fn header_errors_name_the_line() {
    let cases: &[(&str, usize, &str)] = &[
        ("plyx\nformat ascii 1.0\nend_header\n", 1, "first line must be 'ply'"),
        ("", 1, "first line must be 'ply'"),
        ("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", 4, "no 'end_header'"),
        ("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x", 4, "no 'end_header'"),
        ("ply\nformat utf8 1.0\nend_header\n", 2, "unknown format 'utf8'"),
        ("ply\nformat ascii 2.0\nend_header\n", 2, "version"),
        ("ply\nformat ascii 1.0\nproperty float x\nend_header\n", 3, "before any 'element'"),
        ("ply\nformat ascii 1.0\nelement vertex 1\nproperty half x\nend_header\n", 4, "unknown property type 'half'"),
        ("ply\nformat ascii 1.0\nelement vertex -1\nend_header\n", 3, "bad element count '-1'"),
        ("ply\nformat ascii 1.0\nelement vertex\nend_header\n", 3, "needs a name and a count"),
        ("ply\nformat ascii 1.0\nelement face 1\nproperty list float int vertex_indices\nend_header\n", 4, "integer"),
        ("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float x\nend_header\n", 5, "twice"),
        ("ply\nelement vertex 0\nend_header\n", 3, "no 'format'"),
        ("ply\nformat ascii 1.0\nbogus line\nend_header\n", 3, "unknown header keyword 'bogus'"),
    ];
    for &(text, line, what) in cases {
        let (l, msg) = parse_err(text.as_bytes());
        assert_eq!(l, line, "{text:?}: {msg}");
        assert!(msg.contains(what), "{text:?}: {msg}");
    }
}

const ASCII_HEAD: &str =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
    element face 1\nproperty list uchar int vertex_indices\nend_header\n";

#[test]
fn ascii_body_errors_name_the_line() {
    // Body lines start at line 10; "file ends" errors name the last line of the file.
    let cases: &[(&str, usize, &str)] = &[
        ("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 0, ""),
        ("0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", 11, "bad float 'x'"),
        ("0 0 0\n1 0\n0 1 0\n3 0 1 2\n", 11, "property 'z' is missing"),
        ("0 0 0\n1 0 0 5\n0 1 0\n3 0 1 2\n", 11, "more values"),
        ("0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", 13, "refers to vertex 3"),
        ("0 0 0\n1 0 0\n0 1 0\n2 0 1\n", 13, "2 vertices"),
        ("0 0 0\n1 0 0\n0 1 0\n3 0 1\n", 13, "property 'vertex_indices' is missing"),
        ("0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", 13, "vertex index -1"),
        ("0 0 0\n1 0 0\n0 1 0\n256 0 1 2\n", 13, "256 is out of range for uchar"),
        ("0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n", 13, "bad int '1.5'"),
        // Wrong counts: too few lines, too many lines.
        ("0 0 0\n1 0 0\n0 1 0\n", 12, "file ends before element 'face' #0"),
        ("0 0 0\n1 0 0\n", 11, "file ends before element 'vertex' #2"),
        ("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", 14, "data after the last element"),
    ];
    for &(body, line, what) in cases {
        let text = format!("{ASCII_HEAD}{body}");
        if what.is_empty() {
            assert!(ply::read_bytes(text.as_bytes()).is_ok());
            continue;
        }
        let (l, msg) = parse_err(text.as_bytes());
        assert_eq!(l, line, "{body:?}: {msg}");
        assert!(msg.contains(what), "{body:?}: {msg}");
    }
}

#[test]
fn truncated_binary_names_element_and_byte_offset() {
    let full = binary_file(false);
    let header_len = full.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    // Cut inside vertex #1's y (vertex #0 is 4+8+2+4+1+8 = 27 bytes; #1's x is 4 more).
    let cut = header_len + 27 + 4 + 3;
    let (line, msg) = parse_err(&full[..cut]);
    assert_eq!(line, 0);
    assert!(msg.contains("element 'vertex' #1"), "{msg}");
    assert!(msg.contains("property 'y'"), "{msg}");
    assert!(msg.contains(&format!("byte offset {}", header_len + 31)), "{msg}");
    // Cut inside the fixed-size element (after 27 + 19 + 23 vertex bytes and one 5-byte
    // instance): skipped in one step, still located.
    let (_, msg) = parse_err(&full[..header_len + 69 + 5 + 2]);
    assert!(msg.contains("element 'fixed' #1"), "{msg}");
    // Every truncation of the body is an error, never a panic.
    for cut in header_len..full.len() {
        assert!(ply::read_bytes(&full[..cut]).is_err(), "cut at {cut}");
    }
    // Trailing garbage (a count too small) is an error too.
    let mut more = full.clone();
    more.extend_from_slice(&[1, 2, 3]);
    let (_, msg) = parse_err(&more);
    assert!(msg.contains("3 bytes after the last element"), "{msg}");
}

#[test]
fn huge_declared_counts_do_not_allocate() {
    for fmt in ["ascii", "binary_little_endian"] {
        let text = format!(
            "ply\nformat {fmt} 1.0\nelement vertex 4000000000\nproperty double x\nproperty double y\nproperty double z\n\
             element face 4000000000\nproperty list uint int vertex_indices\nend_header\n"
        );
        let mut data = text.into_bytes();
        data.extend_from_slice(&[0u8; 48]);
        assert!(ply::read_bytes(&data).is_err());
    }
    // A list claiming 4 billion entries.
    let mut b = Bytes::new(
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         element face 1\nproperty list uint int vertex_indices\nend_header\n",
        false,
    );
    for _ in 0..9 {
        b.f32(0.0);
    }
    b.u32(u32::MAX).i32(0).i32(1);
    let (_, msg) = parse_err(&b.v);
    assert!(msg.contains("element 'face' #0"), "{msg}");
    // More vertices than u32 indices can address.
    let text = "ply\nformat ascii 1.0\nelement vertex 5000000000\nproperty float x\nend_header\n";
    assert!(ply::read_bytes(text.as_bytes()).is_err());
}

#[test]
fn vertex_element_needs_xyz_and_face_element_needs_indices() {
    let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n";
    assert!(parse_err(text.as_bytes()).1.contains("'z'"));
    let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
                element face 1\nproperty list uchar int corners\nend_header\n0 0 0\n3 0 0 0\n";
    assert!(parse_err(text.as_bytes()).1.contains("vertex_indices"));
}

#[test]
fn triangle_reader_reports_invalid_meshes_and_welds_only_on_request() {
    // Two triangles of a square as a "soup" (six vertices).
    let p = vec![
        Pt3::new(0.0, 0.0, 0.0),
        Pt3::new(1.0, 0.0, 0.0),
        Pt3::new(1.0, 1.0, 0.0),
        Pt3::new(0.0, 0.0, 0.0),
        Pt3::new(1.0, 1.0, 0.0),
        Pt3::new(0.0, 1.0, 0.0),
    ];
    let f = vec![[0u32, 1, 2], [3, 4, 5]];
    let path = tmp("soup.ply");
    let id: Vec<f64> = (0..6).map(f64::from).collect();
    ply::write(&path, &MeshOut::tri(&p, &f), &[("id", PlyData::F64(&id))], Encoding::BinaryLittleEndian).unwrap();
    let (t, props) = ply::read(&path).unwrap();
    assert_eq!(t.n_vertices(), 6);
    assert_eq!(props[0].1.len(), 6);
    let (t, props) = ply::read_with(&path, &ReadOptions { weld: Some(1e-9) }).unwrap();
    assert_eq!(t.n_vertices(), 4);
    assert_eq!(t.topology().edges().len(), 5);
    // Properties follow the welded vertices (each takes its first file vertex's value).
    assert_eq!(props[0].1.len(), 4);
    for (v, q) in t.positions.iter().enumerate() {
        assert_eq!(p[props[0].1[v] as usize], *q);
    }
}
