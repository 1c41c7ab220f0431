//! Matrix lifting-line theory and the six design cases of seed 002 Table 1.
//!
//! Non-dimensional throughout (seed 002 notes §1, Yukish 2019 formulation): Γ̂ = Γ/(V∞·b),
//! ĉ = c/b, stations at y/b = linspace(−½ + 1/(2n), ½ − 1/(2n), n), α in rad from the
//! zero-lift line. With Q_ij = 1/(1 − 4(i−j)²) and W = (a·n/2π)·Q the lifting-line equation is
//! (2/a)(C⁻¹ + W)·Γ̂ = α with C = diag(ĉ). Lift per span ℓ = ρV∞Γ, so ℓ/(ρV∞²b) = Γ̂: the
//! non-dimensional lift *is* Γ̂; the local lift coefficient is c_ℓ = 2Γ̂/ĉ and the wing's
//! c_L = 2ΣΓ̂/Σĉ (= (2AR/n)ΣΓ̂ when Σĉ = n/AR).
//!
//! Two-point cases: the same wing flies at two wing angles, so α₂ = α₁ + Δα·e; Δα is the extra
//! unknown that the aspect-ratio constraint Σĉ = n/AR fixes.

use nalgebra::{DMatrix, DVector};

/// What went wrong in a lifting-line solve.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LltError {
    /// A scalar parameter is out of its domain.
    #[error("lifting line: invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The accepted domain.
        reason: &'static str,
    },
    /// An input vector does not have one value per station.
    #[error("lifting line: {name} has {found} values, expected one per station ({expected})")]
    Length {
        /// Input name.
        name: &'static str,
        /// Station count n.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// An input value is NaN or infinite.
    #[error("lifting line: {name}[{station}] is not finite")]
    NonFinite {
        /// Input name.
        name: &'static str,
        /// Station index.
        station: usize,
    },
    /// A chord (given or solved for) is not positive.
    #[error("lifting line ({case}): chord at station {station} is {value}, must be > 0")]
    NonPositiveChord {
        /// Design case.
        case: &'static str,
        /// Station index.
        station: usize,
        /// The chord ĉ = c/b.
        value: f64,
    },
    /// The design case has no solution for these inputs (a lift or lift difference of zero at
    /// a station, or a singular system).
    #[error("lifting line ({case}): no solution: {reason}")]
    NoSolution {
        /// Design case.
        case: &'static str,
        /// Why.
        reason: String,
    },
}

/// One spanwise distribution set: the wing at one flight condition.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// Chord ĉ = c/b per station.
    pub chord_over_b: DVector<f64>,
    /// Angle of attack from the zero-lift line per station \[rad\] (wing angle included).
    pub alpha_rad: DVector<f64>,
    /// Non-dimensional vorticity Γ̂ = Γ/(V∞b), equal to the non-dimensional lift ℓ/(ρV∞²b).
    pub gamma_hat: DVector<f64>,
    /// Local lift coefficient c_ℓ = 2Γ̂/ĉ (seed 002: c_ℓj = 2ℓ_j/(ρV²c_j)).
    pub cl_local: DVector<f64>,
    /// Wing lift coefficient c_L = 2ΣΓ̂/Σĉ (seed 002: c_L = 2L/(ρV²S)).
    pub c_l: f64,
    /// Induced angle α_i = (n/π)·Q·Γ̂ per station \[rad\] (notes: the W·Γ̂ term of the
    /// lifting-line equation, α = c_ℓ/a + α_i), positive as downwash.
    pub induced_alpha_rad: DVector<f64>,
}

impl Solution {
    /// The geometric section angle for building: α + α_L0 \[rad\] (seed 002 notes, Planform
    /// assembly: "geometric section angle = LLT α + α_L0").
    pub fn geometric_alpha_rad(&self, alpha_l0_rad: f64) -> DVector<f64> {
        self.alpha_rad.add_scalar(alpha_l0_rad)
    }

