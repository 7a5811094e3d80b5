//! Writes the truth frames of a fabric's static and waving trials with their angle maps and
//! fold masks as PNGs into a directory (for looking at them).
//!
//! `cargo run --release -p cloth-fit --example dump_frames -- <dir> [fabric] [width height]`

use cloth_fit::angle::{angle_map, AngleOptions};
use cloth_fit::forward::{ForwardModel, ShellsForward};
use cloth_fit::png_bytes::{gray8, mask};
use cloth_fit::presets::{fit_model, rig_spec, static_trial, waving_trial, FabricPreset};
use cloth_fit::render::{render_intensity, RenderOptions};
use geom_core::image::ImageF32;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().collect();
    let dir = std::path::PathBuf::from(a.get(1).cloned().unwrap_or_else(|| "dump".into()));
    std::fs::create_dir_all(&dir)?;
    let f = match a.get(2).map(String::as_str) {
        Some("fleece") => FabricPreset::Fleece,
        Some("satin") => FabricPreset::Satin,
        Some("knit") => FabricPreset::Knit,
        _ => FabricPreset::Linen,
    };
    let w: u32 = a.get(3).and_then(|s| s.parse().ok()).unwrap_or(320);
    let h: u32 = a.get(4).and_then(|s| s.parse().ok()).unwrap_or(240);
    let rig = rig_spec(w, h).build()?.rig;
    let model = fit_model();
    let faces = ShellsForward.faces(&model);
    let ao = AngleOptions::default();
    for (name, e) in [("static", static_trial(f, 0, 1)), ("waving", waving_trial(f, 0, 40))] {
        let sim = ShellsForward.simulate(&f.params(), &e, &rig, &model)?;
        for (k, q) in sim.frames.iter().enumerate().step_by(8) {
            let (img, sil) = render_intensity(q, &faces, &rig, &RenderOptions::default());
            let am = angle_map(&img, &sil, &ao);
            let th = ImageF32 {
                width: w,
                height: h,
                data: am
                    .theta
                    .data
                    .iter()
                    .zip(&am.valid.data)
                    .map(|(t, v)| if *v { 0.5 + t / std::f32::consts::PI } else { 0.0 })
                    .collect(),
            };
            std::fs::write(dir.join(format!("{name}_{k:02}_img.png")), gray8(&img))?;
            std::fs::write(dir.join(format!("{name}_{k:02}_theta.png")), gray8(&th))?;
            std::fs::write(dir.join(format!("{name}_{k:02}_fold.png")), mask(&am.fold_mask))?;
            let mut g = Vec::new();
            let (wu, hu) = (w as usize, h as usize);
            for y in 1..hu - 1 {
                for x in 1..wu - 1 {
                    let i = y * wu + x;
                    if !(0..3).all(|dy| (0..3).all(|dx| am.valid.data[(y + dy - 1) * wu + x + dx - 1])) {
                        continue;
                    }
                    let u = |j: usize| {
                        let t = 2.0 * am.theta.data[j] as f64;
                        (t.cos(), t.sin())
                    };
                    let (xp, xm, yp, ym) = (u(i + 1), u(i - 1), u(i + wu), u(i - wu));
                    let gx = ((xp.0 - xm.0).powi(2) + (xp.1 - xm.1).powi(2)) / 4.0;
                    let gy = ((yp.0 - ym.0).powi(2) + (yp.1 - ym.1).powi(2)) / 4.0;
                    g.push(0.5 * (gx + gy).sqrt());
                }
            }
            let pc = |q: f64| geom_core::stats::percentile(&g, q);
            println!(
                "{name} frame {k}: valid {} fold {}  |grad θ| p50 {:.4} p75 {:.4} p90 {:.4} p99 {:.4} max {:.4}",
                am.valid.count(),
                am.fold_mask.count(),
                pc(50.0),
                pc(75.0),
                pc(90.0),
                pc(99.0),
                pc(100.0)
            );
        }
    }
    Ok(())
}
