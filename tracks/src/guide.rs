//! The guide animation (spec §2, §3.4): a coarse mesh whose vertex positions are known at any
//! time, either from frames (uniform Catmull–Rom, C¹, or linear interpolation) or from an exact
//! procedural function.

use std::path::Path;
use std::sync::Arc;

use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::TriMesh;

use crate::error::{Result, TrackError};

/// Exact procedural guide: positions of every guide vertex at time t (s).
pub type ProceduralFn = Arc<dyn Fn(f64) -> Vec<Pt3> + Send + Sync>;

/// Time interpolation of frame-sampled guides (spec §3.4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
pub enum TimeInterp {
    /// Uniform Catmull–Rom (C¹; tangents (Q_{j+1} − Q_{j−1})/2, one-sided at the ends). Default.
    #[default]
    CatmullRom,
    /// Piecewise linear (C⁰: the velocity jumps at frame times; only for the accuracy study).
    Linear,
}

/// A coarse guide animation on a fixed topology.
#[derive(Clone)]
pub struct GuideAnimation {
    /// Guide undeformed mesh (reference domain Ω̄ of the test functions).
    pub rest: TriMesh,
    /// Positions per frame (same vertex count as `rest`); frame i is at time i / fps.
    pub frames: Vec<Vec<Pt3>>,
    /// Frames per second of `frames` (> 0).
    pub fps: f64,
    /// Interpolation between frames.
    pub interp: TimeInterp,
    /// Exact sampling (procedural guides); when present it wins over `frames`.
    pub procedural: Option<ProceduralFn>,
    /// Duration (s) of a procedural guide (frame guides: (#frames − 1)/fps).
    pub procedural_duration: f64,
}

impl std::fmt::Debug for GuideAnimation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GuideAnimation")
            .field("vertices", &self.rest.n_vertices())
            .field("frames", &self.frames.len())
            .field("fps", &self.fps)
            .field("procedural", &self.procedural.is_some())
            .finish()
    }
}

impl GuideAnimation {
    /// A frame-sampled guide. Errors: no frames, frame with a different vertex count
    /// (`TopologyMismatch`), NaN/∞ positions (`NonFinite`), fps ≤ 0 (`BadParameter`).
    pub fn from_frames(rest: TriMesh, frames: Vec<Vec<Pt3>>, fps: f64, interp: TimeInterp) -> Result<Self> {
        if !(fps > 0.0 && fps.is_finite()) {
            return Err(TrackError::BadParameter(format!("guide fps must be > 0, got {fps}")));
        }
        if frames.is_empty() {
            return Err(TrackError::BadParameter("guide has no frames".into()));
        }
        let n = rest.n_vertices();
        for f in &frames {
            if f.len() != n {
                return Err(TrackError::TopologyMismatch {
                    what: "guide frame vertex count",
                    expected: n,
                    got: f.len(),
                });
            }
            if f.iter().any(|p| p.iter().any(|c| !c.is_finite())) {
                return Err(TrackError::NonFinite("guide frame positions"));
            }
        }
        Ok(Self { rest, frames, fps, interp, procedural: None, procedural_duration: 0.0 })
    }

    /// A procedural guide sampled exactly at any time in `[0, duration]` (held afterwards).
    /// Errors: the function's output at t = 0 has the wrong length or is not finite.
    pub fn procedural(rest: TriMesh, f: ProceduralFn, duration: f64) -> Result<Self> {
        if !(duration >= 0.0 && duration.is_finite()) {
            return Err(TrackError::BadParameter(format!("guide duration must be ≥ 0, got {duration}")));
        }
        let p0 = f(0.0);
        if p0.len() != rest.n_vertices() {
            return Err(TrackError::TopologyMismatch {
                what: "procedural guide vertex count",
                expected: rest.n_vertices(),
                got: p0.len(),
            });
        }
        if p0.iter().any(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(TrackError::NonFinite("procedural guide positions"));
        }
        Ok(Self {
            rest,
            frames: vec![p0],
            fps: 30.0,
            interp: TimeInterp::CatmullRom,
            procedural: Some(f),
            procedural_duration: duration,
        })
    }

    /// Reads `dir/NNNN.obj` (geom-core's sequence layout): the first frame is the rest mesh.
    pub fn from_obj_sequence(dir: &Path, fps: f64) -> Result<Self> {
        let (rest, frames) = geom_core::io::read_obj_sequence(dir)?;
        Self::from_frames(rest, frames, fps, TimeInterp::CatmullRom)
    }

