//! The design case of a wing spec (`aero.design`): which of the six lifting-line design cases
//! of seed 002 Table 1 the user picks, the inputs each one takes as YAML, their validation, and
//! the solve through [`crate::llt`].
//!
//! | `case` | Table 1 row | inputs | outputs |
//! |---|---|---|---|
//! | `direct` | Direct design | chord shape, root angle, washout | ℓ |
//! | `inverse_twist` | Single-point inverse #1 | chord shape, lift shape, c_L | α |
//! | `inverse_chord` | Single-point inverse #2 | washout (twist shape), lift shape, c_L | c, wing angle |
//! | `two_lift` | Two-point inverse #1 | ℓ₁, ℓ₂ (shape and c_L each) | c, α |
//! | `two_cl` | Two-point inverse #2 | c_ℓ1, c_ℓ2 (spanwise) | c, α |
//! | `lift_and_cl` | Two-point inverse #3 | ℓ₁ (shape and c_L), c_ℓ2 | c, α |
//!
//! Spanwise inputs are functions of η = |2y/b| (0 at the root, 1 at the tip), symmetric, and
//! are evaluated at the lifting-line stations. A lift *shape* is scaled to its c_L with
//! Γ̂ = ½(c_L/AR)·n·shape/Σshape (the notes' "Γ̂ for a lift shape"). Every case ends with a
//! direct analysis of the designed chord and twist (the notes: "after the c_ℓ-based cases, run
//! Direct Design to obtain ℓ"), so the conditions reported are what the built wing does.

use cell_config::{Allowed, Bound, FieldError};
use nalgebra::DVector;
use serde::{Deserialize, Serialize};

use crate::llt::{LiftingLine, LltError, Solution};

/// The example specs shipped under `config/wings/` (`<name>.yaml`), one per design case of
/// seed 002 Table 1: (file stem, [`Design::case`]). Tests and the VLM comparison walk this list.
pub const EXAMPLE_SPECS: [(&str, &str); 6] = [
    ("direct-washout", "direct"),
    ("gwing-table2", "inverse_twist"),
    ("single-point-inverse-chord", "inverse_chord"),
    ("two-point-lift", "two_lift"),
    ("two-point-cl", "two_cl"),
    ("two-point-lift-cl", "lift_and_cl"),
];

/// A chord distribution shape (scaled to the aspect ratio).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum ChordShape {
    /// The discrete ellipse Q⁻¹e.
    Elliptic,
    /// Constant chord.
    Rectangular,
    /// Straight taper, tip/root chord ratio in (0, 1\].
    Tapered {
        /// c_tip / c_root.
        taper_ratio: f64,
    },
}

/// A spanwise lift shape (scaled to the condition's c_L).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum LiftShape {
    /// The discrete ellipse Q⁻¹e: constant downwash, least induced drag for a given span.
    #[default]
    Elliptic,
    /// Prandtl's bell, (1 − η²)^{3/2}: least induced drag for a given root bending moment
    /// (Prandtl 1933; Bowers et al., NASA/TP-2016-219072).
    Bell,
    /// Samples `[η, value]` with η from 0 (root) to 1 (tip), strictly increasing, interpolated
    /// linearly; values > 0 inboard of the tip (the tip value may be 0).
    Points(Vec<[f64; 2]>),
}

/// A spanwise distribution of the local lift coefficient c_ℓ.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum Spanwise {
    /// The same value at every station.
    Constant(f64),
    /// Linear in η from `root` to `tip`.
    Linear {
        /// Value at the root (η = 0).
        root: f64,
        /// Value at the tip (η = 1).
        tip: f64,
    },
    /// Samples `[η, value]` with η from 0 to 1, strictly increasing, interpolated linearly.
    Points(Vec<[f64; 2]>),
}

/// One flight condition given by its lift: a shape at a wing lift coefficient.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LiftCondition {
    /// Lift shape. Default elliptic.
    #[serde(default)]
    pub lift: LiftShape,
    /// Wing lift coefficient c_L of this condition.
    pub c_l: f64,
}

/// One flight condition given by its local lift coefficients.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClCondition {
    /// Local c_ℓ along the span.
    pub local_c_l: Spanwise,
}

