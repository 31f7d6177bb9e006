//! Symmetric second-order tensors (stress in Pa, strain increments, dimensionless), their
//! principal values, and the objective (Jaumann) rotation of stress.
//!
//! Sign convention: tension positive, as in continuum mechanics.

use crate::infra::lanes::{F64x4, Lanes, LANES};
use glam::{DMat3, DVec3};
use std::ops::{Add, AddAssign, Mul, Sub, SubAssign};

/// A symmetric 3×3 tensor stored by its six independent components, of one point
/// ([`Sym3`]) or of four side by side, one per lane ([`Sym3x4`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sym<T> {
    /// Component xx.
    pub xx: T,
    /// Component yy.
    pub yy: T,
    /// Component zz.
    pub zz: T,
    /// Component xy (= yx).
    pub xy: T,
    /// Component yz (= zy).
    pub yz: T,
    /// Component zx (= xz).
    pub zx: T,
}

/// A symmetric 3×3 tensor (stress in Pa, strain increment).
pub type Sym3 = Sym<f64>;

/// The symmetric tensors of four points, one per lane (see [`crate::infra::lanes`]).
pub type Sym3x4 = Sym<F64x4>;

impl<T: Lanes> Sym<T> {
    /// The symmetric tensor whose six independent entries are `e(i, j)` for (i, j) = (0, 0),
    /// (1, 1), (2, 2), (0, 1), (1, 2), (2, 0): `e` is asked for those only.
    #[inline(always)]
    pub fn from_fn(e: impl Fn(usize, usize) -> T) -> Sym<T> {
        Sym {
            xx: e(0, 0),
            yy: e(1, 1),
            zz: e(2, 2),
            xy: e(0, 1),
            yz: e(1, 2),
            zx: e(2, 0),
        }
    }

    /// Trace (sum of the diagonal).
    #[inline(always)]
    pub fn trace(&self) -> T {
        self.xx + self.yy + self.zz
    }

    /// Double contraction a:b.
    #[inline(always)]
    pub fn ddot(&self, b: &Sym<T>) -> T {
        self.xx * b.xx
            + self.yy * b.yy
            + self.zz * b.zz
            + T::splat(2.0) * (self.xy * b.xy + self.yz * b.yz + self.zx * b.zx)
    }

    /// Frobenius norm sqrt(a:a).
    #[inline(always)]
    pub fn norm(&self) -> T {
        self.ddot(self).sqrt()
    }

    /// Mean stress p = tr/3 and the norm of the deviatoric part |s| = sqrt(s:s).
    #[inline(always)]
    pub fn mean_and_deviatoric_norm(&self) -> (T, T) {
        let p = self.trace() / T::splat(3.0);
        let (a, b, c) = (self.xx - p, self.yy - p, self.zz - p);
        let off = self.xy * self.xy + self.yz * self.yz + self.zx * self.zx;
        (p, (a * a + b * b + c * c + T::splat(2.0) * off).sqrt())
    }

    /// Principal values in descending order of a tensor whose z axis is principal
    /// (yz = zx = 0, see [`Sym3::has_principal_z`]); meaningless otherwise. One square root.
    #[inline(always)]
    pub fn planar_principal_values(&self) -> [T; 3] {
        // c + r ≥ c − r: only zz has to find its place, which min/max do without a branch
        // to mispredict, to the same values as the sorting network.
        let [hi, lo, zz] = Planar::of(self).values(self);
        [hi.max(zz), lo.max(hi.min(zz)), lo.min(zz)]
    }
}

impl Sym3x4 {
    /// The tensors `f(0), …, f(3)` in lanes 0 to 3.
    #[inline(always)]
    pub fn gather(f: impl Fn(usize) -> Sym3) -> Sym3x4 {
        // Four named values rather than `array::from_fn`: built through memory, that array
        // was stored a point at a time and read back across the halves of those stores,
        // which the CPU cannot forward (a fifth of the slope's stress update in some builds).
        let (s0, s1, s2, s3) = (f(0), f(1), f(2), f(3));
        let lanes = |c: fn(&Sym3) -> f64| F64x4::new([c(&s0), c(&s1), c(&s2), c(&s3)]);
        Sym {
            xx: lanes(|s| s.xx),
            yy: lanes(|s| s.yy),
            zz: lanes(|s| s.zz),
            xy: lanes(|s| s.xy),
            yz: lanes(|s| s.yz),
            zx: lanes(|s| s.zx),
        }
    }