    /// Number of guide vertices n̄.
    pub fn n_vertices(&self) -> usize {
        self.rest.n_vertices()
    }

    /// Duration (s): the last frame's time, or the procedural duration.
    pub fn duration(&self) -> f64 {
        if self.procedural.is_some() {
            self.procedural_duration
        } else {
            (self.frames.len() - 1) as f64 / self.fps
        }
    }

    /// Frame index and local parameter u ∈ [0, 1] of time t (clamped; `true` when t was past
    /// the end or before 0).
    fn locate(&self, t: f64) -> (usize, f64, bool) {
        let last = self.frames.len() - 1;
        if last == 0 {
            return (0, 0.0, t > 0.0);
        }
        let s = t * self.fps;
        if !(s >= 0.0) {
            return (0, 0.0, true);
        }
        if s >= last as f64 {
            return (last - 1, 1.0, s > last as f64 + 1e-9);
        }
        let i = (s.floor() as usize).min(last - 1);
        (i, s - i as f64, false)
    }

    /// Catmull–Rom tangent (per frame-index unit) at frame j.
    fn tangent(&self, j: usize, v: usize) -> Vec3 {
        let last = self.frames.len() - 1;
        let f = &self.frames;
        if j == 0 {
            f[1][v] - f[0][v]
        } else if j == last {
            f[last][v] - f[last - 1][v]
        } else {
            0.5 * (f[j + 1][v] - f[j - 1][v])
        }
    }

    /// Positions at time t (s) into `out` (length n̄). Returns `true` when t lay outside the
    /// animation and the first/last state was held (spec §3.4: flagged, not an error).
    pub fn sample(&self, t: f64, out: &mut [Pt3]) -> bool {
        if let Some(f) = &self.procedural {
            let tc = t.clamp(0.0, self.procedural_duration);
            let p = f(tc);
            out.copy_from_slice(&p);
            return tc != t;
        }
        let (i, u, held) = self.locate(t);
        let fr = &self.frames;
        if fr.len() == 1 {
            out.copy_from_slice(&fr[0]);
            return held;
        }
        match self.interp {
            TimeInterp::Linear => {
                for (v, o) in out.iter_mut().enumerate() {
                    *o = fr[i][v] + u * (fr[i + 1][v] - fr[i][v]);
                }
            }
            TimeInterp::CatmullRom => {
                let (u2, u3) = (u * u, u * u * u);
                let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
                let h10 = u3 - 2.0 * u2 + u;
                let h01 = -2.0 * u3 + 3.0 * u2;
                let h11 = u3 - u2;
                for (v, o) in out.iter_mut().enumerate() {
                    let p = h00 * fr[i][v].coords
                        + h10 * self.tangent(i, v)
                        + h01 * fr[i + 1][v].coords
                        + h11 * self.tangent(i + 1, v);
                    *o = Pt3::from(p);
                }
            }
        }
        held
    }

    /// Velocities at time t (m/s) into `out`: exact derivative of the interpolant, or a
    /// central difference (δ = 1e-6 s) of a procedural guide. Zero past the end (held).
    pub fn sample_velocity(&self, t: f64, out: &mut [Vec3]) {
        if let Some(f) = &self.procedural {
            let d = 1e-6;
            let (a, b) = ((t - d).max(0.0), (t + d).min(self.procedural_duration));
            if b <= a {
                out.iter_mut().for_each(|o| *o = Vec3::zeros());
                return;
            }
            let (pa, pb) = (f(a), f(b));
            for (v, o) in out.iter_mut().enumerate() {
                *o = (pb[v] - pa[v]) / (b - a);
            }
            return;
        }
        let (i, u, held) = self.locate(t);
        if held || self.frames.len() == 1 {
            out.iter_mut().for_each(|o| *o = Vec3::zeros());
            return;
        }
        let fr = &self.frames;
        match self.interp {
            TimeInterp::Linear => {
                for (v, o) in out.iter_mut().enumerate() {
                    *o = (fr[i + 1][v] - fr[i][v]) * self.fps;
                }
            }
            TimeInterp::CatmullRom => {
                let u2 = u * u;
                let d00 = 6.0 * u2 - 6.0 * u;
                let d10 = 3.0 * u2 - 4.0 * u + 1.0;
                let d01 = -6.0 * u2 + 6.0 * u;
                let d11 = 3.0 * u2 - 2.0 * u;
                for (v, o) in out.iter_mut().enumerate() {
                    let p = d00 * fr[i][v].coords
                        + d10 * self.tangent(i, v)
                        + d01 * fr[i + 1][v].coords
                        + d11 * self.tangent(i + 1, v);
                    *o = p * self.fps;
                }
            }
        }
    }