/// The design case of seed 002 Table 1 (`aero.design`, tagged by `case`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, tag = "case", rename_all = "snake_case")]
pub enum Design {
    /// Direct design: a chord shape and linear washout → lift.
    Direct {
        /// Chord shape.
        chord: ChordShape,
        /// Root angle from the zero-lift line \[deg\].
        root_alpha_deg: f64,
        /// Root minus tip angle \[deg\].
        washout_deg: f64,
    },
    /// Single-point inverse #1: a chord shape and a lift shape at `c_l` → twist.
    InverseTwist {
        /// Chord shape.
        chord: ChordShape,
        /// Lift shape. Default elliptic.
        #[serde(default)]
        lift: LiftShape,
        /// Design wing lift coefficient c_L.
        c_l: f64,
    },
    /// Single-point inverse #2: linear washout (the twist shape) and a lift shape at `c_l` →
    /// chord, with the wing angle that gives the spec's aspect ratio.
    InverseChord {
        /// Lift shape. Default elliptic.
        #[serde(default)]
        lift: LiftShape,
        /// Design wing lift coefficient c_L.
        c_l: f64,
        /// Root minus tip angle \[deg\].
        washout_deg: f64,
    },
    /// Two-point inverse #1: the lift at two conditions → chord and twist.
    TwoLift {
        /// Condition 1.
        first: LiftCondition,
        /// Condition 2 (the same wing at another wing angle).
        second: LiftCondition,
    },
    /// Two-point inverse #2: the local c_ℓ at two conditions → chord and twist.
    TwoCl {
        /// Condition 1.
        first: ClCondition,
        /// Condition 2.
        second: ClCondition,
    },
    /// Two-point inverse #3: the lift at condition 1 and the local c_ℓ at condition 2 → chord
    /// and twist.
    LiftAndCl {
        /// Condition 1.
        first: LiftCondition,
        /// Condition 2.
        second: ClCondition,
    },
}

/// What one condition was asked to meet, per station.
#[derive(Debug, Clone, PartialEq)]
pub enum Target {
    /// A lift Γ̂ per station.
    Lift(DVector<f64>),
    /// Local c_ℓ.
    LocalCl(DVector<f64>),
    /// Nothing: direct design, whose lift is the output.
    None,
}

/// A solved design: the wing's chord and twist, and each condition as a direct analysis of them.
#[derive(Debug, Clone)]
pub struct Designed {
    /// `direct`, `inverse_twist`, …
    pub case: &'static str,
    /// One (single-point cases) or two conditions: Γ̂, c_ℓ, c_L of the designed c and α_k.
    pub conditions: Vec<Solution>,
    /// What each condition was asked for.
    pub targets: Vec<Target>,
    /// What each condition was asked for, in words (for reports).
    pub requested: Vec<String>,
    /// The case's Table 1 row ([`Design::title`]).
    pub title: &'static str,
    /// α₂ − α₁ \[rad\] (two-point cases).
    pub delta_alpha_rad: Option<f64>,
    /// Lift slope c_Lα of the planform \[1/rad\].
    pub lift_slope_per_rad: f64,
}