    /// Which lanes hold a tensor with z as a principal axis (yz = zx = 0): bit l for lane l.
    #[inline(always)]
    pub fn principal_z_lanes(&self) -> u32 {
        let zero = F64x4::splat(0.0);
        (self.yz.simd_eq(zero) & self.zx.simd_eq(zero)).to_bitmask()
    }

    /// The four tensors, lane by lane.
    #[inline(always)]
    pub fn lanes(&self) -> [Sym3; LANES] {
        // Written out rather than with `[..].map`: left outlined, that copy went through
        // memory and stalled on loading lanes stored one by one (a quarter of the slope's
        // stress update in some builds).
        let c = [
            self.xx.to_array(),
            self.yy.to_array(),
            self.zz.to_array(),
            self.xy.to_array(),
            self.yz.to_array(),
            self.zx.to_array(),
        ];
        std::array::from_fn(|l| Sym {
            xx: c[0][l],
            yy: c[1][l],
            zz: c[2][l],
            xy: c[3][l],
            yz: c[4][l],
            zx: c[5][l],
        })
    }
}

/// How a material point stores its stress: the six components of a [`Sym3`] in 3D, the
/// four of [`PlanarSym3`] in plane strain, where yz and zx are zero by construction.
/// Materials and the Jaumann rotation work on [`Sym3`]; a point's stress is widened on load
/// and narrowed on store, which in plane strain the compiler folds into the arithmetic.
pub trait StoredSym: Copy + Send + Sync + std::fmt::Debug + Default + PartialEq + 'static {
    /// The full tensor.
    fn to_sym3(&self) -> Sym3;
    /// The stored form of `s`. In plane strain `s` must have z principal (yz = zx = 0).
    fn from_sym3(s: &Sym3) -> Self;
}

impl StoredSym for Sym3 {
    #[inline(always)]
    fn to_sym3(&self) -> Sym3 {
        *self
    }
    #[inline(always)]
    fn from_sym3(s: &Sym3) -> Self {
        *s
    }
}

/// A symmetric 3×3 tensor with z principal (yz = zx = 0), stored by its four non-zero
/// components: the stress of plane strain, where σzz ≠ 0 but no shear leaves the plane.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlanarSym3 {
    /// Component xx.
    pub xx: f64,
    /// Component yy.
    pub yy: f64,
    /// Component zz.
    pub zz: f64,
    /// Component xy (= yx).
    pub xy: f64,
}

impl StoredSym for PlanarSym3 {
    #[inline(always)]
    fn to_sym3(&self) -> Sym3 {
        Sym3 {
            xx: self.xx,
            yy: self.yy,
            zz: self.zz,
            xy: self.xy,
            yz: 0.0,
            zx: 0.0,
        }
    }
    #[inline(always)]
    fn from_sym3(s: &Sym3) -> Self {
        debug_assert!(s.has_principal_z(), "out-of-plane shear in plane strain: {s:?}");
        PlanarSym3 {
            xx: s.xx,
            yy: s.yy,
            zz: s.zz,
            xy: s.xy,
        }
    }
}

impl Sym3 {
    /// The zero tensor.
    pub const ZERO: Sym3 = Sym3 {
        xx: 0.0,
        yy: 0.0,
        zz: 0.0,
        xy: 0.0,
        yz: 0.0,
        zx: 0.0,
    };
    /// The identity tensor.
    pub const IDENTITY: Sym3 = Sym3 {
        xx: 1.0,
        yy: 1.0,
        zz: 1.0,
        xy: 0.0,
        yz: 0.0,
        zx: 0.0,
    };

    /// A diagonal tensor.
    pub const fn diagonal(a: f64, b: f64, c: f64) -> Sym3 {
        Sym3 {
            xx: a,
            yy: b,
            zz: c,
            xy: 0.0,
            yz: 0.0,
            zx: 0.0,
        }
    }

    /// True when every component is finite.
    #[inline(always)]
    pub fn is_finite(&self) -> bool {
        self.to_array().iter().all(|c| c.is_finite())
    }