    /// Bounding-box diagonal of the guide at t = 0 (the scene scale L of spec §3.8).
    pub fn scale(&self) -> f64 {
        let mut p = vec![Pt3::origin(); self.n_vertices()];
        self.sample(0.0, &mut p);
        geom_core::mesh::bbox_of(&p).map_or(0.0, |(a, b)| (b - a).norm())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::procedural::{grid, GridSpec};

    fn guide(interp: TimeInterp) -> GuideAnimation {
        let rest = grid(&GridSpec { quads: [2, 2], ..GridSpec::default() }).expect("valid grid");
        let frames: Vec<Vec<Pt3>> = (0..6)
            .map(|k| {
                let t = k as f64;
                rest.positions.iter().map(|p| p + Vec3::new(t.sin(), 0.3 * t * t, 0.1 * t)).collect()
            })
            .collect();
        GuideAnimation::from_frames(rest, frames, 10.0, interp).expect("valid frames")
    }

    /// Spec §7 test 16: the interpolant hits the frames and is C¹ (Catmull–Rom); Linear has a
    /// velocity jump. Tolerance 1e-9: velocities differ only by rounding at the shared knot.
    #[test]
    fn catmull_rom() {
        let g = guide(TimeInterp::CatmullRom);
        let n = g.n_vertices();
        let mut p = vec![Pt3::origin(); n];
        for (k, f) in g.frames.iter().enumerate() {
            g.sample(k as f64 / g.fps, &mut p);
            for (a, b) in p.iter().zip(f) {
                assert!((a - b).norm() < 1e-12);
            }
        }
        let (mut va, mut vb) = (vec![Vec3::zeros(); n], vec![Vec3::zeros(); n]);
        for k in 1..5 {
            let t = k as f64 / g.fps;
            g.sample_velocity(t - 1e-12, &mut va);
            g.sample_velocity(t + 1e-12, &mut vb);
            assert!((va[0] - vb[0]).norm() < 1e-6 * va[0].norm().max(1.0), "C¹ at frame {k}");
            // Derivative against a finite difference of the positions (O(δ²) = 1e-8).
            let d = 1e-4;
            let (mut pa, mut pb) = (vec![Pt3::origin(); n], vec![Pt3::origin(); n]);
            g.sample(t + 0.3 / g.fps - d, &mut pa);
            g.sample(t + 0.3 / g.fps + d, &mut pb);
            g.sample_velocity(t + 0.3 / g.fps, &mut va);
            assert!(((pb[0] - pa[0]) / (2.0 * d) - va[0]).norm() < 1e-5);
        }
        let l = guide(TimeInterp::Linear);
        l.sample_velocity(2.0 / l.fps - 1e-9, &mut va);
        l.sample_velocity(2.0 / l.fps + 1e-9, &mut vb);
        assert!((va[0] - vb[0]).norm() > 0.1, "linear interpolation has a velocity jump");
        // Past the end: held and flagged.
        assert!(g.sample(10.0, &mut p));
        assert!((p[0] - g.frames[5][0]).norm() < 1e-12);
    }

    #[test]
    fn bad_frames_rejected() {
        let rest = grid(&GridSpec { quads: [1, 1], ..GridSpec::default() }).expect("valid grid");
        let bad = vec![vec![Pt3::origin(); 3]];
        assert!(matches!(
            GuideAnimation::from_frames(rest.clone(), bad, 30.0, TimeInterp::Linear),
            Err(TrackError::TopologyMismatch { .. })
        ));
        let mut f = rest.positions.clone();
        f[0].x = f64::NAN;
        assert!(matches!(
            GuideAnimation::from_frames(rest, vec![f], 30.0, TimeInterp::Linear),
            Err(TrackError::NonFinite(_))
        ));
    }
}