impl Design {
    /// The case's name as the spec spells it.
    pub fn case(&self) -> &'static str {
        match self {
            Self::Direct { .. } => "direct",
            Self::InverseTwist { .. } => "inverse_twist",
            Self::InverseChord { .. } => "inverse_chord",
            Self::TwoLift { .. } => "two_lift",
            Self::TwoCl { .. } => "two_cl",
            Self::LiftAndCl { .. } => "lift_and_cl",
        }
    }

    /// The case's Table 1 row, with its inputs and outputs.
    pub fn title(&self) -> &'static str {
        match self {
            Self::Direct { .. } => "direct design: c, α → ℓ",
            Self::InverseTwist { .. } => "single-point inverse #1: c, ℓ → α",
            Self::InverseChord { .. } => "single-point inverse #2: α, ℓ → c",
            Self::TwoLift { .. } => "two-point inverse #1: ℓ₁, ℓ₂ → c, α",
            Self::TwoCl { .. } => "two-point inverse #2: c_ℓ1, c_ℓ2 → c, α",
            Self::LiftAndCl { .. } => "two-point inverse #3: ℓ₁, c_ℓ2 → c, α",
        }
    }

    /// Checks every field that does not need the stations: angles finite, c_L > 0, taper in
    /// (0, 1], samples from η = 0 to 1 in order. Field paths are relative to `aero.design`.
    ///
    /// # Errors
    /// The first [`FieldError`].
    pub fn validate(&self) -> Result<(), FieldError> {
        let finite = |field: &str, v: f64| Allowed::FINITE.check_field(field, v, "deg");
        let c_l = |field: &str, v: f64| Allowed::POSITIVE.check_field(field, v, "");
        match self {
            Self::Direct {
                chord,
                root_alpha_deg,
                washout_deg,
            } => {
                check_chord(chord)?;
                finite("root_alpha_deg", *root_alpha_deg)?;
                finite("washout_deg", *washout_deg)
            }
            Self::InverseTwist {
                chord,
                lift,
                c_l: cl,
            } => {
                check_chord(chord)?;
                check_lift(lift).map_err(|e| e.within("lift"))?;
                c_l("c_l", *cl)
            }
            Self::InverseChord {
                lift,
                c_l: cl,
                washout_deg,
            } => {
                check_lift(lift).map_err(|e| e.within("lift"))?;
                c_l("c_l", *cl)?;
                finite("washout_deg", *washout_deg)
            }
            Self::TwoLift { first, second } => {
                check_lift_condition(first).map_err(|e| e.within("first"))?;
                check_lift_condition(second).map_err(|e| e.within("second"))
            }
            Self::TwoCl { first, second } => {
                check_spanwise(&first.local_c_l).map_err(|e| e.within("first.local_c_l"))?;
                check_spanwise(&second.local_c_l).map_err(|e| e.within("second.local_c_l"))
            }
            Self::LiftAndCl { first, second } => {
                check_lift_condition(first).map_err(|e| e.within("first"))?;
                check_spanwise(&second.local_c_l).map_err(|e| e.within("second.local_c_l"))
            }
        }
    }

    /// Solves the case on `ll`, then analyses the designed chord and twist directly at each
    /// condition.
    ///
    /// # Errors
    /// [`DesignError::Field`] for a field [`Design::validate`] refuses, or inputs that admit
    /// no wing at the stations (a lift difference that changes sign, a c_ℓ difference of
    /// zero); the field is relative to `aero.design`.
    /// [`DesignError::Llt`] when the solve fails (no positive chord, no convergence).
    pub fn solve(&self, ll: &LiftingLine) -> Result<Designed, DesignError> {
        // A spec built in code has not been through `WingSpec::validate`.
        self.validate()?;
        let y = ll.stations();
        let eta = y.map(|y| (2.0 * y).abs());
        // Q⁻¹e is a factorisation: once, for a chord and a lift that are both elliptic.
        let ellipse = std::cell::OnceCell::new();
        let elliptic = || ellipse.get_or_init(|| ll.elliptic_shape()).clone();
        let washout = |root: f64, washout: f64| eta.map(|e| (root - washout * e).to_radians());
        let chord = |c: &ChordShape| -> Result<DVector<f64>, LltError> {
            let raw = match *c {
                ChordShape::Elliptic => elliptic(),
                ChordShape::Rectangular => DVector::repeat(ll.n(), 1.0),
                ChordShape::Tapered { taper_ratio } => eta.map(|e| 1.0 - e * (1.0 - taper_ratio)),
            };
            ll.chord_from_shape(&raw)
        };
        let lift = |shape: &LiftShape, c_l: f64| -> Result<DVector<f64>, LltError> {
            let raw = match shape {
                LiftShape::Elliptic => elliptic(),
                LiftShape::Bell => eta.map(|e| (1.0 - e * e).max(0.0).powf(1.5)),
                LiftShape::Points(p) => eta.map(|e| interpolate(p, e)),
            };
            ll.gamma_from_shape(&raw, c_l)
        };
        let local_cl = |s: &Spanwise| match s {
            Spanwise::Constant(v) => DVector::repeat(ll.n(), *v),
            Spanwise::Linear { root, tip } => eta.map(|e| root + (tip - root) * e),
            Spanwise::Points(p) => eta.map(|e| interpolate(p, e)),
        };
        let (chord, alpha, delta, targets, requested) = match self {
            Self::Direct {
                chord: c,
                root_alpha_deg,
                washout_deg,
            } => (
                chord(c)?,
                washout(*root_alpha_deg, *washout_deg),
                None,
                vec![Target::None],
                vec![format!(
                    "{} chord, α {root_alpha_deg}° at the root, {washout_deg}° washout",
                    chord_words(c)
                )],
            ),
            Self::InverseTwist {
                chord: c,
                lift: l,
                c_l,
            } => {
                let gamma = lift(l, *c_l)?;
                let s = ll.inverse_twist(&chord(c)?, &gamma)?;
                (
                    s.chord_over_b,
                    s.alpha_rad,
                    None,
                    vec![Target::Lift(gamma)],
                    vec![format!(
                        "{} lift at c_L {c_l}, {} chord",
                        lift_words(l),
                        chord_words(c)
                    )],
                )
            }
            Self::InverseChord {
                lift: l,
                c_l,
                washout_deg,
            } => {
                let gamma = lift(l, *c_l)?;
                let s = ll.inverse_chord_at_aspect_ratio(&washout(0.0, *washout_deg), &gamma)?;
                (
                    s.chord_over_b,
                    s.alpha_rad,
                    None,
                    vec![Target::Lift(gamma)],
                    vec![format!(
                        "{} lift at c_L {c_l} with {washout_deg}° washout",
                        lift_words(l)
                    )],
                )
            }
            Self::TwoLift { first, second } => {
                let g1 = lift(&first.lift, first.c_l)?;
                let g2 = lift(&second.lift, second.c_l)?;
                let d = &g2 - &g1;
                if let Some(j) = (0..d.len()).find(|&j| d[j] * d[0] <= 0.0) {
                    return Err(FieldError::new(
                        "second",
                        format!(
                            "ℓ₂ − ℓ₁ must keep one sign along the span (two-point inverse #1); \
                             it is {:+.3e} at the first station and {:+.3e} at η = {:.4}",
                            d[0], d[j], eta[j]
                        ),
                    )
                    .into());
                }
                let t = ll.two_lift(&g1, &g2)?;
                (
                    t.first.chord_over_b,
                    t.first.alpha_rad,
                    Some(t.delta_alpha_rad),
                    vec![Target::Lift(g1), Target::Lift(g2)],
                    vec![lift_condition_words(first), lift_condition_words(second)],
                )
            }
            Self::TwoCl { first, second } => {
                let (c1, c2) = (local_cl(&first.local_c_l), local_cl(&second.local_c_l));
                let d = &c2 - &c1;
                if let Some(j) = (0..d.len()).find(|&j| d[j] * d[0] <= 0.0) {
                    return Err(FieldError::new(
                        "second.local_c_l",
                        format!(
                            "c_ℓ2 − c_ℓ1 must be non-zero with one sign along the span \
                             (two-point inverse #2); it is {:+.4} at the first station and \
                             {:+.4} at η = {:.4}",
                            d[0], d[j], eta[j]
                        ),
                    )
                    .into());
                }
                let t = ll.two_cl(&c1, &c2)?;
                (
                    t.first.chord_over_b,
                    t.first.alpha_rad,
                    Some(t.delta_alpha_rad),
                    vec![Target::LocalCl(c1), Target::LocalCl(c2)],
                    vec![
                        format!("local c_ℓ {}", spanwise_words(&first.local_c_l)),
                        format!("local c_ℓ {}", spanwise_words(&second.local_c_l)),
                    ],
                )
            }
            Self::LiftAndCl { first, second } => {
                let g1 = lift(&first.lift, first.c_l)?;
                let c2 = local_cl(&second.local_c_l);
                let t = ll.lift_and_cl(&g1, &c2)?;
                (
                    t.first.chord_over_b,
                    t.first.alpha_rad,
                    Some(t.delta_alpha_rad),
                    vec![Target::Lift(g1), Target::LocalCl(c2)],
                    vec![
                        lift_condition_words(first),
                        format!("local c_ℓ {}", spanwise_words(&second.local_c_l)),
                    ],
                )
            }
        };
        // The notes: after the inverse solve, a direct analysis of c and α gives ℓ; α = 1 rad
        // everywhere gives the lift slope c_Lα.
        let mut alphas = vec![DVector::repeat(ll.n(), 1.0), alpha.clone()];
        alphas.extend(delta.map(|da| alpha.add_scalar(da)));
        let mut conditions = ll.direct_many(&chord, &alphas)?;
        let lift_slope_per_rad = conditions.remove(0).c_l;
        Ok(Designed {
            case: self.case(),
            title: self.title(),
            conditions,
            targets,
            requested,
            delta_alpha_rad: delta,
            lift_slope_per_rad,
        })
    }
}

