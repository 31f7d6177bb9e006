//! The spatial dimension as a type parameter.
//!
//! Every solver type is generic over [`Dim`], implemented by [`Dim2`] (plane strain, unit
//! thickness), [`DimAxi`] (axisymmetric, per radian) and [`Dim3`]. A 2D scene therefore
//! stores two-component vectors, visits four nodes per point with linear shape functions
//! and never touches a third axis; the only 3D quantity it keeps is the out-of-plane normal
//! stress, which plane strain requires and which is the hoop stress σ_θθ in axisymmetry.

use crate::infra::lanes::{madd, Lanes};
use crate::tensor::{PlanarSym3, StoredSym, Sym, Sym3};
use glam::{DMat2, DMat3, DVec2, DVec3};
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// Operations the solver needs from a position/velocity vector (m, m/s, N, ...).
pub trait Vector:
    Copy
    + Send
    + Sync
    + Debug
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<f64, Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + 'static
{
    /// The zero vector.
    const ZERO: Self;
    /// Component `axis` (0 = x, 1 = y, 2 = z).
    fn get(self, axis: usize) -> f64;
    /// Sets component `axis`.
    fn set(&mut self, axis: usize, value: f64);
    /// Scalar product.
    fn dot(self, other: Self) -> f64;
    /// True when every component is finite.
    fn is_finite(self) -> bool;
    /// `self·k + acc`, each component rounded once (see [`crate::infra::lanes::madd`]).
    fn madd(self, k: f64, acc: Self) -> Self;
}

/// The same glam methods serve both vector types.
macro_rules! impl_vector {
    ($t:ty) => {
        impl Vector for $t {
            const ZERO: Self = <$t>::ZERO;
            #[inline(always)]
            fn get(self, axis: usize) -> f64 {
                self[axis]
            }
            #[inline(always)]
            fn set(&mut self, axis: usize, value: f64) {
                self[axis] = value;
            }
            #[inline(always)]
            fn dot(self, other: Self) -> f64 {
                <$t>::dot(self, other)
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            #[inline(always)]
            fn madd(self, k: f64, acc: Self) -> Self {
                let (v, a) = (self.to_array(), acc.to_array());
                <$t>::from_array(std::array::from_fn(|i| madd(v[i], k, a[i])))
            }
        }
    };
}

impl_vector!(DVec2);
impl_vector!(DVec3);

/// A spatial dimension: its vector and velocity-gradient types and the few operations that
/// differ between plane strain and 3D.
pub trait Dim: Copy + Send + Sync + Debug + Default + 'static {
    /// Number of spatial axes (2 or 3).
    const N: usize;
    /// Axisymmetric about the y axis, x being the radius r (a point's volume and mass are
    /// per radian; the hoop strain rate v_r/r and the hoop stress's force −σ_θθ/r join the
    /// in-plane ones).
    const AXISYMMETRIC: bool = false;
    /// Normal strains that can be non-zero: 2 in plane strain, 3 in 3D and in axisymmetry
    /// (the hoop strain).
    const STRAIN_AXES: usize = Self::N;
    /// Position, velocity, force (m, m/s, N).
    type Vec: Vector;
    /// Velocity gradient L_ij = ∂v_i/∂x_j (1/s), column-major glam matrix.
    type Mat: Copy + Send + Sync + Debug + PartialEq + 'static;
    /// A point's stored stress (Pa): [`PlanarSym3`] in plane strain, [`Sym3`] in 3D.
    type Stress: StoredSym;

    /// The zero velocity gradient.
    const MAT_ZERO: Self::Mat;

    /// Builds a vector from the first `N` entries of `xyz` (extra entries are ignored).
    fn vec_from(xyz: [f64; 3]) -> Self::Vec;
    /// The vector padded with zeros to three components.
    fn vec_to3(v: Self::Vec) -> [f64; 3];
    /// Strain increment sym(L)·dt and spin increment skew(L)·dt embedded in 3D
    /// (plane strain: zero out-of-plane components), with `l(i, j)` = L_ij (1/s) of one
    /// point or four in lanes. Spin is (W_yz, W_zx, W_xy).
    fn strain_spin<T: Lanes>(l: impl Fn(usize, usize) -> T, dt: T) -> (Sym<T>, [T; 3]);
    /// Entry (i, j) of a matrix: row i, column j.
    fn mat_entry(m: &Self::Mat, i: usize, j: usize) -> f64;
    /// The stress rotated by a spin increment from [`Dim::strain_spin`] (the Jaumann term),
    /// of one point or four in lanes; plane strain's spin is about z alone, and its rotation
    /// does only that.
    fn jaumann_rotate<T: Lanes>(s: &Sym<T>, w: [T; 3]) -> Sym<T>;
    /// det(I + L·dt): the volume ratio of one step.
    fn volume_ratio(l: &Self::Mat, dt: f64) -> f64;
    /// `m += k·I`.
    fn add_identity(m: &mut Self::Mat, k: f64);
    /// tr(L): the rate of volume change of a velocity gradient (1/s), the hoop rate
    /// v_r/r included in axisymmetry; `add_identity(l, k)` raises it by `STRAIN_AXES`·k.
    #[inline(always)]
    fn volumetric_rate(l: &Self::Mat) -> f64 {
        Self::strain_spin(|i, j| Self::mat_entry(l, i, j), 1.0).0.trace()
    }
    /// The matrix whose column j is `c[j]`, for the first `N` columns.
    fn mat_from_cols(c: [Self::Vec; 3]) -> Self::Mat;
    /// Completes a point's velocity gradient `l` from its place `x` and velocity `v`: the
    /// hoop strain rate v_r/r in axisymmetry, nothing otherwise.
    #[inline(always)]
    fn complete_gradient(_l: &mut Self::Mat, _x: Self::Vec, _v: Self::Vec) {}
}