    /// Components in the order xx, yy, zz, xy, yz, zx.
    #[inline(always)]
    pub fn to_array(&self) -> [f64; 6] {
        [self.xx, self.yy, self.zz, self.xy, self.yz, self.zx]
    }

    /// The full matrix.
    #[inline(always)]
    pub fn to_mat3(&self) -> DMat3 {
        DMat3::from_cols(
            DVec3::new(self.xx, self.xy, self.zx),
            DVec3::new(self.xy, self.yy, self.yz),
            DVec3::new(self.zx, self.yz, self.zz),
        )
    }

    /// The symmetric part of a matrix.
    #[inline(always)]
    pub fn from_mat3(m: &DMat3) -> Sym3 {
        let c = |i: usize, j: usize| m.col(j)[i];
        Sym3 {
            xx: c(0, 0),
            yy: c(1, 1),
            zz: c(2, 2),
            xy: 0.5 * (c(0, 1) + c(1, 0)),
            yz: 0.5 * (c(1, 2) + c(2, 1)),
            zx: 0.5 * (c(2, 0) + c(0, 2)),
        }
    }

    /// R·a·Rᵀ built from principal values `p` and the principal directions (columns of `r`).
    #[inline]
    pub fn from_principal(p: [f64; 3], r: &DMat3) -> Sym3 {
        // a_ij = Σ_k p_k r_ik r_jk, component by component (cheaper than two products).
        let (c0, c1, c2) = (r.x_axis, r.y_axis, r.z_axis);
        Sym3::from_fn(|i, j| p[0] * c0[i] * c0[j] + p[1] * c1[i] * c1[j] + p[2] * c2[i] * c2[j])
    }

    /// Principal values in descending order (σ1 ≥ σ2 ≥ σ3) and the matching unit
    /// eigenvectors as the columns of a rotation matrix.
    pub fn eigen(&self) -> ([f64; 3], DMat3) {
        // Plane strain (and any state with z as a principal axis): closed form in the x-y
        // plane, several times cheaper than Jacobi sweeps.
        let (vals, vecs) = if self.has_principal_z() {
            planar_eigen(self)
        } else {
            jacobi_eigen(self)
        };
        let order = descending_order(vals);
        let p = order.map(|i| vals[i]);
        let r = DMat3::from_cols(vecs.col(order[0]), vecs.col(order[1]), vecs.col(order[2]));
        (p, r)
    }

    /// Principal values in descending order, bit for bit those of [`Sym3::eigen`] for a finite
    /// tensor (up to the sign of a zero); when z is a principal axis they cost one square root, without the eigenvectors.
    pub fn principal_values(&self) -> [f64; 3] {
        if self.has_principal_z() {
            self.planar_principal_values()
        } else {
            self.eigen().0
        }
    }

    /// True when z is a principal axis (yz = zx = 0), as in every plane-strain state.
    #[inline(always)]
    pub fn has_principal_z(&self) -> bool {
        self.yz == 0.0 && self.zx == 0.0
    }
}

/// Indices of `v` from the largest value to the smallest (a three-element sorting network).
#[inline(always)]
fn descending_order(v: [f64; 3]) -> [usize; 3] {
    let mut order = [0usize, 1, 2];
    if v[order[0]] < v[order[1]] {
        order.swap(0, 1);
    }
    if v[order[1]] < v[order[2]] {
        order.swap(1, 2);
    }
    if v[order[0]] < v[order[1]] {
        order.swap(0, 1);
    }
    order
}

/// The x-y block of a tensor whose z axis is principal as centre c, half-difference d and
/// radius r of its Mohr circle: principal values c ± r and zz.
struct Planar<T> {
    c: T,
    d: T,
    r: T,
}

impl<T: Lanes> Planar<T> {
    #[inline(always)]
    fn of(s: &Sym<T>) -> Planar<T> {
        let half = T::splat(0.5);
        let d = half * (s.xx - s.yy);
        Planar {
            c: half * (s.xx + s.yy),
            d,
            // Plain sqrt, not hypot: stresses are far from overflow and hypot is slow in glibc.
            r: (d * d + s.xy * s.xy).sqrt(),
        }
    }

    /// Principal values, unsorted: c + r, c − r, zz.
    #[inline(always)]
    fn values(&self, s: &Sym<T>) -> [T; 3] {
        [self.c + self.r, self.c - self.r, s.zz]
    }
}