/// A design that cannot be solved.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// Inputs that admit no wing, naming the field (relative to `aero.design`).
    #[error(transparent)]
    Field(#[from] FieldError),
    /// The lifting-line solve.
    #[error(transparent)]
    Llt(#[from] LltError),
}

impl Designed {
    /// The condition the structure is sized for: the one whose lift sits farthest outboard
    /// (largest Σ Γ̂|y| / ΣΓ̂), i.e. the larger root bending moment for the same total lift.
    pub fn structure_condition(&self, stations: &DVector<f64>) -> usize {
        let arm = |s: &Solution| {
            s.gamma_hat
                .iter()
                .zip(stations.iter())
                .map(|(g, y)| g * y.abs())
                .sum::<f64>()
                / s.gamma_hat.sum()
        };
        (0..self.conditions.len())
            .max_by(|&a, &b| arm(&self.conditions[a]).total_cmp(&arm(&self.conditions[b])))
            .unwrap_or(0)
    }

    /// The largest miss of condition `k`'s target: |Γ̂ − Γ̂_req| / max Γ̂_req for a lift,
    /// |c_ℓ − c_ℓ,req| for local lift coefficients; None for direct design.
    pub fn target_error(&self, k: usize) -> Option<f64> {
        let s = self.conditions.get(k)?;
        match self.targets.get(k)? {
            Target::Lift(g) => Some((&s.gamma_hat - g).amax() / g.amax()),
            Target::LocalCl(c) => Some((&s.cl_local - c).amax()),
            Target::None => None,
        }
    }

    /// The report of this design for a wing of `span_mm` whose spars are sized for condition
    /// `structure_condition` (0-based).
    pub fn report(&self, span_mm: f64, structure_condition: usize) -> DesignReport {
        let first = &self.conditions[0];
        let c = &first.chord_over_b;
        let n = c.len();
        let (root, tip) = (centre_value(c), 0.5 * (c[0] + c[n - 1]));
        DesignReport {
            case: self.case,
            title: self.title,
            root_chord_mm: root * span_mm,
            tip_chord_mm: tip * span_mm,
            mean_chord_mm: c.mean() * span_mm,
            area_mm2: c.mean() * span_mm * span_mm,
            aspect_ratio: first.aspect_ratio(),
            lift_slope_per_rad: self.lift_slope_per_rad,
            delta_alpha_deg: self.delta_alpha_rad.map(f64::to_degrees),
            structure_condition: structure_condition + 1,
            conditions: self
                .conditions
                .iter()
                .enumerate()
                .map(|(k, s)| {
                    let a = &s.alpha_rad;
                    let cl = &s.cl_local;
                    ConditionReport {
                        requested: self.requested.get(k).cloned().unwrap_or_default(),
                        c_l: s.c_l,
                        root_alpha_deg: centre_value(a).to_degrees(),
                        tip_alpha_deg: (0.5 * (a[0] + a[n - 1])).to_degrees(),
                        local_c_l_min: cl.min(),
                        local_c_l_max: cl.max(),
                        target_error: self.target_error(k),
                    }
                })
                .collect(),
        }
    }
}

/// The design in `report.json` and a goal's `report_json`: the case, the solved planform and
/// each condition, requested against achieved.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DesignReport {
    /// `direct`, `inverse_twist`, `inverse_chord`, `two_lift`, `two_cl` or `lift_and_cl`.
    pub case: &'static str,
    /// Its Table 1 row.
    pub title: &'static str,
    /// Chord at the centre \[mm\].
    pub root_chord_mm: f64,
    /// Chord at the outermost station \[mm\].
    pub tip_chord_mm: f64,
    /// Mean chord S/b \[mm\].
    pub mean_chord_mm: f64,
    /// Wing area S \[mm²\].
    pub area_mm2: f64,
    /// Aspect ratio of the solved chord, n/Σĉ.
    pub aspect_ratio: f64,
    /// Lift slope c_Lα of the planform \[1/rad\].
    pub lift_slope_per_rad: f64,
    /// α₂ − α₁ \[deg\] (two-point cases).
    pub delta_alpha_deg: Option<f64>,
    /// The condition (1 or 2) whose lift sizes the spars.
    pub structure_condition: usize,
    /// Condition 1 (and 2), from a direct analysis of the designed wing.
    pub conditions: Vec<ConditionReport>,
}