    /// Induced drag coefficient C_Di = Σc_ℓ·α_i·ĉ/Σĉ = 2ΣΓ̂α_i/Σĉ: each strip's lift
    /// tilted back by its induced angle (Kutta–Joukowski with the induced downwash; Anderson,
    /// *Fundamentals of Aerodynamics*, §5.3). For an elliptic load α_i = c_L/(πAR) everywhere,
    /// so C_Di = c_L²/(πAR).
    pub fn induced_drag_coefficient(&self) -> f64 {
        2.0 * self.gamma_hat.dot(&self.induced_alpha_rad) / self.chord_over_b.sum()
    }

    /// Span efficiency e = c_L²/(π·AR·C_Di) (1 for the elliptic load).
    pub fn span_efficiency(&self) -> f64 {
        self.c_l * self.c_l
            / (std::f64::consts::PI * self.aspect_ratio() * self.induced_drag_coefficient())
    }

    /// Aspect ratio implied by the chord: n/Σĉ.
    pub fn aspect_ratio(&self) -> f64 {
        self.chord_over_b.len() as f64 / self.chord_over_b.sum()
    }

    /// Lift per unit span \[N/m\] when the wing carries `total_lift_n` (lift ∝ Γ̂, stations
    /// b/n wide): ℓ_j = L·Γ̂_j / (ΣΓ̂ · b/n).
    pub fn lift_per_span_n_m(&self, total_lift_n: f64, span_m: f64) -> DVector<f64> {
        let n = self.gamma_hat.len() as f64;
        &self.gamma_hat * (total_lift_n / (self.gamma_hat.sum() * span_m / n))
    }
}

/// The wing at two flight conditions (two-point design cases).
#[derive(Debug, Clone, PartialEq)]
pub struct TwoPoint {
    /// The first condition.
    pub first: Solution,
    /// The second condition: same chord, α₂ = α₁ + Δα.
    pub second: Solution,
    /// Wing angle difference Δα = α₂ − α₁ \[rad\].
    pub delta_alpha_rad: f64,
}

/// A discretised lifting line: n stations, aspect ratio, 2-D lift slope `a`.
#[derive(Debug, Clone)]
pub struct LiftingLine {
    n: usize,
    aspect_ratio: f64,
    lift_slope_per_rad: f64,
    q: DMatrix<f64>,
    w: DMatrix<f64>,
}