/// Eigen-decomposition of a tensor whose z axis is principal: the x-y block in closed form
/// (no trigonometry: the eigenvector of the larger value is (d + r, xy) normalised, taking
/// the better-conditioned of the two equivalent forms).
fn planar_eigen(s: &Sym3) -> ([f64; 3], DMat3) {
    let planar = Planar::of(s);
    let (d, r) = (planar.d, planar.r);
    let (ex, ey) = if r == 0.0 {
        (1.0, 0.0)
    } else if d >= 0.0 {
        let n = ((d + r) * (d + r) + s.xy * s.xy).sqrt();
        ((d + r) / n, s.xy / n)
    } else {
        let n = (s.xy * s.xy + (r - d) * (r - d)).sqrt();
        (s.xy / n, (r - d) / n)
    };
    let vecs = DMat3::from_cols(DVec3::new(ex, ey, 0.0), DVec3::new(-ey, ex, 0.0), DVec3::Z);
    (planar.values(s), vecs)
}

/// Cyclic Jacobi eigen-decomposition of a symmetric 3×3 tensor. Robust for repeated
/// eigenvalues (common here: a uniaxial or zero stress), which closed forms handle badly.
fn jacobi_eigen(s: &Sym3) -> ([f64; 3], DMat3) {
    let mut a = [[s.xx, s.xy, s.zx], [s.xy, s.yy, s.yz], [s.zx, s.yz, s.zz]];
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let scale = s.norm();
    for _sweep in 0..32 {
        let off = a[0][1].abs() + a[1][2].abs() + a[0][2].abs();
        if off <= f64::EPSILON * 1e-3 * scale || off == 0.0 {
            break;
        }
        for (p, q) in [(0usize, 1usize), (0, 2), (1, 2)] {
            let apq = a[p][q];
            if apq == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let sn = t * c;
            for k in 0..3 {
                let akp = a[k][p];
                let akq = a[k][q];
                a[k][p] = c * akp - sn * akq;
                a[k][q] = sn * akp + c * akq;
            }
            for k in 0..3 {
                let apk = a[p][k];
                let aqk = a[q][k];
                a[p][k] = c * apk - sn * aqk;
                a[q][k] = sn * apk + c * aqk;
            }
            for row in v.iter_mut() {
                let vp = row[p];
                let vq = row[q];
                row[p] = c * vp - sn * vq;
                row[q] = sn * vp + c * vq;
            }
        }
    }
    let vecs = DMat3::from_cols(
        DVec3::new(v[0][0], v[1][0], v[2][0]),
        DVec3::new(v[0][1], v[1][1], v[2][1]),
        DVec3::new(v[0][2], v[1][2], v[2][2]),
    );
    ([a[0][0], a[1][1], a[2][2]], vecs)
}

/// Rotates `stress` by the spin increment `w = (W_yz, W_zx, W_xy)·dt` (the skew part of the
/// velocity gradient times the step): the Jaumann-rate term σ̇ = … + Wσ − σW of eq. (8), for
/// one point (`T = f64`) or four in lanes (`T = F64x4`), with the same bits either way.
///
/// The rotation is the Cayley transform R = (I − W/2)⁻¹(I + W/2) (Hughes–Winget), which is
/// exactly orthogonal: a rigid rotation leaves the principal stresses unchanged to round-off,
/// where the forward-Euler form σ + Wσ − σW would inflate them by (1 + |w|²) every step.
/// No branch on the spin (a zero spin gives R = I exactly), so that lanes need none.
#[inline(always)]
pub fn jaumann_rotate<T: Lanes>(stress: &Sym<T>, w: [T; 3]) -> Sym<T> {
    let half = T::splat(0.5);
    // Half-spin Â = W/2 with W_xy = w[2], W_yz = w[0], W_zx = w[1] (W skew), so that
    // Âv = v × â with â = (a, b, c) and Â² = ââᵀ − |â|² I.
    let (a, b, c) = (half * w[0], half * w[1], half * w[2]);
    let n2 = a * a + b * b + c * c;
    // Cayley: R = I + 2/(1 + |â|²) (Â + Â²).
    let one = T::splat(1.0);
    let k = T::splat(2.0) / (one + n2);
    let d = one - k * n2;
    let r = [
        [d + k * a * a, k * (a * b + c), k * (a * c - b)],
        [k * (a * b - c), d + k * b * b, k * (b * c + a)],
        [k * (a * c + b), k * (b * c - a), d + k * c * c],
    ];
    // R σ Rᵀ: T = Rσ in full, then only the six independent entries of T Rᵀ.
    let s = [
        [stress.xx, stress.xy, stress.zx],
        [stress.xy, stress.yy, stress.yz],
        [stress.zx, stress.yz, stress.zz],
    ];
    let t: [[T; 3]; 3] = std::array::from_fn(|i| {
        std::array::from_fn(|j| T::madd(r[i][0], s[0][j], T::madd(r[i][1], s[1][j], r[i][2] * s[2][j])))
    });
    Sym::from_fn(|i, j| T::madd(t[i][0], r[j][0], T::madd(t[i][1], r[j][1], t[i][2] * r[j][2])))
}