/// One flight condition in a [`DesignReport`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConditionReport {
    /// What the spec asked for.
    pub requested: String,
    /// Wing lift coefficient c_L.
    pub c_l: f64,
    /// Angle from the zero-lift line at the centre \[deg\].
    pub root_alpha_deg: f64,
    /// The same at the outermost station \[deg\].
    pub tip_alpha_deg: f64,
    /// Smallest local c_ℓ.
    pub local_c_l_min: f64,
    /// Largest local c_ℓ.
    pub local_c_l_max: f64,
    /// Largest miss of the target ([`Designed::target_error`]); None for direct design.
    pub target_error: Option<f64>,
}

impl DesignReport {
    /// One line per condition for a terminal.
    pub fn lines(&self) -> Vec<String> {
        let mut out = vec![format!(
            "design {} ({}): chord {:.1} → {:.1} mm root → tip, mean {:.1} mm, AR {:.3}, \
             c_Lα {:.4} /rad{}",
            self.case,
            self.title,
            self.root_chord_mm,
            self.tip_chord_mm,
            self.mean_chord_mm,
            self.aspect_ratio,
            self.lift_slope_per_rad,
            self.delta_alpha_deg
                .map(|d| format!(", Δα {d:.3}°"))
                .unwrap_or_default()
        )];
        for (k, c) in self.conditions.iter().enumerate() {
            out.push(format!(
                "  condition {}{}: c_L {:.4}, α {:.3}° → {:.3}° root → tip, c_ℓ {:.3}…{:.3}; \
                 asked {}{}",
                k + 1,
                if k + 1 == self.structure_condition && self.conditions.len() > 1 {
                    " (sizes the spars)"
                } else {
                    ""
                },
                c.c_l,
                c.root_alpha_deg,
                c.tip_alpha_deg,
                c.local_c_l_min,
                c.local_c_l_max,
                c.requested,
                c.target_error
                    .map(|e| format!(", missed by {e:.1e}"))
                    .unwrap_or_default()
            ));
        }
        out
    }
}

