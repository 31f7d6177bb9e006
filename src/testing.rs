//! Helpers shared by the library's unit tests.

use crate::materials::Material;
use crate::tensor::Sym3;

/// A reproducible value in [−1, 1) from `seed`, which it advances (a 64-bit linear
/// congruential generator: the same sequence on every machine, with no crate to pin).
pub(crate) fn uniform(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*seed >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// A stress-controlled triaxial test of `m` from the default state: `steps` increments of
/// axial strain `de_axial` along z while the lateral stresses σxx = σyy are held at
/// `confinement` (Pa, tension positive) by bisection on the lateral strain increment.
/// Returns the stress and state after each step.
pub(crate) fn triaxial<M: Material>(
    m: &M,
    confinement: f64,
    de_axial: f64,
    steps: usize,
) -> Vec<(Sym3, M::State)> {
    let mut s = Sym3::diagonal(confinement, confinement, confinement);
    let mut state = M::State::default();
    let mut path = Vec::with_capacity(steps);
    for _ in 0..steps {
        let attempt = |e: f64| {
            let (mut t, mut k) = (s, state);
            m.update(&mut t, &Sym3::diagonal(e, e, de_axial), &mut k);
            (t, k)
        };
        let (mut lo, mut hi) = (-1e-3, 1e-3);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if attempt(mid).0.xx > confinement {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        (s, state) = attempt(0.5 * (lo + hi));
        path.push((s, state));
    }
    path
}
