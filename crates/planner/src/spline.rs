//! Uniform cubic B-splines of scalar control values over u ∈ [0, 1]: the displacement δ(u)
//! of the wire path along its normals (seed 000 §IV.C) and the feed ratio's ln ρ(u).
//!
//! Two end conditions ([`SplineEnds`]):
//!
//! - **periodic** (the paper's: the path is a closed loop): with t = u·K, k = ⌊t⌋, f = t − k,
//!   δ = B₀(f)·c_{k−1} + B₁(f)·c_k + B₂(f)·c_{k+1} + B₃(f)·c_{k+2} (indices mod K), the
//!   uniform cubic basis B₀ = (1−f)³/6, B₁ = (3f³ − 6f² + 4)/6, B₂ = (−3f³ + 3f² + 3f + 1)/6,
//!   B₃ = f³/6. C² everywhere and δ(0) = δ(1);
//! - **open** (clamped): knots 0,0,0,0, 1/(K−3), …, 1,1,1,1 (K − 3 equal spans), the basis by
//!   the Cox–de Boor recursion (Piegl & Tiller, *The NURBS Book*, A2.2). δ(0) = c₀ and
//!   δ(1) = c_{K−1}, independent of each other: the wire's first and last passes by the
//!   entry point get their own offset and feed (crate docs, "Why the swarm stalled").
//!
//! Either way the four non-zero weights are ≥ 0 and sum to 1, so min c ≤ δ ≤ max c (what
//! [`crate::problem::Problem::bounds`] relies on).
//!
//! Written here (60 lines) because the spline crates on offer are general NURBS libraries
//! and this is all the optimiser needs.

/// How the spline behaves at u = 0 and u = 1 (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SplineEnds {
    /// δ(0) = δ(1), C² across the join (seed 000's closed path).
    Periodic,
    /// Clamped: δ(0) = c₀, δ(1) = c_{K−1} (default).
    #[default]
    Open,
}

impl SplineEnds {
    /// Fewest control values the end condition works with.
    pub fn min_controls(self) -> usize {
        match self {
            Self::Periodic => 1,
            Self::Open => 4,
        }
    }

    /// Indices and weights of the four non-zero basis functions of a K-control spline at u
    /// (periodic: u wrapped into [0, 1); open: u clamped to [0, 1]). K below
    /// [`SplineEnds::min_controls`] gives zero weights.
    pub fn basis(self, k: usize, u: f64) -> ([usize; 4], [f64; 4]) {
        if k < self.min_controls() {
            return ([0; 4], [0.0; 4]);
        }
        match self {
            Self::Periodic => periodic_basis(k, u),
            Self::Open => open_basis(k, u),
        }
    }

    /// δ(u) for `controls` (0 with too few controls).
    pub fn eval(self, controls: &[f64], u: f64) -> f64 {
        let (idx, w) = self.basis(controls.len(), u);
        (0..4)
            .map(|q| w[q] * controls.get(idx[q]).copied().unwrap_or(0.0))
            .sum()
    }
}

/// δ(u) of the periodic spline (module docs); 0 for no controls.
pub fn periodic_cubic_bspline(controls: &[f64], u: f64) -> f64 {
    SplineEnds::Periodic.eval(controls, u)
}

fn periodic_basis(k: usize, u: f64) -> ([usize; 4], [f64; 4]) {
    let t = u.rem_euclid(1.0) * k as f64;
    let i = (t.floor() as usize).min(k - 1);
    let f = t - i as f64;
    let (f2, f3) = (f * f, f * f * f);
    let w = [
        (1.0 - f).powi(3) / 6.0,
        (3.0 * f3 - 6.0 * f2 + 4.0) / 6.0,
        (-3.0 * f3 + 3.0 * f2 + 3.0 * f + 1.0) / 6.0,
        f3 / 6.0,
    ];
    ([(i + k - 1) % k, i, (i + 1) % k, (i + 2) % k], w)
}

/// Cox–de Boor on the clamped uniform knot vector (module docs): the span s = ⌊u·(K−3)⌋
/// (the last span includes u = 1) has non-zero basis functions N_s … N_{s+3}.
fn open_basis(k: usize, u: f64) -> ([usize; 4], [f64; 4]) {
    let spans = (k - 3) as f64;
    let u = u.clamp(0.0, 1.0);
    let s = ((u * spans).floor() as usize).min(k - 4);
    // Knot m of the clamped vector: 0 for m ≤ 3, 1 for m ≥ K, (m − 3)/(K − 3) between.
    let knot = |m: usize| ((m as f64 - 3.0) / spans).clamp(0.0, 1.0);
    let i = s + 3; // knot span index: knot(i) ≤ u < knot(i + 1)
    let mut n = [1.0, 0.0, 0.0, 0.0];
    let (mut left, mut right) = ([0.0; 4], [0.0; 4]);
    for j in 1..=3 {
        left[j] = u - knot(i + 1 - j);
        right[j] = knot(i + j) - u;
        let mut saved = 0.0;
        for r in 0..j {
            let denom = right[r + 1] + left[j - r];
            let temp = if denom > 0.0 { n[r] / denom } else { 0.0 };
            n[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        n[j] = saved;
    }
    ([s, s + 1, s + 2, s + 3], n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn open_ends_interpolate_their_end_controls_and_periodic_ones_join() {
        let c = [0.3, -0.2, 0.5, 1.0, 2.0, -1.0, 0.7];
        assert!((SplineEnds::Open.eval(&c, 0.0) - 0.3).abs() < 1e-12);
        assert!((SplineEnds::Open.eval(&c, 1.0) - 0.7).abs() < 1e-12);
        let p = SplineEnds::Periodic;
        assert!((p.eval(&c, 0.0) - p.eval(&c, 1.0 - 1e-12)).abs() < 1e-9);
        // Four controls, open: one span, the cubic Bernstein basis.
        let b = SplineEnds::Open.basis(4, 0.5).1;
        for (w, e) in b.iter().zip([0.125, 0.375, 0.375, 0.125]) {
            assert!((w - e).abs() < 1e-12, "{b:?}");
        }
        // Too few controls: zero.
        assert_eq!(SplineEnds::Open.eval(&[1.0, 2.0], 0.5), 0.0);
        assert_eq!(periodic_cubic_bspline(&[], 0.5), 0.0);
    }

    proptest! {
        #[test]
        fn weights_are_a_partition_of_unity_and_continuous(k in 4usize..40, u in 0.0f64..1.0) {
            for ends in [SplineEnds::Open, SplineEnds::Periodic] {
                let (idx, w) = ends.basis(k, u);
                prop_assert!(w.iter().all(|&x| x >= -1e-15));
                prop_assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
                prop_assert!(idx.iter().all(|&i| i < k));
                // C⁰ (in fact C²): a small step in u changes δ by little.
                let c: Vec<f64> = (0..k).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
                let d = (ends.eval(&c, u) - ends.eval(&c, (u + 1e-9).min(1.0))).abs();
                prop_assert!(d < 1e-6, "{:?} {} {}", ends, u, d);
            }
        }
    }
}