impl LiftingLine {
    /// Builds Q and W = (a·n/2π)·Q for `n` stations.
    ///
    /// # Errors
    /// [`LltError::InvalidParameter`] for n < 2, or a non-finite or non-positive aspect ratio
    /// or lift slope.
    pub fn new(n: usize, aspect_ratio: f64, lift_slope_per_rad: f64) -> Result<Self, LltError> {
        if n < 2 {
            return Err(LltError::InvalidParameter {
                name: "n",
                value: n as f64,
                reason: "need at least 2 stations",
            });
        }
        for (name, value) in [
            ("aspect_ratio", aspect_ratio),
            ("lift_slope_per_rad", lift_slope_per_rad),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(LltError::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite and > 0",
                });
            }
        }
        let q = DMatrix::from_fn(n, n, |i, j| {
            let d = i as f64 - j as f64;
            1.0 / (1.0 - 4.0 * d * d)
        });
        let w = &q * (lift_slope_per_rad * n as f64 / (2.0 * std::f64::consts::PI));
        Ok(Self {
            n,
            aspect_ratio,
            lift_slope_per_rad,
            q,
            w,
        })
    }

    /// Number of stations n.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Station centres y/b.
    pub fn stations(&self) -> DVector<f64> {
        let n = self.n as f64;
        DVector::from_fn(self.n, |j, _| -0.5 + (j as f64 + 0.5) / n)
    }

    /// The discrete elliptic lift shape Q⁻¹·e (seed 002 notes, "Elliptic shape").
    pub fn elliptic_shape(&self) -> DVector<f64> {
        self.q
            .clone()
            .lu()
            .solve(&DVector::repeat(self.n, 1.0))
            .expect("Q is non-singular")
    }

    /// A chord shape scaled to this aspect ratio: ĉ = (n/AR)·shape/Σshape.
    pub fn chord_from_shape(&self, shape: &DVector<f64>) -> Result<DVector<f64>, LltError> {
        self.check("chord shape", shape)?;
        Ok(shape * (self.n as f64 / self.aspect_ratio / shape.sum()))
    }

    /// Γ̂ of a lift shape at wing lift coefficient `c_l`: Γ̂ = ½(c_L/AR)·n·shape/Σshape.
    pub fn gamma_from_shape(
        &self,
        shape: &DVector<f64>,
        c_l: f64,
    ) -> Result<DVector<f64>, LltError> {
        self.check("lift shape", shape)?;
        Ok(shape * (0.5 * c_l / self.aspect_ratio * self.n as f64 / shape.sum()))
    }

    /// Lift slope of a planform, c_Lα = a·eᵀ(C⁻¹ + W)⁻¹e / Σĉ \[1/rad\].
    pub fn lift_curve_slope(&self, chord_over_b: &DVector<f64>) -> Result<f64, LltError> {
        let s = self.direct(chord_over_b, &DVector::repeat(self.n, 1.0))?;
        Ok(s.c_l)
    }

    /// Direct design (Table 1 row 1): c, α → Γ̂ = ½a(C⁻¹ + W)⁻¹α.
    pub fn direct(
        &self,
        chord_over_b: &DVector<f64>,
        alpha_rad: &DVector<f64>,
    ) -> Result<Solution, LltError> {
        const CASE: &str = "direct design";
        self.check_chord(CASE, chord_over_b)?;
        self.check("alpha_rad", alpha_rad)?;
        let m = self.c_inv_plus_w(chord_over_b);
        let gamma = m
            .lu()
            .solve(&(alpha_rad * (0.5 * self.lift_slope_per_rad)))
            .ok_or_else(|| no_solution(CASE, "C⁻¹ + W is singular"))?;
        Ok(self.solution(chord_over_b.clone(), alpha_rad.clone(), gamma))
    }

    /// Direct design of one planform at several twist distributions with one factorisation
    /// of C⁻¹ + W: a [`Solution`] per α, in order.
    pub fn direct_many(
        &self,
        chord_over_b: &DVector<f64>,
        alphas_rad: &[DVector<f64>],
    ) -> Result<Vec<Solution>, LltError> {
        const CASE: &str = "direct design";
        self.check_chord(CASE, chord_over_b)?;
        let lu = self.c_inv_plus_w(chord_over_b).lu();
        alphas_rad
            .iter()
            .map(|alpha| {
                self.check("alpha_rad", alpha)?;
                let gamma = lu
                    .solve(&(alpha * (0.5 * self.lift_slope_per_rad)))
                    .ok_or_else(|| no_solution(CASE, "C⁻¹ + W is singular"))?;
                Ok(self.solution(chord_over_b.clone(), alpha.clone(), gamma))
            })
            .collect()
    }

    /// Single-point inverse design #1 (Table 1 row 2): c, ℓ → α = (2/a)(C⁻¹ + W)Γ̂.
    pub fn inverse_twist(
        &self,
        chord_over_b: &DVector<f64>,
        gamma_hat: &DVector<f64>,
    ) -> Result<Solution, LltError> {
        self.check_chord("single-point inverse #1", chord_over_b)?;
        self.check("gamma_hat", gamma_hat)?;
        let alpha = self.alpha_for(chord_over_b, gamma_hat);
        Ok(self.solution(chord_over_b.clone(), alpha, gamma_hat.clone()))
    }

    /// Single-point inverse design #2 (Table 1 row 3): α, ℓ → c, from
    /// Γ̂_j/ĉ_j = aα_j/2 − (WΓ̂)_j at each station (a diagonal solve).
    pub fn inverse_chord(
        &self,
        alpha_rad: &DVector<f64>,
        gamma_hat: &DVector<f64>,
    ) -> Result<Solution, LltError> {
        const CASE: &str = "single-point inverse #2";
        self.check("alpha_rad", alpha_rad)?;
        self.check("gamma_hat", gamma_hat)?;
        let wg = &self.w * gamma_hat;
        let chord = DVector::from_fn(self.n, |j, _| {
            gamma_hat[j] / (0.5 * self.lift_slope_per_rad * alpha_rad[j] - wg[j])
        });
        self.check_chord(CASE, &chord)?;
        Ok(self.solution(chord, alpha_rad.clone(), gamma_hat.clone()))
    }

    /// Single-point inverse design #2 with the wing angle free: a twist shape t and ℓ → c and
    /// α = α₀ + t, with the wing angle α₀ fixed by the aspect ratio Σĉ = n/AR.
    ///
    /// For Γ̂ > 0, ĉ_j(α₀) = Γ̂_j / (a(α₀ + t_j)/2 − (WΓ̂)_j) is positive past the last pole
    /// α₀ > max_j(2(WΓ̂)_j/a − t_j) and Σĉ falls monotonically from +∞ to 0 there, so α₀ is
    /// found by bisection (as in [`LiftingLine::two_lift`]); the chord then comes from
    /// [`LiftingLine::inverse_chord`].
    pub fn inverse_chord_at_aspect_ratio(
        &self,
        twist_rad: &DVector<f64>,
        gamma_hat: &DVector<f64>,
    ) -> Result<Solution, LltError> {
        const CASE: &str = "single-point inverse #2";
        self.check("twist_rad", twist_rad)?;
        self.check("gamma_hat", gamma_hat)?;
        if gamma_hat.iter().any(|g| *g <= 0.0) {
            return Err(no_solution(CASE, "ℓ must be positive at every station"));
        }
        let wg = &self.w * gamma_hat;
        let half_a = 0.5 * self.lift_slope_per_rad;
        let target = self.n as f64 / self.aspect_ratio;
        let sum = |a0: f64| {
            (0..self.n)
                .map(|j| gamma_hat[j] / (half_a * (a0 + twist_rad[j]) - wg[j]))
                .sum::<f64>()
        };
        let lo0 = (0..self.n)
            .map(|j| wg[j] / half_a - twist_rad[j])
            .fold(f64::NEG_INFINITY, f64::max);
        let a0 = falling_root_past_pole(lo0, target, sum)
            .ok_or_else(|| no_solution(CASE, "no wing angle meets the aspect ratio"))?;
        self.inverse_chord(&twist_rad.add_scalar(a0), gamma_hat)
    }

    /// Two-point inverse design #1 (Table 1 row 4): ℓ₁, ℓ₂ → c, α.
    ///
    /// Subtracting the two lifting-line equations gives ĉ_j = ΔΓ̂_j / (aΔα/2 − (WΔΓ̂)_j) with
    /// ΔΓ̂ = Γ̂₂ − Γ̂₁; Σĉ(Δα) is monotone on the branch where every chord is positive, so Δα
    /// is found by bisection on Σĉ = n/AR. Then α₁ = (2/a)(C⁻¹ + W)Γ̂₁.
    pub fn two_lift(
        &self,
        gamma1: &DVector<f64>,
        gamma2: &DVector<f64>,
    ) -> Result<TwoPoint, LltError> {
        const CASE: &str = "two-point inverse #1";
        self.check("gamma1", gamma1)?;
        self.check("gamma2", gamma2)?;
        let d = gamma2 - gamma1;
        // Work with sign s so that s·ΔΓ̂ > 0 everywhere; ĉ is unchanged by flipping ΔΓ̂ and Δα.
        let s = if d[0] > 0.0 { 1.0 } else { -1.0 };
        if d.iter().any(|v| s * v <= 0.0) {
            return Err(no_solution(
                CASE,
                "ℓ₂ − ℓ₁ must be non-zero with one sign at every station",
            ));
        }
        let ds = &d * s;
        let wd = &self.w * &ds;
        let half_a = 0.5 * self.lift_slope_per_rad;
        let target = self.n as f64 / self.aspect_ratio;
        let sum = |da: f64| {
            ds.iter()
                .zip(wd.iter())
                .map(|(g, w)| g / (half_a * da - w))
                .sum::<f64>()
        };
        let lo0 = wd.max() / half_a;
        let da = falling_root_past_pole(lo0, target, sum)
            .ok_or_else(|| no_solution(CASE, "no wing angle difference meets the aspect ratio"))?;
        let chord = DVector::from_fn(self.n, |j, _| ds[j] / (half_a * da - wd[j]));
        self.check_chord(CASE, &chord)?;
        Ok(self.two_point(chord, gamma1.clone(), s * da))
    }

    /// Two-point inverse design #2 (Table 1 row 5): c_ℓ1, c_ℓ2 → c, α.
    ///
    /// With Γ̂ = ½ĉ∘c_ℓ the difference of the two conditions is linear in ĉ:
    /// W(ĉ∘Δc_ℓ) = aΔα·e − Δc_ℓ, so ĉ = D⁻¹W⁻¹(aΔα·e − Δc_ℓ) (D = diag Δc_ℓ) and Σĉ = n/AR
    /// gives Δα in closed form.
    pub fn two_cl(&self, cl1: &DVector<f64>, cl2: &DVector<f64>) -> Result<TwoPoint, LltError> {
        const CASE: &str = "two-point inverse #2";
        self.check("cl1", cl1)?;
        self.check("cl2", cl2)?;
        let dcl = cl2 - cl1;
        if let Some(j) = dcl.iter().position(|v| *v == 0.0) {
            return Err(no_solution(
                CASE,
                format!("c_ℓ2 − c_ℓ1 is 0 at station {j}"),
            ));
        }
        let lu = self.w.clone().lu();
        let solve = |rhs: &DVector<f64>| {
            lu.solve(rhs)
                .ok_or_else(|| no_solution(CASE, "W is singular"))
        };
        let u = solve(&DVector::repeat(self.n, 1.0))?.component_div(&dcl);
        let v = solve(&dcl)?.component_div(&dcl);
        let da =
            (self.n as f64 / self.aspect_ratio + v.sum()) / (self.lift_slope_per_rad * u.sum());
        let chord = u * (self.lift_slope_per_rad * da) - v;
        self.check_chord(CASE, &chord)?;
        let gamma1 = chord.component_mul(cl1) * 0.5;
        Ok(self.two_point(chord, gamma1, da))
    }

    /// Two-point inverse design #3 (Table 1 row 6): ℓ₁, c_ℓ2 → c, α.
    ///
    /// F(ĉ, Δα) = ½c_ℓ2 + ½W(ĉ∘c_ℓ2) − Γ̂₁/ĉ − WΓ̂₁ − (a/2)Δα·e = 0 with Σĉ = n/AR is
    /// nonlinear in ĉ (Γ̂₁/ĉ); it is solved by damped Newton steps, each one linear solve of the
    /// (n+1)×(n+1) Jacobian, from the chord shaped like ℓ₁.
    pub fn lift_and_cl(
        &self,
        gamma1: &DVector<f64>,
        cl2: &DVector<f64>,
    ) -> Result<TwoPoint, LltError> {
        const CASE: &str = "two-point inverse #3";
        self.check("gamma1", gamma1)?;
        self.check("cl2", cl2)?;
        if gamma1.iter().any(|g| *g <= 0.0) {
            return Err(no_solution(CASE, "ℓ₁ must be positive at every station"));
        }
        let n = self.n;
        let half_a = 0.5 * self.lift_slope_per_rad;
        let target = n as f64 / self.aspect_ratio;
        let wg1 = &self.w * gamma1;
        let residual = |c: &DVector<f64>, da: f64| {
            let mut r = DVector::zeros(n + 1);
            let wc = &self.w * c.component_mul(cl2);
            for j in 0..n {
                r[j] = 0.5 * cl2[j] + 0.5 * wc[j] - gamma1[j] / c[j] - wg1[j] - half_a * da;
            }
            r[n] = c.sum() - target;
            r
        };
        let mut c = gamma1 * (target / gamma1.sum());
        let mut da = 0.0;
        let mut r = residual(&c, da);
        for _ in 0..100 {
            if r.amax() < 1e-13 {
                break;
            }
            let mut jac = DMatrix::zeros(n + 1, n + 1);
            for i in 0..n {
                for j in 0..n {
                    jac[(i, j)] = 0.5 * self.w[(i, j)] * cl2[j];
                }
                jac[(i, i)] += gamma1[i] / (c[i] * c[i]);
                jac[(i, n)] = -half_a;
                jac[(n, i)] = 1.0;
            }
            let step = jac
                .lu()
                .solve(&(-&r))
                .ok_or_else(|| no_solution(CASE, "singular Newton step"))?;
            let mut t = 1.0;
            loop {
                let c_new = &c + step.rows(0, n) * t;
                if c_new.iter().all(|v| *v > 0.0) {
                    let r_new = residual(&c_new, da + t * step[n]);
                    if r_new.amax() < r.amax() || t < 1e-6 {
                        c = c_new;
                        da += t * step[n];
                        r = r_new;
                        break;
                    }
                }
                t *= 0.5;
                if t < 1e-12 {
                    return Err(no_solution(
                        CASE,
                        "Newton step cannot keep the chord positive",
                    ));
                }
            }
        }
        if r.amax() >= 1e-9 {
            return Err(no_solution(
                CASE,
                format!("Newton did not converge (residual {:e})", r.amax()),
            ));
        }
        self.check_chord(CASE, &c)?;
        Ok(self.two_point(c, gamma1.clone(), da))
    }

    fn two_point(&self, chord: DVector<f64>, gamma1: DVector<f64>, da: f64) -> TwoPoint {
        let alpha1 = self.alpha_for(&chord, &gamma1);
        let alpha2 = alpha1.add_scalar(da);
        let first = self.solution(chord.clone(), alpha1, gamma1);
        let m = self.c_inv_plus_w(&chord);
        let gamma2 = m
            .lu()
            .solve(&(&alpha2 * (0.5 * self.lift_slope_per_rad)))
            .unwrap_or_else(|| DVector::from_element(self.n, f64::NAN));
        let second = self.solution(chord, alpha2, gamma2);
        TwoPoint {
            first,
            second,
            delta_alpha_rad: da,
        }
    }

    fn alpha_for(&self, chord: &DVector<f64>, gamma: &DVector<f64>) -> DVector<f64> {
        (self.c_inv_plus_w(chord) * gamma) * (2.0 / self.lift_slope_per_rad)
    }

    fn c_inv_plus_w(&self, chord: &DVector<f64>) -> DMatrix<f64> {
        let mut m = self.w.clone();
        for j in 0..self.n {
            m[(j, j)] += 1.0 / chord[j];
        }
        m
    }

    fn solution(&self, chord: DVector<f64>, alpha: DVector<f64>, gamma: DVector<f64>) -> Solution {
        let cl_local = gamma.component_div(&chord) * 2.0;
        let c_l = 2.0 * gamma.sum() / chord.sum();
        let induced_alpha_rad = (&self.q * &gamma) * (self.n as f64 / std::f64::consts::PI);
        Solution {
            chord_over_b: chord,
            alpha_rad: alpha,
            gamma_hat: gamma,
            cl_local,
            c_l,
            induced_alpha_rad,
        }
    }

    fn check(&self, name: &'static str, v: &DVector<f64>) -> Result<(), LltError> {
        if v.len() != self.n {
            return Err(LltError::Length {
                name,
                expected: self.n,
                found: v.len(),
            });
        }
        match v.iter().position(|x| !x.is_finite()) {
            Some(station) => Err(LltError::NonFinite { name, station }),
            None => Ok(()),
        }
    }

    fn check_chord(&self, case: &'static str, c: &DVector<f64>) -> Result<(), LltError> {
        self.check("chord_over_b", c)?;
        match c.iter().position(|x| *x <= 0.0) {
            Some(station) => Err(LltError::NonPositiveChord {
                case,
                station,
                value: c[station],
            }),
            None => Ok(()),
        }
    }
}

