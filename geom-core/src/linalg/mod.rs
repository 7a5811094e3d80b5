//! Sparse linear algebra: triplet assembly, our own CSR operator type, and the solver facade over
//! faer (sparse Cholesky and LDLᵀ with reusable symbolic analysis, preconditioned CG). Method
//! crates never import faer's sparse solver modules; they go through this module
//! (GEOM-CORE.md §3.7).
//!
//! - Operators: [`Triplets`] → [`Csr`] (`u32` columns; products, transpose, `⊗ I₃`, …).
//! - Direct solvers take a [`Csc`] (faer's column-major type) whose **lower triangle** is read;
//!   [`FixedPattern`] re-assembles one with a fixed pattern every step.
//! - [`SparseLlt`] (SPD) and [`SparseLdlt`] (KKT, dynamic regularisation + refinement) share the
//!   analyse / factor / solve shape and the [`LltSymbolic`] analysis.
//! - [`pcg`] with [`Jacobi`], [`Ic0`] (IC(0)/MIC(0)) for large SPD systems.
//! - [`dot`], [`flat`] & co.: deterministic reductions and zero-copy views of `Pt3`/`Vec3` arrays.
//!
//! Errors: NaN/∞ in a matrix or right-hand side is [`crate::Error::NonFinite`], never a NaN
//! solution; an SPD factorisation of an indefinite or singular matrix is
//! [`crate::Error::NotPositiveDefinite`]. Parallel loops (row products, assembly, reductions) are
//! bitwise identical for any thread count; the direct factorisations run with `faer::Par::Seq`
//! by default for the same reason (opt into Rayon with `set_par`).

mod bordered;
mod cg;
mod csc;
mod csr;
mod csr_ops;
pub mod dense;
mod ldlt;
mod llt;
mod pattern;
mod precond;
mod symbolic;
mod triplets;
mod upper_state;
mod vector;

pub use bordered::BorderedLlt;
pub use cg::{pcg, CgOptions, CgReport};
pub use csc::{rel_residual, sym_mul_vec, Csc};
pub use csr::{Csr, PAR_ROWS};
pub use ldlt::{Regularization, SparseLdlt};
pub use llt::{SparseLlt, SINGULAR_PIVOT_TOL};
pub use pattern::FixedPattern;
pub use precond::{Ic0, Identity, Jacobi, Preconditioner, IC0_PIVOT_SIGMA};
pub use symbolic::{LltSymbolic, Ordering};
pub use triplets::Triplets;
pub use upper_state::zero_upper;
pub use vector::{
    all_finite, as_pt3, as_pt3_mut, as_vec3, as_vec3_mut, dot, flat, flat_mut, flat_vec, flat_vec_mut, norm2, DOT_CHUNK,
};
