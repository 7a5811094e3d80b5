//! Robustness of the mesh readers: random bytes, truncated valid files and randomly mutated
//! valid files, for OBJ, PLY (ASCII and both binary encodings) and OFF. The readers must return
//! `Ok` or an `Err` with a non-empty message, and never panic (proptest reports a panic as a
//! failing case) nor allocate by a declared count (a huge count would abort the test run).

use geom_core::graph::Ragged;
use geom_core::io::ply::{self, Encoding, PlyData};
use geom_core::io::{obj, off, MeshOut};
use geom_core::math::{Pt2, Pt3, Vec3};
use geom_core::mesh::Uv;
use geom_core::{Error, Result};
use proptest::prelude::*;

/// Checks the contract on one reader result.
fn check<T>(r: Result<T>) -> std::result::Result<(), TestCaseError> {
    if let Err(e) = r {
        prop_assert!(!e.to_string().is_empty());
        if let Error::Parse { msg, .. } = &e {
            prop_assert!(!msg.is_empty());
        }
    }
    Ok(())
}

fn all_readers(data: &[u8]) -> std::result::Result<(), TestCaseError> {
    check(obj::parse(data))?;
    check(ply::read_bytes(data))?;
    check(off::parse(data))?;
    Ok(())
}

/// Valid files of every format and encoding, with polygons, UVs, normals and properties.
fn seeds() -> Vec<Vec<u8>> {
    let p: Vec<Pt3> = (0..6).map(|i| Pt3::new(i as f64 * 0.3, (i * i) as f64 / 7.0, -1.0 / (i as f64 + 1.0))).collect();
    let f = Ragged::from_rows([vec![0u32, 1, 2, 3], vec![3, 4, 5], vec![5, 0, 3]]);
    let tris = vec![[0u32, 1, 2], [2, 3, 4], [4, 5, 0]];
    let uv = Uv::PerVertex((0..6).map(|i| Pt2::new(i as f64 / 5.0, 0.5)).collect());
    let corner = Uv::PerCorner(vec![[Pt2::new(0.0, 0.0), Pt2::new(1.0, 0.0), Pt2::new(0.0, 1.0)]; 3]);
    let n: Vec<Vec3> = (0..6).map(|i| Vec3::new(0.0, 0.0, if i % 2 == 0 { 1.0 } else { -1.0 })).collect();
    let w: Vec<f64> = (0..6).map(|i| i as f64 * 1.5).collect();
    let c: Vec<[u8; 3]> = (0..6).map(|i| [i as u8, 2, 3]).collect();
    let props = [("w", PlyData::F64(&w)), ("color", PlyData::Rgb(&c))];
    let mut out = vec![
        obj::to_string(&MeshOut::poly(&p, &f).with_uv(&uv).with_normals(&n)).unwrap().into_bytes(),
        obj::to_string(&MeshOut::tri(&p, &tris).with_uv(&corner)).unwrap().into_bytes(),
        b"# messy\r\no a\r\nv 0 0 0\r\nv 1 0 0 1\r\nv 1 1 0 0.5 0.5 0.5\r\nvt 0 0\r\nvn 0 0 1\r\n\
          f 1/1/1 2/1/1 -1/1/1\r\ng b\r\nf 1 2 \\\r\n 3\r\nl 1 2\r\n"
            .to_vec(),
        b"COFF\n# c\n4 2 0\n0 0 0 1 0 0 1\n1 0 0 0 1 0 1\n1 1 0 0 0 1 1\n0 1 0 1 1 1 1\n3 0 1 2 255 0 0\n3 0 2 3\n"
            .to_vec(),
        b"OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n".to_vec(),
    ];
    for enc in [Encoding::Ascii, Encoding::BinaryLittleEndian, Encoding::BinaryBigEndian] {
        out.push(ply::to_bytes(&MeshOut::poly(&p, &f).with_uv(&uv).with_normals(&n), &props, enc).unwrap());
        out.push(ply::to_bytes(&MeshOut::tri(&p, &tris).with_uv(&corner), &[], enc).unwrap());
        out.push(ply::points_to_bytes(geom_core::io::Positions::F64(&p), &props, enc).unwrap());
    }
    out
}

/// A random edit of a byte string.
#[derive(Clone, Debug)]
enum Edit {
    Set(usize, u8),
    Insert(usize, Vec<u8>),
    Delete(usize, usize),
    /// Replace a byte with a character that matters to the parsers.
    Special(usize, usize),
}

