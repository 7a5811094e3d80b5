//! Renders frames of a shell run (an OBJ sequence) with the scene's obstacles into one PNG strip
//! (Lambert shading, geom-core's rasteriser): a quick look while tuning a scene.
//!
//! `cargo run --release -p shells --example look -- <scene.ron> <frames dir> <out.png> <frame> [frame …] [--eye x,y,z] [--target x,y,z]`

use geom_core::math::{Pt3, Vec3};
use geom_core::raster::{lambert_preview, Camera, RasterOptions};
use serde::Deserialize;
use shells::scene::ShellScene;
use shells::ObstacleShape;

#[derive(Deserialize)]
struct Params {
    shell: ShellScene,
}

#[derive(Deserialize)]
struct File {
    params: Params,
}

fn parse3(s: &str) -> Option<Pt3> {
    let v: Vec<f64> = s.split(',').filter_map(|x| x.parse().ok()).collect();
    (v.len() == 3).then(|| Pt3::new(v[0], v[1], v[2]))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut eye = Pt3::new(1.6, 1.4, 2.0);
    let mut target = Pt3::new(0.0, 0.4, 0.0);
    if let Some(i) = args.iter().position(|a| a == "--eye") {
        eye = parse3(&args[i + 1]).ok_or("--eye x,y,z")?;
        args.drain(i..i + 2);
    }
    if let Some(i) = args.iter().position(|a| a == "--target") {
        target = parse3(&args[i + 1]).ok_or("--target x,y,z")?;
        args.drain(i..i + 2);
    }
    let [scene, dir, out, frames @ ..] = args.as_slice() else {
        return Err("usage: look <scene.ron> <frames dir> <out.png> <frame> [frame …]".into());
    };
    let text = std::fs::read_to_string(scene)?;
    let file: File =
        ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME).from_str(&text)?;
    let built = file.params.shell.build(std::path::Path::new("."))?;
    // Static context: obstacle meshes (planes as a 3 m square).
    let (mut cp, mut cf): (Vec<Pt3>, Vec<[u32; 3]>) = (Vec::new(), Vec::new());
    let mut add = |p: &[Pt3], f: &[[u32; 3]]| {
        let o = cp.len() as u32;
        cp.extend_from_slice(p);
        cf.extend(f.iter().map(|t| t.map(|i| i + o)));
    };
    for o in &built.desc.effects.obstacles {
        match &o.shape {
            ObstacleShape::Plane { normal, offset } => {
                let n = normal.normalize();
                let u = n.cross(&if n.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() }).normalize() * 1.5;
                let v = n.cross(&u);
                let c = Pt3::from(n * *offset);
                add(&[c - u - v, c + u - v, c + u + v, c - u + v], &[[0, 2, 1], [0, 3, 2], [0, 1, 2], [0, 2, 3]]);
            }
            shape => {
                if let Some((p, f)) = shape.surface_mesh()? {
                    add(&p, &f);
                }
            }
        }
    }
    let (w, h) = (360u32, 300u32);
    let cam = Camera::look_at(&eye, &target, &Vec3::y(), 40.0, w, h)?;
    let mut strip = vec![0u8; (w as usize * frames.len()) * h as usize];
    for (k, f) in frames.iter().enumerate() {
        let n: usize = f.parse()?;
        let m = geom_core::io::obj::read_tri(geom_core::io::frame_path(std::path::Path::new(dir), n))?;
        let mut p = cp.clone();
        let mut fc = cf.clone();
        let o = p.len() as u32;
        p.extend_from_slice(&m.positions);
        fc.extend(m.faces.iter().map(|t| t.map(|i| i + o)));
        // Both sides of the cloth.
        fc.extend(m.faces.iter().map(|t| [t[0] + o, t[2] + o, t[1] + o]));
        let img = lambert_preview(&cam, &p, &fc, &Vec3::new(0.4, 1.0, 0.6), &RasterOptions::default());
        for y in 0..h as usize {
            for x in 0..w as usize {
                strip[y * w as usize * frames.len() + k * w as usize + x] =
                    (img.at(x as u32, y as u32).clamp(0.0, 1.0) * 255.0) as u8;
            }
        }
    }
    let file = std::fs::File::create(out)?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w * frames.len() as u32, h);
    enc.set_color(png::ColorType::Grayscale);
    enc.write_header()?.write_image_data(&strip)?;
    Ok(())
}