/// Plane strain, unit thickness (m).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Dim2;

/// Three dimensions.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Dim3;

/// Axisymmetric about the y axis: x is the radius r ≥ 0, y the axial coordinate z, and the
/// stress's out-of-plane normal the hoop stress σ_θθ. Volumes and masses are per radian
/// (V = r · area), so are forces; the velocity gradient carries v_r/r at (2, 2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DimAxi;

impl Dim for Dim2 {
    const N: usize = 2;
    type Vec = DVec2;
    type Mat = DMat2;
    type Stress = PlanarSym3;
    const MAT_ZERO: DMat2 = DMat2::ZERO;

    #[inline(always)]
    fn vec_from(xyz: [f64; 3]) -> DVec2 {
        DVec2::new(xyz[0], xyz[1])
    }
    #[inline(always)]
    fn vec_to3(v: DVec2) -> [f64; 3] {
        [v.x, v.y, 0.0]
    }
    #[inline(always)]
    fn jaumann_rotate<T: Lanes>(s: &Sym<T>, w: [T; 3]) -> Sym<T> {
        crate::tensor::jaumann_rotate_about_z(s, w[2])
    }
    #[inline(always)]
    fn strain_spin<T: Lanes>(l: impl Fn(usize, usize) -> T, dt: T) -> (Sym<T>, [T; 3]) {
        let (l00, l10, l01, l11) = (l(0, 0), l(1, 0), l(0, 1), l(1, 1));
        let (half, zero) = (T::splat(0.5), T::splat(0.0));
        let strain = Sym {
            xx: l00 * dt,
            yy: l11 * dt,
            xy: half * (l01 + l10) * dt,
            zz: zero,
            yz: zero,
            zx: zero,
        };
        (strain, [zero, zero, half * (l01 - l10) * dt])
    }
    #[inline(always)]
    fn mat_entry(m: &DMat2, i: usize, j: usize) -> f64 {
        m.col(j)[i]
    }
    #[inline(always)]
    fn volume_ratio(l: &DMat2, dt: f64) -> f64 {
        (DMat2::IDENTITY + *l * dt).determinant()
    }
    #[inline(always)]
    fn add_identity(m: &mut DMat2, k: f64) {
        m.x_axis.x += k;
        m.y_axis.y += k;
    }
    #[inline(always)]
    fn mat_from_cols(c: [DVec2; 3]) -> DMat2 {
        DMat2::from_cols(c[0], c[1])
    }
}

impl Dim for Dim3 {
    const N: usize = 3;
    type Vec = DVec3;
    type Mat = DMat3;
    type Stress = Sym3;
    const MAT_ZERO: DMat3 = DMat3::ZERO;