/// [`jaumann_rotate`] for a spin `wxy` = W_xy·dt about z only, as in all of plane strain:
/// the Cayley rotation in the x-y plane, cos θ = (1 − a²)/(1 + a²), sin θ = 2a/(1 + a²) with
/// a = W_xy/2 (a third of the general rotation's arithmetic).
#[inline(always)]
pub fn jaumann_rotate_about_z<T: Lanes>(s: &Sym<T>, wxy: T) -> Sym<T> {
    let a = T::splat(0.5) * wxy;
    let one = T::splat(1.0);
    let k = one / (one + a * a);
    let (c, sn) = ((one - a * a) * k, T::splat(2.0) * a * k);
    // σ' = R σ Rᵀ with R = [[c, sn], [−sn, c]] in the x-y block.
    let (xx, yy, xy) = (s.xx, s.yy, s.xy);
    let cc = c * c;
    let ss = sn * sn;
    let cs = c * sn;
    let two = T::splat(2.0);
    Sym {
        xx: cc * xx + two * cs * xy + ss * yy,
        yy: ss * xx - two * cs * xy + cc * yy,
        xy: (cc - ss) * xy + cs * (yy - xx),
        zz: s.zz,
        yz: c * s.yz - sn * s.zx,
        zx: c * s.zx + sn * s.yz,
    }
}

impl<T: Lanes> Add for Sym<T> {
    type Output = Sym<T>;
    #[inline(always)]
    fn add(self, b: Sym<T>) -> Sym<T> {
        Sym {
            xx: self.xx + b.xx,
            yy: self.yy + b.yy,
            zz: self.zz + b.zz,
            xy: self.xy + b.xy,
            yz: self.yz + b.yz,
            zx: self.zx + b.zx,
        }
    }
}

impl Sub for Sym3 {
    type Output = Sym3;
    #[inline(always)]
    fn sub(self, b: Sym3) -> Sym3 {
        self + b * -1.0
    }
}

impl Mul<f64> for Sym3 {
    type Output = Sym3;
    #[inline(always)]
    fn mul(self, k: f64) -> Sym3 {
        Sym3 {
            xx: self.xx * k,
            yy: self.yy * k,
            zz: self.zz * k,
            xy: self.xy * k,
            yz: self.yz * k,
            zx: self.zx * k,
        }
    }
}

impl<T: Lanes> AddAssign for Sym<T> {
    #[inline(always)]
    fn add_assign(&mut self, b: Sym<T>) {
        *self = *self + b;
    }
}