/// The value at the centre: the middle station, or the mean of the two middle ones.
fn centre_value(v: &DVector<f64>) -> f64 {
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Linear interpolation of validated samples (η from 0 to 1, increasing) at `eta` in [0, 1].
fn interpolate(points: &[[f64; 2]], eta: f64) -> f64 {
    let k = points
        .windows(2)
        .position(|w| eta <= w[1][0])
        .unwrap_or(points.len().saturating_sub(2));
    let ([e0, v0], [e1, v1]) = (points[k], points[k + 1]);
    v0 + (v1 - v0) * (eta - e0) / (e1 - e0)
}

fn check_chord(chord: &ChordShape) -> Result<(), FieldError> {
    match chord {
        ChordShape::Tapered { taper_ratio } => Allowed::between(
            Bound::Exclusive(0.0),
            Bound::Inclusive(1.0),
        )
        .check_field("chord.tapered.taper_ratio", *taper_ratio, ""),
        ChordShape::Elliptic | ChordShape::Rectangular => Ok(()),
    }
}

fn check_lift_condition(c: &LiftCondition) -> Result<(), FieldError> {
    check_lift(&c.lift).map_err(|e| e.within("lift"))?;
    Allowed::POSITIVE.check_field("c_l", c.c_l, "")
}

/// A lift shape's samples: η in order from 0 to 1; values > 0 inboard of the tip, ≥ 0 there
/// (the solves need lift at every station, and stations stop short of the tip).
fn check_lift(l: &LiftShape) -> Result<(), FieldError> {
    let LiftShape::Points(p) = l else {
        return Ok(());
    };
    check_samples(p)?;
    for (i, [eta, v]) in p.iter().enumerate() {
        let allowed = if *eta < 1.0 {
            Allowed::POSITIVE
        } else {
            Allowed::NON_NEGATIVE
        };
        allowed.check(*v, "").map_err(|e| {
            e.because("lift inboard of the tip")
                .at(format!("points[{i}][1]"))
        })?;
    }
    Ok(())
}

fn check_spanwise(s: &Spanwise) -> Result<(), FieldError> {
    match s {
        Spanwise::Constant(v) => Allowed::FINITE.check_field("constant", *v, ""),
        Spanwise::Linear { root, tip } => {
            Allowed::FINITE.check_field("linear.root", *root, "")?;
            Allowed::FINITE.check_field("linear.tip", *tip, "")
        }
        Spanwise::Points(p) => {
            check_samples(p)?;
            for (i, [_, v]) in p.iter().enumerate() {
                Allowed::FINITE.check_field(&format!("points[{i}][1]"), *v, "")?;
            }
            Ok(())
        }
    }
}

/// Most samples in one spanwise input (issue 23's rule: every count a spec makes is capped).
/// Each station interpolates through the list, so the work is stations × samples; 1000 is
/// 2.5× the paper's 400 stations, finer than any input needs.
pub const MAX_SAMPLES: usize = 1_000;

/// Samples `[η, value]` (the field `points`): 2 to [`MAX_SAMPLES`] of them, η from exactly 0
/// to exactly 1, strictly increasing.
fn check_samples(p: &[[f64; 2]]) -> Result<(), FieldError> {
    Allowed::closed(2.0, MAX_SAMPLES as f64)
        .whole()
        .check(p.len() as f64, "")
        .map_err(|e| e.because("[η, value] samples (MAX_SAMPLES)").at("points"))?;
    for (i, [eta, _]) in p.iter().enumerate() {
        let field = format!("points[{i}][0]");
        Allowed::closed(0.0, 1.0).check_field(&field, *eta, "")?;
        if i > 0 && *eta <= p[i - 1][0] {
            return Err(FieldError::new(
                field,
                format!(
                    "η = {eta} must be above the previous sample's {}",
                    p[i - 1][0]
                ),
            ));
        }
    }
    let (first, last) = (p[0][0], p[p.len() - 1][0]);
    if first != 0.0 || last != 1.0 {
        return Err(FieldError::new(
            "points",
            format!("the samples span η = {first}…{last}: they must run from 0 (root) to 1 (tip)"),
        ));
    }
    Ok(())
}

fn chord_words(c: &ChordShape) -> String {
    match c {
        ChordShape::Elliptic => "elliptic".into(),
        ChordShape::Rectangular => "rectangular".into(),
        ChordShape::Tapered { taper_ratio } => format!("tapered ({taper_ratio})"),
    }
}

fn lift_words(l: &LiftShape) -> String {
    match l {
        LiftShape::Elliptic => "elliptic".into(),
        LiftShape::Bell => "bell".into(),
        LiftShape::Points(p) => format!("sampled ({} points)", p.len()),
    }
}

fn lift_condition_words(c: &LiftCondition) -> String {
    format!("{} lift at c_L {}", lift_words(&c.lift), c.c_l)
}

fn spanwise_words(s: &Spanwise) -> String {
    match s {
        Spanwise::Constant(v) => format!("{v}"),
        Spanwise::Linear { root, tip } => format!("{root} → {tip} root → tip"),
        Spanwise::Points(p) => format!(
            "{} → {} root → tip ({} samples)",
            p[0][1],
            p[p.len() - 1][1],
            p.len()
        ),
    }
}
