//! Reference solutions and measured data the scenes are compared with: Martin & Moyce's (1952)
//! dam-break tables, the linear theory of a standing wave, and the hydrostatic pressure.

use crate::scene::{Scene, Shape};

/// Martin & Moyce (1952), Phil. Trans. R. Soc. A 244, Fig./Table for `a = 2¼ in`, `n² = 2`
/// (spec §6 S2): dimensionless surge front `Z = x_front / a` at `T = t √(2g/a)`.
pub const MARTIN_MOYCE_FRONT: [(f64, f64); 15] = [
    (0.41, 1.11),
    (0.84, 1.22),
    (1.19, 1.44),
    (1.43, 1.67),
    (1.63, 1.89),
    (1.83, 2.11),
    (1.98, 2.33),
    (2.20, 2.56),
    (2.32, 2.78),
    (2.51, 3.00),
    (2.65, 3.22),
    (2.83, 3.44),
    (2.98, 3.67),
    (3.11, 3.89),
    (3.33, 4.11),
];

/// Martin & Moyce (1952) residual column height `H = h / (2a)` at `τ = t √(g/a)` (spec §6 S2).
pub const MARTIN_MOYCE_HEIGHT: [(f64, f64); 17] = [
    (0.56, 0.94),
    (0.77, 0.89),
    (0.93, 0.83),
    (1.08, 0.78),
    (1.28, 0.72),
    (1.46, 0.67),
    (1.66, 0.61),
    (1.84, 0.56),
    (2.00, 0.50),
    (2.21, 0.44),
    (2.45, 0.39),
    (2.70, 0.33),
    (3.06, 0.28),
    (3.44, 0.22),
    (4.20, 0.17),
    (5.25, 0.11),
    (7.40, 0.06),
];

/// Martin & Moyce (1952), Fig. 3, surge front for `n² = 2`, `a = 2¼ in`: `(T = t √(2g/a), Z =
/// x/a)`, as digitised in PySPH (`pysph/examples/db_exp_data.py`, `mm_data_2`, repository
/// pypr/pysph, commit 483e444; J. C. Martin and W. J. Moyce, "An experimental study of the
/// collapse of liquid columns on a rigid horizontal plane", Phil. Trans. R. Soc. Lond. A 244,
/// 312–324). Covers a longer tank than [`MARTIN_MOYCE_FRONT`] (the spec's table, same figure).
pub const MM_FRONT_A225: [(f64, f64); 15] = [
    (0.832, 1.217),
    (1.219, 1.474),
    (1.997, 2.292),
    (2.547, 2.995),
    (3.345, 4.134),
    (4.034, 4.944),
    (4.418, 5.881),
    (5.091, 6.980),
    (5.685, 7.945),
    (6.306, 8.966),
    (6.822, 9.986),
    (7.439, 10.963),
    (8.031, 11.977),
    (8.633, 13.005),
    (9.237, 13.970),
];

/// Martin & Moyce (1952), Fig. 3, surge front for `n² = 2`, `a = 1⅛ in`: `(T, Z)` as in
/// [`MM_FRONT_A225`] (PySPH `mm_data_1`, same provenance).
pub const MM_FRONT_A1125: [(f64, f64); 10] = [
    (0.849, 1.245),
    (1.212, 1.443),
    (1.602, 1.884),
    (2.283, 2.689),
    (2.950, 3.728),
    (3.598, 4.528),
    (3.905, 4.999),
    (4.592, 5.841),
    (4.961, 6.271),
    (5.316, 6.717),
];

/// Koshizuka & Oka (1996), surge front of their dam-break experiment (column `L × 2L`,
/// `L = 0.146` m): `(T = t √(2g/L), Z = x/L)`, as digitised in PySPH
/// (`pysph/examples/db_exp_data.py`, `ko_data`, repository pypr/pysph, commit 483e444;
/// S. Koshizuka and Y. Oka, "Moving-particle semi-implicit method for fragmentation of
/// incompressible fluid", Nucl. Sci. Eng. 123, 421–434).
pub const KO_FRONT: [(f64, f64); 9] = [
    (0.0, 1.000),
    (0.381, 1.111),
    (0.769, 1.252),
    (1.153, 1.505),
    (1.537, 1.892),
    (1.935, 2.241),
    (2.323, 2.615),
    (2.719, 3.003),
    (3.096, 3.624),
];

/// Hydrostatic gauge pressure `ρ g d` (Pa) at depth `d` (m) below a free surface.
pub fn hydrostatic_pressure(rho: f64, g: f64, depth: f64) -> f64 {
    rho * g * depth
}

/// The standing-wave scene's mode and its linear theory (spec §6 S3; Lamb, *Hydrodynamics*
/// §227): `η(x, t) = H̄ + A cos(π (x − x0)/L) cos(ω t)`, `ω² = g k tanh(k H)`, `k = π/L`.
#[derive(Clone, Copy, Debug)]
pub struct WaveTheory {
    /// Mean surface height `H̄` (m, absolute `y`).
    pub mean: f64,
    /// Initial amplitude `A` (m).
    pub amp: f64,
    /// Tank length `L` (m).
    pub len: f64,
    /// Tank start `x0` (m).
    pub x0: f64,
    /// Angular frequency `ω = √(g k tanh(k H))`, `k = π/L` (rad/s).
    pub omega: f64,
    /// Period `2π/ω` (s).
    pub period: f64,
}

impl WaveTheory {
    /// Reads the scene's `CosineSurface` (its first liquid shape) and gravity; `None` when the
    /// first liquid shape is not a cosine surface.
    pub fn of(scene: &Scene) -> Option<Self> {
        let (mean, amp, len, x0) = match scene.liquid.first() {
            Some(Shape::CosineSurface { mean, amplitude, length, x0 }) => (*mean, *amplitude, *length, *x0),
            _ => return None,
        };
        let depth = mean - scene.domain.min[1];
        let g = -scene.gravity[1];
        let k = std::f64::consts::PI / len;
        let omega = (g * k * (k * depth).tanh()).sqrt();
        Some(Self { mean, amp, len, x0, omega, period: 2.0 * std::f64::consts::PI / omega })
    }

    /// Linear-theory surface height at `x` and time `t` (m).
    pub fn eta(&self, x: f64, t: f64) -> f64 {
        self.mean + self.amp * (std::f64::consts::PI * (x - self.x0) / self.len).cos() * (self.omega * t).cos()
    }
}