    #[inline(always)]
    fn vec_from(xyz: [f64; 3]) -> DVec3 {
        DVec3::from_array(xyz)
    }
    #[inline(always)]
    fn vec_to3(v: DVec3) -> [f64; 3] {
        v.to_array()
    }
    #[inline(always)]
    fn jaumann_rotate<T: Lanes>(s: &Sym<T>, w: [T; 3]) -> Sym<T> {
        crate::tensor::jaumann_rotate(s, w)
    }
    #[inline(always)]
    fn strain_spin<T: Lanes>(c: impl Fn(usize, usize) -> T, dt: T) -> (Sym<T>, [T; 3]) {
        let half = T::splat(0.5);
        let strain = Sym {
            xx: c(0, 0) * dt,
            yy: c(1, 1) * dt,
            zz: c(2, 2) * dt,
            xy: half * (c(0, 1) + c(1, 0)) * dt,
            yz: half * (c(1, 2) + c(2, 1)) * dt,
            zx: half * (c(2, 0) + c(0, 2)) * dt,
        };
        let spin = [
            half * (c(1, 2) - c(2, 1)) * dt,
            half * (c(2, 0) - c(0, 2)) * dt,
            half * (c(0, 1) - c(1, 0)) * dt,
        ];
        (strain, spin)
    }
    #[inline(always)]
    fn mat_entry(m: &DMat3, i: usize, j: usize) -> f64 {
        m.col(j)[i]
    }
    #[inline(always)]
    fn volume_ratio(l: &DMat3, dt: f64) -> f64 {
        (DMat3::IDENTITY + *l * dt).determinant()
    }
    #[inline(always)]
    fn add_identity(m: &mut DMat3, k: f64) {
        m.x_axis.x += k;
        m.y_axis.y += k;
        m.z_axis.z += k;
    }
    #[inline(always)]
    fn mat_from_cols(c: [DVec3; 3]) -> DMat3 {
        DMat3::from_cols(c[0], c[1], c[2])
    }
}

impl Dim for DimAxi {
    const N: usize = 2;
    const AXISYMMETRIC: bool = true;
    const STRAIN_AXES: usize = 3;
    type Vec = DVec2;
    /// The in-plane gradient in the upper 2 × 2, the hoop rate v_r/r at (2, 2).
    type Mat = DMat3;
    type Stress = PlanarSym3;
    const MAT_ZERO: DMat3 = DMat3::ZERO;

    #[inline(always)]
    fn vec_from(xyz: [f64; 3]) -> DVec2 {
        Dim2::vec_from(xyz)
    }
    #[inline(always)]
    fn vec_to3(v: DVec2) -> [f64; 3] {
        Dim2::vec_to3(v)
    }
    #[inline(always)]
    fn jaumann_rotate<T: Lanes>(s: &Sym<T>, w: [T; 3]) -> Sym<T> {
        // The spin is in the r–z plane, about the hoop direction, as plane strain's.
        crate::tensor::jaumann_rotate_about_z(s, w[2])
    }
    #[inline(always)]
    fn strain_spin<T: Lanes>(l: impl Fn(usize, usize) -> T, dt: T) -> (Sym<T>, [T; 3]) {
        let (mut strain, spin) = Dim2::strain_spin(&l, dt);
        strain.zz = l(2, 2) * dt;
        (strain, spin)
    }
    #[inline(always)]
    fn mat_entry(m: &DMat3, i: usize, j: usize) -> f64 {
        Dim3::mat_entry(m, i, j)
    }
    #[inline(always)]
    fn volume_ratio(l: &DMat3, dt: f64) -> f64 {
        // det(I + L dt) with L's hoop entry: the in-plane ratio times (1 + v_r/r dt).
        Dim3::volume_ratio(l, dt)
    }
    #[inline(always)]
    fn add_identity(m: &mut DMat3, k: f64) {
        Dim3::add_identity(m, k)
    }
    #[inline(always)]
    fn mat_from_cols(c: [DVec2; 3]) -> DMat3 {
        DMat3::from_cols(c[0].extend(0.0), c[1].extend(0.0), DVec3::ZERO)
    }
    #[inline(always)]
    fn complete_gradient(l: &mut DMat3, x: DVec2, v: DVec2) {
        // v_r/r (1/s); points lie off the axis (r > 0) by construction.
        l.z_axis.z = v.x / x.x;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn madd_rounds_once_on_every_build() {
        // (1 + 2⁻³⁰)(1 − 2⁻³⁰) − 1 = −2⁻⁶⁰ exactly; the product alone rounds to 1, so a
        // multiply-add rounded twice would give 0.
        let (a, b) = (1.0 + 2f64.powi(-30), 1.0 - 2f64.powi(-30));
        let expected = -(2f64.powi(-60));
        assert_eq!(madd(a, b, -1.0), expected);
        let v = DVec3::splat(a).madd(b, DVec3::splat(-1.0));
        assert_eq!(v, DVec3::splat(expected));
        let v = DVec2::splat(a).madd(b, DVec2::splat(-1.0));
        assert_eq!(v, DVec2::splat(expected));
    }
}
