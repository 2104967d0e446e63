//! The instruction set of the optimised twins' streaming loops, chosen at run time.
//!
//! The build targets baseline x86-64 (SSE2, two doubles per vector) and uses no target-cpu
//! flags. On a CPU with AVX (four doubles per vector) the uniform right-hand side
//! (`bar::kernels::rhs_fast`), the uniform energy sums (`bar::kernels::energy_fast`) and the
//! twisted solves' sweeps ([`super::ldlt_fast`], [`super::block_tridiag_fast`]) run through
//! `run`, compiled with AVX's three-operand instructions, their streaming loops vectorised.
//! The bits do not change: AVX without FMA performs the same IEEE operations in the same order
//! (Rust never contracts `a * b + c` into a fused multiply-add), and every sum has its lane
//! order fixed in the source. The twins' tests compare the AVX and the portable paths bit for
//! bit.

/// A streaming kernel with its arguments. `call` must be `#[inline(always)]`: it is then
/// compiled into each caller, including the AVX one (a closure would be compiled once, for
/// the baseline, and called from there).
pub(crate) trait Kernel {
    type Output;
    fn call(self) -> Self::Output;
}

/// Runs `kernel`, compiled for AVX when the CPU has it (detected once; std caches the
/// answer), else as built.
#[inline(always)]
pub(crate) fn run<K: Kernel>(kernel: K) -> K::Output {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU supports AVX, the only feature `with_avx` enables.
        return unsafe { with_avx(kernel) };
    }
    kernel.call()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline(never)]
unsafe fn with_avx<K: Kernel>(kernel: K) -> K::Output {
    kernel.call()
}