impl SubAssign for Sym3 {
    #[inline(always)]
    fn sub_assign(&mut self, b: Sym3) {
        *self = *self - b;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::infra::lanes::gather;

    fn sample() -> Sym3 {
        Sym3 {
            xx: -3.0e5,
            yy: -1.2e5,
            zz: -0.7e5,
            xy: 4.0e4,
            yz: -1.0e4,
            zx: 2.5e4,
        }
    }

    #[test]
    fn eigen_reconstructs_the_tensor() {
        let s = sample();
        let (p, r) = s.eigen();
        assert!(p[0] >= p[1] && p[1] >= p[2]);
        let back = Sym3::from_principal(p, &r);
        assert!((back - s).norm() < 1e-9 * s.norm());
        assert!((p.iter().sum::<f64>() - s.trace()).abs() < 1e-9 * s.norm());
    }

    #[test]
    fn planar_eigen_agrees_with_jacobi() {
        for s in [
            Sym3 {
                xx: -3.0e5,
                yy: -1.2e5,
                zz: -2.0e5,
                xy: 4.0e4,
                ..Sym3::ZERO
            },
            Sym3 {
                xx: 1.0,
                yy: 1.0,
                zz: 5.0,
                xy: 0.0,
                ..Sym3::ZERO
            },
            Sym3 {
                xx: -1.0,
                yy: 2.0,
                zz: 0.5,
                xy: -3.0,
                ..Sym3::ZERO
            },
        ] {
            let (p, r) = s.eigen();
            let (pj, _) = jacobi_eigen(&s);
            let mut pj = pj.to_vec();
            pj.sort_by(|a, b| b.total_cmp(a));
            for k in 0..3 {
                assert!((p[k] - pj[k]).abs() < 1e-12 * s.norm());
            }
            assert!((Sym3::from_principal(p, &r) - s).norm() < 1e-12 * s.norm());
        }
    }

    #[test]
    fn planar_principal_values_are_those_of_the_eigen_decomposition_bit_for_bit() {
        // The Mohr-Coulomb update decides elastic or plastic on these values and returns
        // plastic points with eigen's: the two must agree to the last bit, with zz above,
        // inside, at the ends of and below the x-y pair, and for repeated values.
        let mut n = 0;
        for xy in [0.0, 3.0e4, -7.1e4] {
            for zz in [-4.0e5, -2.6e5, -2.0e5, -1.2e5, -0.5e5, 0.0, 1.0e5] {
                for (xx, yy) in [(-3.0e5, -1.2e5), (-1.2e5, -3.0e5), (-2.0e5, -2.0e5)] {
                    let s = Sym3 {
                        xx,
                        yy,
                        zz,
                        xy,
                        ..Sym3::ZERO
                    };
                    let p = s.principal_values();
                    assert_eq!(p.map(f64::to_bits), s.eigen().0.map(f64::to_bits), "{s:?}");
                    n += 1;
                }
            }
        }
        assert_eq!(n, 63);
        // A general state goes through the same Jacobi sweeps either way.
        assert_eq!(sample().principal_values(), sample().eigen().0);
    }

    #[test]
    fn eigen_handles_repeated_values() {
        let (p, _) = Sym3::diagonal(-1.0, -1.0, -1.0).eigen();
        assert_eq!(p, [-1.0, -1.0, -1.0]);
        let (p, _) = Sym3::ZERO.eigen();
        assert_eq!(p, [0.0; 3]);
    }

    #[test]
    fn rigid_rotation_through_jaumann_update_keeps_principal_stresses() {
        // A full turn about a skew axis in 1000 increments: the Cayley rotation is orthogonal,
        // so the principal values must survive to round-off.
        let s0 = sample();
        let p0 = s0.principal_values();
        let axis = DVec3::new(0.3, -0.5, 0.8).normalize();
        let dtheta = 2.0 * std::f64::consts::PI / 1000.0;
        let mut s = s0;
        for _ in 0..1000 {
            s = jaumann_rotate(&s, (axis * dtheta).to_array());
        }
        let p = s.principal_values();
        for k in 0..3 {
            assert!((p[k] - p0[k]).abs() < 1e-9 * s0.norm(), "{p:?} vs {p0:?}");
        }
    }

    #[test]
    fn rotation_about_z_matches_the_general_rotation() {
        let s = sample();
        for w in [1e-3, -0.4, 2.5] {
            let fast = jaumann_rotate_about_z(&s, w);
            // The general rotation rounds differently: the same to round-off.
            let general = jaumann_rotate(&s, [0.0, 0.0, w]);
            assert!(
                (fast - general).norm() < 1e-12 * s.norm(),
                "{fast:?} vs {general:?}"
            );
            // The matrix form.
            let a = 0.5 * w;
            let half = DMat3::from_cols(DVec3::new(0.0, -a, 0.0), DVec3::new(a, 0.0, 0.0), DVec3::ZERO);
            let r = DMat3::IDENTITY + (half + half * half) * (2.0 / (1.0 + a * a));
            let general = Sym3::from_mat3(&(r * s.to_mat3() * r.transpose()));
            assert!(
                (fast - general).norm() < 1e-12 * s.norm(),
                "{fast:?} vs {general:?}"
            );
        }
    }

    #[test]
    fn a_plane_strain_stress_stays_planar_through_spin_and_material_and_stores_in_four_components() {
        // Plane strain keeps yz = zx = 0 (the stored form drops them): the spin of a 2D
        // velocity gradient is about z only, and an in-plane strain adds no out-of-plane shear.
        let s = PlanarSym3 {
            xx: -3.0e5,
            yy: -1.2e5,
            zz: -0.7e5,
            xy: 4.0e4,
        };
        let elastic = crate::materials::Elasticity::new(20e6, 0.3);
        for w in [1e-3, -0.4, 2.5] {
            let de = Sym3 {
                xx: 1e-4,
                yy: -2e-4,
                xy: 3e-5 * w,
                ..Sym3::ZERO
            };
            let full = jaumann_rotate(&s.to_sym3(), [0.0, 0.0, w]) + elastic.stress_increment(&de);
            assert!(full.has_principal_z(), "{full:?}");
            assert_eq!(PlanarSym3::from_sym3(&full).to_sym3(), full);
        }
    }

    #[test]
    fn general_rotation_matches_the_matrix_form_of_the_cayley_transform() {
        // R = (I − Â)⁻¹(I + Â), Â = W/2, built and applied as full 3×3 matrices.
        let s = sample();
        for w in [[0.3, -0.7, 1.1], [-2.0, 0.5, 0.0], [1e-4, 2e-4, -3e-4]] {
            let half = DMat3::from_cols(
                DVec3::new(0.0, -w[2], w[1]),
                DVec3::new(w[2], 0.0, -w[0]),
                DVec3::new(-w[1], w[0], 0.0),
            ) * 0.5;
            let r = (DMat3::IDENTITY - half).inverse() * (DMat3::IDENTITY + half);
            let matrix = Sym3::from_mat3(&(r * s.to_mat3() * r.transpose()));
            let fast = jaumann_rotate(&s, w);
            assert!(
                (fast - matrix).norm() < 1e-12 * s.norm(),
                "{w:?}: {fast:?} vs {matrix:?}"
            );
        }
    }

    #[test]
    fn rotations_in_lanes_give_each_lane_the_bits_of_one_point() {
        // Four stresses and spins (one of them zero, one about z only) side by side.
        let base = sample();
        let stresses: [Sym3; 4] =
            std::array::from_fn(|l| base * (1.0 + l as f64) + Sym3::diagonal(-7e3 * l as f64, 0.0, 3e3));
        let spins = [[0.3, -0.7, 1.1], [0.0; 3], [0.0, 0.0, -0.4], [1e-4, 2e-4, -3e-4]];
        let lanes = Sym3x4::gather(|l| stresses[l]);
        let w = [0, 1, 2].map(|axis| gather(|l| spins[l][axis]));
        let general = jaumann_rotate(&lanes, w).lanes();
        let about_z = jaumann_rotate_about_z(&lanes, w[2]).lanes();
        let bits = |s: &Sym3| s.to_array().map(f64::to_bits);
        for l in 0..4 {
            assert_eq!(
                bits(&general[l]),
                bits(&jaumann_rotate(&stresses[l], spins[l])),
                "lane {l}"
            );
            assert_eq!(
                bits(&about_z[l]),
                bits(&jaumann_rotate_about_z(&stresses[l], spins[l][2])),
                "lane {l}"
            );
        }
        // A zero spin leaves the stress as it was.
        assert_eq!(general[1], stresses[1]);
    }

    #[test]
    fn small_spin_matches_the_jaumann_rate() {
        // For a small increment the rotation must equal σ + Wσ − σW to second order.
        let s = sample();
        let w = [1e-6, -2e-6, 3e-6];
        let rotated = jaumann_rotate(&s, w);
        let wm = DMat3::from_cols(
            DVec3::new(0.0, -w[2], w[1]),
            DVec3::new(w[2], 0.0, -w[0]),
            DVec3::new(-w[1], w[0], 0.0),
        );
        let sm = s.to_mat3();
        let euler = Sym3::from_mat3(&(sm + wm * sm - sm * wm));
        assert!((rotated - euler).norm() < 1e-9 * s.norm());
    }
}