const SPECIAL: &[u8] = b" \n\r\t/#-0123456789.e\\\0";

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Set(i, b)),
        (any::<usize>(), proptest::collection::vec(any::<u8>(), 1..8)).prop_map(|(i, v)| Edit::Insert(i, v)),
        (any::<usize>(), 1usize..16).prop_map(|(i, n)| Edit::Delete(i, n)),
        (any::<usize>(), 0..SPECIAL.len()).prop_map(|(i, k)| Edit::Special(i, k)),
    ]
}

fn apply(data: &mut Vec<u8>, e: &Edit) {
    let n = data.len().max(1);
    match e {
        Edit::Set(i, b) => {
            if !data.is_empty() {
                data[i % n] = *b;
            }
        }
        Edit::Insert(i, v) => {
            let at = i % (data.len() + 1);
            data.splice(at..at, v.iter().copied());
        }
        Edit::Delete(i, k) => {
            if !data.is_empty() {
                let a = i % n;
                let b = (a + k).min(data.len());
                data.drain(a..b);
            }
        }
        Edit::Special(i, k) => {
            if !data.is_empty() {
                data[i % n] = SPECIAL[*k];
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn random_bytes_never_panic(data in proptest::collection::vec(any::<u8>(), 0..1024)) {
        all_readers(&data)?;
    }

    #[test]
    fn random_text_with_format_headers_never_panics(
        head in 0usize..4,
        body in proptest::collection::vec(prop_oneof![Just(b' '), Just(b'\n'), Just(b'/'), Just(b'-'), 0x30u8..0x3a, any::<u8>()], 0..512),
    ) {
        let prefix: &[u8] = [&b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"[..],
            b"OFF\n", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf ", b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n"][head];
        let mut data = prefix.to_vec();
        data.extend_from_slice(&body);
        all_readers(&data)?;
    }

    #[test]
    fn random_ply_headers_with_any_counts_never_panic_or_overallocate(
        fmt in 0usize..3,
        counts in proptest::collection::vec(prop_oneof![0u64..5, any::<u32>().prop_map(u64::from), Just(u64::MAX)], 1..4),
        types in proptest::collection::vec(0usize..9, 1..5),
        body in proptest::collection::vec(any::<u8>(), 0..256),
    ) {
        const T: [&str; 9] = ["char", "uchar", "short", "ushort", "int", "uint", "float", "double", "list uint int"];
        let mut h = format!("ply\nformat {} 1.0\n", ["ascii", "binary_little_endian", "binary_big_endian"][fmt]);
        for (k, c) in counts.iter().enumerate() {
            let name = ["vertex", "face", "other"][k % 3];
            h.push_str(&format!("element {name} {c}\n"));
            if name == "vertex" {
                h.push_str("property float x\nproperty float y\nproperty float z\n");
            }
            if name == "face" {
                h.push_str("property list uchar int vertex_indices\n");
            }
            for (j, t) in types.iter().enumerate() {
                h.push_str(&format!("property {} p{j}\n", T[*t]));
            }
        }
        h.push_str("end_header\n");
        let mut data = h.into_bytes();
        data.extend_from_slice(&body);
        check(ply::read_bytes(&data))?;
    }

    #[test]
    fn truncated_valid_files_never_panic(k in 0usize..14, cut in any::<prop::sample::Index>()) {
        let s = seeds();
        let data = &s[k % s.len()];
        let cut = cut.index(data.len() + 1);
        all_readers(&data[..cut])?;
    }

    #[test]
    fn mutated_valid_files_never_panic(k in 0usize..14, edits in proptest::collection::vec(edit(), 1..6)) {
        let s = seeds();
        let mut data = s[k % s.len()].clone();
        for e in &edits {
            apply(&mut data, e);
        }
        all_readers(&data)?;
    }
}

#[test]
fn seeds_are_valid() {
    // The mutation tests start from files that parse, so they probe the paths of real files.
    let s = seeds();
    assert_eq!(s.len(), 14);
    assert!(obj::parse(&s[0]).is_ok());
    assert!(obj::parse(&s[1]).is_ok());
    assert!(obj::parse(&s[2]).is_ok());
    assert!(off::parse(&s[3]).is_ok());
    assert!(off::parse(&s[4]).is_ok());
    for d in &s[5..] {
        assert!(ply::read_bytes(d).is_ok());
    }
}
