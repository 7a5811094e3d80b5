//! Writes the guide of the built-in scene `tracks/own-guide`: the toolkit's own coarse preview of
//! the flag (spec §6.1's design loop — the 35-vertex cotton flag thrown at the branch; the first
//! of the 20 previews that ends stuck on it, else the last) as a time-sampled `.usda`, the file
//! an artist would export from their preview tool.
//!
//! `cargo run --release -p tracks --example write_flag_guide -- assets/guides/flag-preview.usda`

use geom_core::io::usd::{self, UsdFrame, UsdOptions};
use shells::ContactMethod;
use tracks::experiments::flag::PREVIEW_DURATION;
use tracks::presets::flag_design;

fn main() {
    let Some(out) = std::env::args().nth(1) else {
        eprintln!("usage: write_flag_guide <out.usda>");
        std::process::exit(2);
    };
    let d = match flag_design(PREVIEW_DURATION, ContactMethod::Ipc) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("flag design loop failed: {e}");
            std::process::exit(1);
        }
    };
    let faces = &d.guide.rest.faces;
    let frames: Vec<UsdFrame> = d.guide.frames.iter().map(|q| UsdFrame::new(q, faces)).collect();
    let doc = format!(
        "tracks flag preview: 35-vertex cotton flag thrown at ({}, {}) m/s, stuck on the branch: {}",
        d.velocity.0,
        d.velocity.1,
        d.stuck_flags.iter().any(|&s| s)
    );
    let o = UsdOptions { fps: d.guide.fps, doc, ..UsdOptions::default() };
    if let Err(e) = usd::write(&out, "flag_preview", &frames, &o) {
        eprintln!("{out}: {e}");
        std::process::exit(1);
    }
    println!("{out}: {} frames at {} fps, velocity {:?}", frames.len(), d.guide.fps, d.velocity);
}