/// The x > `pole` where a function falling from +∞ (just past its pole) towards 0 equals
/// `target`: the bracket doubles away from the pole until `f` drops to `target`, then bisects
/// to the last representable step. `None` when no finite bracket is found.
fn falling_root_past_pole(pole: f64, target: f64, f: impl Fn(f64) -> f64) -> Option<f64> {
    let (mut lo, mut hi) = (pole, pole + pole.abs().max(1e-3));
    while f(hi) > target {
        hi = pole + 2.0 * (hi - pole);
        if !hi.is_finite() {
            return None;
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid == lo || mid == hi {
            break;
        }
        if f(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

fn no_solution(case: &'static str, reason: impl Into<String>) -> LltError {
    LltError::NoSolution {
        case,
        reason: reason.into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
        (a - b).amax() / b.amax()
    }

    #[test]
    fn elliptic_lift_slope_matches_the_fixture() {
        let ll = LiftingLine::new(400, 8.0, 2.0 * std::f64::consts::PI).unwrap();
        let c = ll.chord_from_shape(&ll.elliptic_shape()).unwrap();
        let slope = ll.lift_curve_slope(&c).unwrap();
        assert!(
            (slope - 5.0291).abs() < 1e-3,
            "elliptic n=400 AR=8: c_Lα = 5.0291 /rad (notes; theory a/(1+a/πAR) = 5.0265), got {slope}"
        );
        let rect = ll.chord_from_shape(&DVector::repeat(400, 1.0)).unwrap();
        let slope = ll.lift_curve_slope(&rect).unwrap();
        assert!(
            (slope - 4.8448).abs() < 1e-3,
            "rectangular: 4.8448 /rad, got {slope}"
        );
    }

    #[test]
    fn induced_drag_is_least_for_the_elliptic_load() {
        let ll = LiftingLine::new(400, 8.0, 2.0 * std::f64::consts::PI).unwrap();
        let alpha = DVector::repeat(400, 0.1);
        let c = ll.chord_from_shape(&ll.elliptic_shape()).unwrap();
        let s = ll.direct(&c, &alpha).unwrap();
        let ideal = s.c_l * s.c_l / (std::f64::consts::PI * 8.0);
        let cdi = s.induced_drag_coefficient();
        assert!(
            (cdi / ideal - 1.0).abs() < 3e-3,
            "elliptic: C_Di = c_L²/(πAR) = {ideal}, got {cdi}"
        );
        // Discrete: e = 1.0025 at n = 400 (α_i = α − c_ℓ/a inherits the 0.05 % of c_Lα, ×5).
        assert!((s.span_efficiency() - 1.0).abs() < 3e-3);
        // The equation's balance: α = c_ℓ/a + α_i at every station.
        let back = &s.cl_local / (2.0 * std::f64::consts::PI) + &s.induced_alpha_rad;
        assert!((back - &alpha).amax() < 1e-12);
        let rect = ll.chord_from_shape(&DVector::repeat(400, 1.0)).unwrap();
        let e = ll.direct(&rect, &alpha).unwrap().span_efficiency();
        assert!(
            (0.9..0.995).contains(&e),
            "a rectangular AR 8 wing loses a few % (e ≈ 0.97), got {e}"
        );
    }

    #[test]
    fn elliptic_planform_gives_elliptic_lift() {
        let ll = LiftingLine::new(200, 8.0, 6.0).unwrap();
        let y = ll.stations();
        let ellipse = y.map(|y| (1.0 - 4.0 * y * y).sqrt());
        let lift_shape_error = |chord_shape: &DVector<f64>| {
            let c = ll.chord_from_shape(chord_shape).unwrap();
            let s = ll.direct(&c, &DVector::repeat(200, 0.1)).unwrap();
            rel(&(&s.gamma_hat / s.gamma_hat.max()), &ellipse)
        };
        let e = lift_shape_error(&ellipse);
        assert!(
            e < 0.03,
            "elliptic chord → elliptic lift, max deviation {e}"
        );
        let r = lift_shape_error(&DVector::repeat(200, 1.0));
        assert!(r > 0.1, "a rectangular wing is not elliptic ({r})");
        // Elliptic: constant local c_ℓ (the discrete ellipse Q⁻¹e exactly).
        let c = ll.chord_from_shape(&ll.elliptic_shape()).unwrap();
        let s = ll.direct(&c, &DVector::repeat(200, 0.1)).unwrap();
        assert!(s.cl_local.max() - s.cl_local.min() < 1e-9);
    }

    /// A tapered, washed-out wing: the fixture the six cases must reproduce.
    fn wing(ll: &LiftingLine) -> (DVector<f64>, DVector<f64>) {
        let y = ll.stations();
        let c = ll
            .chord_from_shape(&y.map(|y| 1.0 - 1.2 * y.abs()))
            .unwrap();
        let a = y.map(|y| 0.08 - 0.06 * 4.0 * y * y);
        (c, a)
    }

    #[test]
    fn the_six_design_cases_round_trip() {
        let ll = LiftingLine::new(120, 8.0, 2.0 * std::f64::consts::PI).unwrap();
        let (c, a) = wing(&ll);
        let d = ll.direct(&c, &a).unwrap();
        // SPI #1: c, ℓ → α.
        let s1 = ll.inverse_twist(&c, &d.gamma_hat).unwrap();
        assert!(rel(&s1.alpha_rad, &a) < 1e-10);
        // SPI #2: α, ℓ → c.
        let s2 = ll.inverse_chord(&a, &d.gamma_hat).unwrap();
        assert!(rel(&s2.chord_over_b, &c) < 1e-10);
        // SPI #2 with the wing angle from the aspect ratio: the twist shape is α minus its mean.
        let s2a = ll
            .inverse_chord_at_aspect_ratio(&a.add_scalar(-a.mean()), &d.gamma_hat)
            .unwrap();
        assert!(rel(&s2a.chord_over_b, &c) < 1e-9, "SPI #2 at AR: chord");
        assert!(rel(&s2a.alpha_rad, &a) < 1e-9, "SPI #2 at AR: wing angle");
        // Second condition: the same wing 4° higher.
        let da = 4f64.to_radians();
        let d2 = ll.direct(&c, &a.add_scalar(da)).unwrap();
        for (name, t) in [
            ("TPI #1", ll.two_lift(&d.gamma_hat, &d2.gamma_hat).unwrap()),
            ("TPI #2", ll.two_cl(&d.cl_local, &d2.cl_local).unwrap()),
            (
                "TPI #3",
                ll.lift_and_cl(&d.gamma_hat, &d2.cl_local).unwrap(),
            ),
        ] {
            assert!(rel(&t.first.chord_over_b, &c) < 1e-8, "{name} chord");
            assert!(rel(&t.first.alpha_rad, &a) < 1e-8, "{name} twist");
            assert!((t.delta_alpha_rad - da).abs() < 1e-9, "{name} Δα");
            assert!(rel(&t.second.gamma_hat, &d2.gamma_hat) < 1e-8, "{name} ℓ₂");
            assert!((t.first.c_l - d.c_l).abs() < 1e-10);
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        assert!(LiftingLine::new(1, 8.0, 6.0).is_err());
        assert!(LiftingLine::new(10, f64::NAN, 6.0).is_err());
        let ll = LiftingLine::new(10, 8.0, 6.0).unwrap();
        let e = DVector::repeat(10, 0.1);
        assert!(matches!(
            ll.direct(&DVector::repeat(9, 0.1), &e),
            Err(LltError::Length { .. })
        ));
        let mut c = DVector::repeat(10, 0.0125);
        c[3] = -1.0;
        assert!(matches!(
            ll.direct(&c, &e),
            Err(LltError::NonPositiveChord { station: 3, .. })
        ));
        c[3] = f64::NAN;
        assert!(matches!(
            ll.direct(&c, &e),
            Err(LltError::NonFinite { station: 3, .. })
        ));
        assert!(ll.two_lift(&e, &e).is_err(), "equal lifts: no Δ");
        assert!(ll.two_cl(&e, &e).is_err());
    }
}
