//! Probes a scene can place (issue 26): the water height at given `(x, z)` columns and the gauge
//! pressure at given points, and the force and torque of the liquid's pressure on every
//! obstacle, sampled at every frame into the `probes` table (`probes.csv`).

use geom_core::math::Pt3;
use geom_core::record::{Cell, Recorder};
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::metrics::surface_height;
use crate::sim::FlipTetSim;

/// The probes of a scene (scene file `probes: (heights: [...], pressures: [...])`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Probes {
    /// Columns `(x, z)` (m) whose liquid surface height `y` (m) is recorded (the highest
    /// liquid-to-air crossing of the node level set, [`surface_height`]; empty cell without liquid).
    pub heights: Vec<(f64, f64)>,
    /// Points (m) whose gauge pressure (Pa) is recorded ([`FlipTetSim::pressure_at`]).
    pub pressures: Vec<[f64; 3]>,
    /// Force (N) and torque (N·m, about the obstacle's moved centre) of the gauge pressure on
    /// every obstacle ([`FlipTetSim::obstacle_force`]): columns `force_<k>_{x,y,z}_N`,
    /// `torque_<k>_{x,y,z}_Nm` after the others.
    pub obstacle_forces: bool,
}

impl Probes {
    /// Whether there is no probe.
    pub fn is_empty(&self) -> bool {
        self.heights.is_empty() && self.pressures.is_empty() && !self.obstacle_forces
    }

    /// Column names: `t`, `height_<i>_m`, `pressure_<i>_Pa`, then with `obstacle_forces` for
    /// each of the `n_obstacles` obstacles `force_<k>_{x,y,z}_N`, `torque_<k>_{x,y,z}_Nm`.
    pub fn header(&self, n_obstacles: usize) -> Vec<String> {
        let mut h = vec!["t".to_string()];
        h.extend((0..self.heights.len()).map(|i| format!("height_{i}_m")));
        h.extend((0..self.pressures.len()).map(|i| format!("pressure_{i}_Pa")));
        if self.obstacle_forces {
            for k in 0..n_obstacles {
                h.extend(["x", "y", "z"].map(|a| format!("force_{k}_{a}_N")));
                h.extend(["x", "y", "z"].map(|a| format!("torque_{k}_{a}_Nm")));
            }
        }
        h
    }

    /// Forces and torques of every obstacle, flattened as in [`Self::header`] (empty without
    /// `obstacle_forces`).
    pub fn forces(&self, sim: &FlipTetSim) -> Vec<f64> {
        if !self.obstacle_forces {
            return Vec::new();
        }
        (0..sim.obstacles().len())
            .flat_map(|k| {
                let (f, t) = sim.obstacle_force(k);
                [f.x, f.y, f.z, t.x, t.y, t.z]
            })
            .collect()
    }

    /// The probe values now: heights (m, NaN without liquid), pressures (Pa, NaN outside the mesh
    /// or before the first step).
    pub fn sample(&self, sim: &FlipTetSim) -> (Vec<f64>, Vec<f64>) {
        let h = self.heights.iter().map(|&(x, z)| surface_height(sim, x, z).unwrap_or(f64::NAN)).collect();
        let p =
            self.pressures.iter().map(|q| sim.pressure_at(&Pt3::new(q[0], q[1], q[2])).unwrap_or(f64::NAN)).collect();
        (h, p)
    }

    /// Declares the table `name`.
    pub fn declare(&self, rec: &mut dyn Recorder, name: &str, n_obstacles: usize) -> Result<()> {
        let header = self.header(n_obstacles);
        let cols: Vec<&str> = header.iter().map(String::as_str).collect();
        rec.table(name, &cols)?;
        Ok(())
    }

    /// Samples the probes and appends a row to the table `name`; returns the values.
    pub fn record(&self, sim: &FlipTetSim, rec: &mut dyn Recorder, name: &str) -> Result<(Vec<f64>, Vec<f64>)> {
        let (h, p) = self.sample(sim);
        let mut row = vec![Cell::Num(sim.time())];
        row.extend(h.iter().chain(&p).chain(&self.forces(sim)).map(|&v| Cell::Num(v)));
        rec.row(name, &row)?;
        Ok((h, p))
    }
}
