//! File-level I/O: format detection ([`read_any`]), OBJ frame sequences, path-naming errors.

use std::path::{Path, PathBuf};

use geom_core::io::{frame_path, obj, ply, read_any, read_obj_sequence, sniff, write_obj_frame, MeshFormat, MeshOut};
use geom_core::math::{Pt3, Vec3};
use geom_core::Error;

fn dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("io_files").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn square() -> (Vec<Pt3>, Vec<[u32; 3]>) {
    (
        vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(1.0, 1.0, 0.0), Pt3::new(0.0, 1.0, 0.0)],
        vec![[0, 1, 2], [0, 2, 3]],
    )
}

#[test]
fn frame_paths_have_at_least_four_digits() {
    let d = Path::new("out/frames");
    assert_eq!(frame_path(d, 0), d.join("0000.obj"));
    assert_eq!(frame_path(d, 42), d.join("0042.obj"));
    assert_eq!(frame_path(d, 12345), d.join("12345.obj"));
}

#[test]
fn sequences_round_trip_and_check_topology() {
    let d = dir("seq");
    let (p, f) = square();
    let frames: Vec<Vec<Pt3>> =
        (0..12).map(|i| p.iter().map(|q| q + Vec3::new(0.0, 0.0, i as f64 / 3.0)).collect()).collect();
    for (i, fr) in frames.iter().enumerate() {
        let path = write_obj_frame(&d, i, &MeshOut::tri(fr, &f)).unwrap();
        assert_eq!(path, frame_path(&d, i));
    }
    // Unrelated files are ignored.
    std::fs::write(d.join("notes.txt"), "x").unwrap();
    std::fs::write(d.join("mesh_a.obj"), "x").unwrap();
    let (mesh, got) = read_obj_sequence(&d).unwrap();
    assert_eq!(mesh.faces, f);
    assert_eq!(got, frames, "frames are read in numeric order, positions exact");

    // A frame with another vertex count.
    let d2 = dir("seq_count");
    write_obj_frame(&d2, 0, &MeshOut::tri(&p, &f)).unwrap();
    write_obj_frame(&d2, 1, &MeshOut::tri(&p[..3], &f[..1])).unwrap();
    assert!(matches!(read_obj_sequence(&d2), Err(Error::TopologyMismatch { expected: 4, got: 3 })));
    // Same counts, other faces.
    let d3 = dir("seq_faces");
    write_obj_frame(&d3, 0, &MeshOut::tri(&p, &f)).unwrap();
    write_obj_frame(&d3, 1, &MeshOut::tri(&p, &[[0, 1, 3], [1, 2, 3]])).unwrap();
    match read_obj_sequence(&d3) {
        Err(Error::Parse { msg, .. }) => assert!(msg.contains("0001.obj") && msg.contains("triangle 0"), "{msg}"),
        other => panic!("expected a topology error, got {other:?}"),
    }
    // A gap in the numbering, and an empty directory.
    let d4 = dir("seq_gap");
    write_obj_frame(&d4, 0, &MeshOut::tri(&p, &f)).unwrap();
    write_obj_frame(&d4, 2, &MeshOut::tri(&p, &f)).unwrap();
    assert!(matches!(read_obj_sequence(&d4), Err(Error::InvalidParameter(m)) if m.contains("frame 1 is missing")));
    assert!(matches!(read_obj_sequence(&dir("seq_empty")), Err(Error::InvalidParameter(_))));
    // A damaged frame names its file and line.
    let d5 = dir("seq_bad");
    write_obj_frame(&d5, 0, &MeshOut::tri(&p, &f)).unwrap();
    std::fs::write(frame_path(&d5, 1), "v 0 0 0\nv 1 0\n").unwrap();
    match read_obj_sequence(&d5) {
        Err(Error::Parse { line: 2, msg, .. }) => assert!(msg.contains("0001.obj"), "{msg}"),
        other => panic!("expected a parse error, got {other:?}"),
    }
}

#[test]
fn read_any_uses_extension_then_content() {
    let d = dir("any");
    let (p, f) = square();
    let m = MeshOut::tri(&p, &f);
    obj::write(d.join("a.obj"), &m).unwrap();
    ply::write(d.join("a.PLY"), &m, &[], ply::Encoding::BinaryLittleEndian).unwrap();
    std::fs::write(d.join("a.off"), "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n").unwrap();
    // Same contents without (or with a misleading) extension: sniffed.
    std::fs::copy(d.join("a.obj"), d.join("obj_noext")).unwrap();
    std::fs::copy(d.join("a.PLY"), d.join("ply.dat")).unwrap();
    std::fs::copy(d.join("a.off"), d.join("off.mesh")).unwrap();
    for name in ["a.obj", "a.PLY", "obj_noext", "ply.dat"] {
        let m = read_any(d.join(name)).unwrap();
        assert_eq!(m.positions, p, "{name}");
        assert_eq!(m.faces.len(), 2, "{name}");
    }
    for name in ["a.off", "off.mesh"] {
        let m = read_any(d.join(name)).unwrap();
        assert_eq!(m.positions, p, "{name}");
        assert_eq!(m.faces.row(0), &[0, 1, 2, 3]);
    }
    std::fs::write(d.join("x.bin"), [0u8, 159, 146, 150]).unwrap();
    match read_any(d.join("x.bin")) {
        Err(Error::Parse { format: "mesh", msg, .. }) => {
            assert!(msg.contains("cannot tell the format") && msg.contains("x.bin"), "{msg}")
        }
        other => panic!("expected a format error, got {other:?}"),
    }
    match read_any(d.join("missing.obj")) {
        Err(Error::Io(e)) => assert!(e.to_string().contains("missing.obj")),
        other => panic!("expected an I/O error, got {other:?}"),
    }
}

#[test]
fn sniffing() {
    assert_eq!(sniff(b"ply\r\nformat ascii 1.0\n"), Some(MeshFormat::Ply));
    assert_eq!(sniff(b"# comment\n\nCOFF\n"), Some(MeshFormat::Off));
    assert_eq!(sniff(b"# exported\nmtllib a.mtl\nv 0 0 0\n"), Some(MeshFormat::Obj));
    assert_eq!(sniff(b"solid cube\nfacet normal 0 0 1\n"), None);
    assert_eq!(sniff(b""), None);
    assert_eq!(sniff(b"\xEF\xBB\xBFv 1 2 3\n"), Some(MeshFormat::Obj));
}
