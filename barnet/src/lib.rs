//! # barnet — bar-network (force density) driven skin deformation
//!
//! Zhang, Yang and Zhao, *Bar-net driven skinning for character animation*, CAVW 18(4–5), 2007,
//! with the force density method of Schek (1974). A bar-net couples the coarse control mesh of a
//! character (vertices = nodes, edges = bars) to physics: free nodes settle where the bar forces
//! `q_j (x_k − x_i)` balance the animator's virtual loads, which is **one sparse linear solve**
//! whose matrix does not depend on the loads (spec `shared/specs/barnet.md`).
//!
//! - [`net`]: [`BarNet`], validation, the branch–node matrix (§3.1, §3.3, §8).
//! - [`assemble`]: `D = CᵀQC`, `D_f = CᵀQC_f` by direct assembly (§3.2).
//! - [`solver`]: [`FdmSolver`] — factor once, back-substitute per frame; refactor when q changes.
//! - [`nonlinear`]: Schek's nonlinear FDM and elastic bars by Newton (§3.7), the comparison.
//! - [`analytic`]: cable and membrane nets with exact solutions (§7.1).
//! - [`subdiv`], [`wrap`]: the fine skin from the control mesh (§3.4.4).
//! - [`skin`], [`arm`], [`patch`], [`deformer`]: the character coupling (§3.4–3.6, §3.8).
//! - [`presets`]: the paper's biceps arm and its bar-net; [`metrics`]: every figure the scenes
//!   report; [`experiments`]: the reproduction scenes of spec §6 as library calls.

pub mod analytic;
pub mod arm;
pub mod assemble;
pub mod deformer;
pub mod error;
pub mod experiments;
pub mod metrics;
pub mod net;
pub mod nonlinear;
pub mod patch;
pub mod presets;
pub mod skin;
pub mod solver;
pub mod subdiv;
pub mod topo;
pub mod volume;
pub mod wrap;

pub use error::{BarNetError, Result};
pub use net::{Bar, BarNet, NetReport};
pub use solver::{FdmOptions, FdmSolver, SolveInfo, SolverPath};
