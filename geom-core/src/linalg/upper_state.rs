//! Clearing the upper halves of the vector registers after faer's dense `matmul`.
//!
//! faer's `faer::linalg::matmul::matmul` entry point returns with the upper bits of the ymm/zmm
//! registers dirty (its AVX-512 kernels end without `vzeroupper`). Everything in this workspace is
//! compiled for baseline x86-64, so scalar `f64` code uses legacy-SSE encodings, and with a dirty
//! upper state every such instruction carries a merge dependency on the full register: measured on
//! this project's 2-core Xeon (Sapphire Rapids), a scalar loop ran **15–21× slower** after one
//! 64×12·12×64 product — until some later AVX code happened to execute `vzeroupper` — and at full
//! speed again right after [`zero_upper`] (`cargo run --release -p geom-core --example
//! upper_state`). faer's sparse and dense Cholesky and LDLᵀ factorisations and solves do not dirty
//! the state (measured the same way), so only direct `matmul` calls need it: use
//! [`super::dense::matmul`], which calls [`zero_upper`] after the product.

/// Executes `vzeroupper` when the CPU has AVX (a no-op elsewhere); about one cycle.
#[inline]
pub fn zero_upper() {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: AVX is present (checked above), which is all `vzeroupper` needs.
            unsafe { zero_upper_avx() }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn zero_upper_avx() {
    std::arch::x86_64::_mm256_zeroupper();
}
