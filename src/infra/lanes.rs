//! One point or four side by side: the arithmetic the stress update's formulas are written
//! in, so that each formula exists once and runs on a scalar `f64` (one point) or on
//! [`F64x4`] (four points, one per SIMD lane).
//!
//! The stress update treats four points at a time: its Jaumann rotation and the elastic
//! increment are a chain of ~80 dependent multiply-adds and a division per point, which one
//! point at a time keeps the core waiting on latencies; four in the lanes of one AVX register
//! take about the time of one. Every operation is done lane by lane with the same rounding as
//! the scalar one, so a point's result does not depend on which lane, or which path, it took.

use std::ops::{Add, Div, Mul, Sub};

/// `a·b + c` rounded once (IEEE 754 fusedMultiplyAdd), on every machine: one instruction
/// where the build targets a CPU with fused multiply-add (x86-64 with FMA, which
/// `.cargo/config.toml`'s `target-cpu=native` turns on where the CPU has it; every
/// aarch64), the C library's `fma` elsewhere (slower, the same bits). So a run gives the
/// same bits whichever machine built it, and for every thread count.
#[inline(always)]
pub fn madd(a: f64, b: f64, c: f64) -> f64 {
    a.mul_add(b, c)
}

/// Four f64 lanes (one 256-bit AVX register where the build targets AVX).
pub type F64x4 = wide::f64x4;

/// Points per group in the stress update.
pub const LANES: usize = 4;

/// The operations a formula over [`Lanes`] may use: `+ − × ÷` lane by lane, constants,
/// [`Lanes::madd`], which rounds exactly like [`madd`], square root, and the larger or smaller
/// of two values (as `f64::max` and `f64::min`: a NaN loses to a number).
pub trait Lanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// `v` in every lane.
    fn splat(v: f64) -> Self;
    /// `a·b + c` lane by lane, rounded once, as [`madd`].
    fn madd(a: Self, b: Self, c: Self) -> Self;
    /// Square root, correctly rounded.
    fn sqrt(self) -> Self;
    /// The larger value, as `f64::max`.
    fn max(self, b: Self) -> Self;
    /// The smaller value, as `f64::min`.
    fn min(self, b: Self) -> Self;
}

impl Lanes for f64 {
    #[inline(always)]
    fn splat(v: f64) -> f64 {
        v
    }
    #[inline(always)]
    fn madd(a: f64, b: f64, c: f64) -> f64 {
        madd(a, b, c)
    }
    #[inline(always)]
    fn sqrt(self) -> f64 {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn max(self, b: f64) -> f64 {
        f64::max(self, b)
    }
    #[inline(always)]
    fn min(self, b: f64) -> f64 {
        f64::min(self, b)
    }
}

impl Lanes for F64x4 {
    #[inline(always)]
    fn splat(v: f64) -> F64x4 {
        F64x4::splat(v)
    }
    #[inline(always)]
    fn madd(a: F64x4, b: F64x4, c: F64x4) -> F64x4 {
        if cfg!(all(target_feature = "avx", target_feature = "fma")) {
            // One fused instruction for the four lanes.
            a.mul_add(b, c)
        } else {
            // `wide` rounds twice here (a·b, then + c); lane by lane through `madd` keeps
            // the one rounding.
            let (a, b, c) = (a.to_array(), b.to_array(), c.to_array());
            F64x4::new(std::array::from_fn(|i| madd(a[i], b[i], c[i])))
        }
    }
    #[inline(always)]
    fn sqrt(self) -> F64x4 {
        F64x4::sqrt(self)
    }
    #[inline(always)]
    fn max(self, b: F64x4) -> F64x4 {
        F64x4::max(self, b)
    }
    #[inline(always)]
    fn min(self, b: F64x4) -> F64x4 {
        F64x4::min(self, b)
    }
}

/// The lanes `f(0), …, f(3)`.
#[inline(always)]
pub fn gather(f: impl Fn(usize) -> f64) -> F64x4 {
    F64x4::new([f(0), f(1), f(2), f(3)])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lane_multiply_add_rounds_like_the_scalar_one() {
        // 1 + 2⁻⁵² squared: the exact product 1 + 2⁻⁵¹ + 2⁻¹⁰⁴ loses its last term when
        // rounded before the add, so fused and unfused differ in the last bit; the lanes,
        // like `madd`, round once on every build.
        let a = 1.0 + f64::EPSILON;
        let c = -(1.0 + 2.0 * f64::EPSILON);
        let lane = <F64x4 as Lanes>::madd(F64x4::splat(a), F64x4::splat(a), F64x4::splat(c));
        for v in lane.to_array() {
            assert_eq!(v.to_bits(), madd(a, a, c).to_bits());
            assert_eq!(v, 2f64.powi(-104));
        }
    }
}
