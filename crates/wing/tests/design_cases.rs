//! The six design cases of seed 002 Table 1 through the wing spec (issue 24): each example spec
//! under `config/wings/` designs a wing that meets what it asks for, checked independently of
//! `cell_wing::llt`: the built chord and twist (`Wing::planform`) are analysed with this file's
//! own lifting-line matrices (the notes' Yukish formulation, solved in the form
//! (I + C·W)Γ̂ = ½a·C·α rather than the library's (C⁻¹ + W)Γ̂ = ½a·α), and the lift, the local
//! c_ℓ, the chord and the twist are compared with targets computed here from the spec's words.
//! Bad design fields are refused naming the field.

use std::path::{Path, PathBuf};

use cell_wing::design::{ChordShape, Design, LiftCondition, LiftShape, Spanwise};
use cell_wing::spec::{Wing, WingSpec};
use nalgebra::{DMatrix, DVector};

fn config(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../config/wings")
        .join(name)
}

/// Q_ij = 1/(1 − 4(i−j)²) (notes, "Lifting-line matrix core").
fn q(n: usize) -> DMatrix<f64> {
    DMatrix::from_fn(n, n, |i, j| {
        let d = i as f64 - j as f64;
        1.0 / (1.0 - 4.0 * d * d)
    })
}

/// The wing as built, non-dimensional: ĉ = c/b and the LLT α = built twist − α_L0.
fn built(w: &Wing) -> (DVector<f64>, DVector<f64>) {
    let b = w.planform.span_mm;
    let c = DVector::from_iterator(
        w.planform.chord_mm.len(),
        w.planform.chord_mm.iter().map(|c| c / b),
    );
    let a0 = w.spec.aero.alpha_l0_deg.to_radians();
    let alpha = DVector::from_iterator(c.len(), w.planform.twist_rad.iter().map(|t| t - a0));
    (c, alpha)
}

/// Γ̂ of chord ĉ at α: (I + C·W)Γ̂ = ½a·C·α with W = (a·n/2π)·Q.
fn analyse(a: f64, c: &DVector<f64>, alpha: &DVector<f64>) -> DVector<f64> {
    let n = c.len();
    let w = q(n) * (a * n as f64 / (2.0 * std::f64::consts::PI));
    let m = DMatrix::identity(n, n) + DMatrix::from_diagonal(c) * w;
    m.lu().solve(&(c.component_mul(alpha) * (0.5 * a))).unwrap()
}

/// η = |2y/b| at the stations y/b = −½ + (j + ½)/n.
fn eta(n: usize) -> DVector<f64> {
    DVector::from_fn(n, |j, _| (2.0 * (-0.5 + (j as f64 + 0.5) / n as f64)).abs())
}

/// Γ̂ of a lift shape at c_L: ½(c_L/AR)·n·shape/Σshape.
fn target_lift(l: &LiftCondition, ar: f64, n: usize) -> DVector<f64> {
    let e = eta(n);
    let shape = match &l.lift {
        LiftShape::Elliptic => q(n).lu().solve(&DVector::repeat(n, 1.0)).unwrap(),
        LiftShape::Bell => e.map(|e| (1.0 - e * e).powf(1.5)),
        LiftShape::Points(p) => e.map(|e| lerp(p, e)),
    };
    &shape * (0.5 * l.c_l / ar * n as f64 / shape.sum())
}

fn target_cl(s: &Spanwise, n: usize) -> DVector<f64> {
    let e = eta(n);
    match s {
        Spanwise::Constant(v) => DVector::repeat(n, *v),
        Spanwise::Linear { root, tip } => e.map(|e| root + (tip - root) * e),
        Spanwise::Points(p) => e.map(|e| lerp(p, e)),
    }
}

fn lerp(p: &[[f64; 2]], e: f64) -> f64 {
    let w = p.windows(2).find(|w| e <= w[1][0]).unwrap();
    w[0][1] + (w[1][1] - w[0][1]) * (e - w[0][0]) / (w[1][0] - w[0][0])
}

fn rel(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / b.amax()
}

/// What one example spec was checked against: (case, worst lift/c_ℓ miss per condition).
fn check(name: &str) -> (String, Vec<f64>) {
    let spec = WingSpec::load(config(name)).unwrap();
    let wing = Wing::design(spec.clone()).unwrap();
    let (ar, a, n) = (
        spec.aero.aspect_ratio,
        spec.aero.lift_slope_per_rad,
        spec.aero.stations,
    );
    let (c, alpha1) = built(&wing);
    assert_eq!(c.len(), n);
    // Every design meets the spec's aspect ratio and span.
    let achieved_ar = n as f64 / c.sum();
    assert!(
        (achieved_ar - ar).abs() < 1e-9 * ar,
        "{name}: AR {achieved_ar}"
    );
    let gamma1 = analyse(a, &c, &alpha1);
    let cl = |g: &DVector<f64>| g.component_div(&c) * 2.0;
    let c_l = |g: &DVector<f64>| 2.0 * g.sum() / c.sum();
    // The library's first condition is what this analysis finds.
    assert!(rel(&wing.aero.gamma_hat, &gamma1) < 1e-9, "{name}: ℓ₁");
    let second = || {
        let da = wing.design.delta_alpha_rad.expect("two-point: Δα");
        analyse(a, &c, &alpha1.add_scalar(da))
    };
    let given_chord = |shape: &ChordShape| {
        let e = eta(n);
        let raw = match *shape {
            ChordShape::Elliptic => q(n).lu().solve(&DVector::repeat(n, 1.0)).unwrap(),
            ChordShape::Rectangular => DVector::repeat(n, 1.0),
            ChordShape::Tapered { taper_ratio } => e.map(|e| 1.0 - e * (1.0 - taper_ratio)),
        };
        &raw * (n as f64 / ar / raw.sum())
    };
    let misses = match &spec.aero.design {
        Design::Direct {
            chord,
            root_alpha_deg,
            washout_deg,
        } => {
            assert!(
                rel(&c, &given_chord(chord)) < 1e-12,
                "{name}: chord as given"
            );
            let want = eta(n).map(|e| (root_alpha_deg - washout_deg * e).to_radians());
            assert!((&alpha1 - want).amax() < 1e-12, "{name}: twist as given");
            // The output is the lift: the library's c_L is this analysis's.
            assert!((wing.aero.c_l - c_l(&gamma1)).abs() < 1e-12);
            vec![]
        }
        Design::InverseTwist {
            chord,
            lift,
            c_l: want,
        } => {
            assert!(
                rel(&c, &given_chord(chord)) < 1e-12,
                "{name}: chord as given"
            );
            let t = target_lift(
                &LiftCondition {
                    lift: lift.clone(),
                    c_l: *want,
                },
                ar,
                n,
            );
            assert!((c_l(&gamma1) - want).abs() < 1e-9, "{name}: c_L");
            vec![rel(&gamma1, &t)]
        }
        Design::InverseChord {
            lift,
            c_l: want,
            washout_deg,
        } => {
            // Twist: linear washout about whatever wing angle the solve chose.
            let shape = &alpha1 - eta(n).map(|e| -(washout_deg * e).to_radians());
            assert!(
                shape.max() - shape.min() < 1e-12,
                "{name}: washout as given"
            );
            let t = target_lift(
                &LiftCondition {
                    lift: lift.clone(),
                    c_l: *want,
                },
                ar,
                n,
            );
            assert!((c_l(&gamma1) - want).abs() < 1e-9, "{name}: c_L");
            vec![rel(&gamma1, &t)]
        }
        Design::TwoLift { first, second: s2 } => {
            let g2 = second();
            assert!((c_l(&gamma1) - first.c_l).abs() < 1e-9, "{name}: c_L1");
            assert!((c_l(&g2) - s2.c_l).abs() < 1e-9, "{name}: c_L2");
            vec![
                rel(&gamma1, &target_lift(first, ar, n)),
                rel(&g2, &target_lift(s2, ar, n)),
            ]
        }
        Design::TwoCl { first, second: s2 } => vec![
            (cl(&gamma1) - target_cl(&first.local_c_l, n)).amax(),
            (cl(&second()) - target_cl(&s2.local_c_l, n)).amax(),
        ],
        Design::LiftAndCl { first, second: s2 } => {
            assert!((c_l(&gamma1) - first.c_l).abs() < 1e-9, "{name}: c_L1");
            vec![
                rel(&gamma1, &target_lift(first, ar, n)),
                (cl(&second()) - target_cl(&s2.local_c_l, n)).amax(),
            ]
        }
    };
    for (k, m) in misses.iter().enumerate() {
        assert!(
            *m < 1e-8,
            "{name}: condition {} misses its target by {m:e}",
            k + 1
        );
    }
    // The report says the same.
    let r = wing.design_report();
    assert_eq!(r.case, spec.aero.design.case());
    assert_eq!(r.conditions.len(), wing.design.conditions.len());
    assert!((r.aspect_ratio - ar).abs() < 1e-9);
    for (k, m) in misses.iter().enumerate() {
        let e = r.conditions[k].target_error.unwrap();
        assert!(
            (e - m).abs() < 1e-8,
            "{name}: report's miss {e:e}, measured {m:e}"
        );
    }
    // A printable wing: positive chord below the span, sections, layers.
    assert!(c.iter().all(|c| *c > 0.0 && *c < 0.5), "{name}: chord");
    assert!(
        wing.layers(0).is_some_and(|l| l.len() > 10),
        "{name}: layers"
    );
    for line in r.lines() {
        eprintln!("{name}: {line}");
    }
    let shown: Vec<String> = misses.iter().map(|m| format!("{m:.1e}")).collect();
    eprintln!("{name}: independent re-solve misses the targets by {shown:?}");
    (r.case.to_owned(), misses)
}

#[test]
fn every_example_spec_meets_its_targets() {
    for (name, case) in cell_wing::design::EXAMPLE_SPECS {
        let file = format!("{name}.yaml");
        let (got, _) = check(&file);
        assert_eq!(got, case, "{file}");
    }
}

/// A spec with `design` (YAML lines under `aero.design`, indented by four).
fn spec_text(design: &str) -> String {
    format!(
        "airfoil: {}\naero:\n  span_mm: 1090\n  aspect_ratio: 8\n  stations: 100\n  design:\n{design}\nloads:\n  gross_weight_n: 9.81\n",
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../config/airfoils/ag24.dat")
            .display()
    )
}

/// The error of loading, or else of designing, a spec with `design`.
fn error(design: &str) -> String {
    let spec = match WingSpec::from_yaml_str(&spec_text(design), "w.yaml") {
        Ok(s) => s,
        Err(e) => return e.to_string(),
    };
    match Wing::design(spec) {
        Ok(_) => panic!("designed:\n{design}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_design_fields_are_named() {
    let cases: &[(&str, &str)] = &[
        (
            "    case: direct\n    chord: {tapered: {taper_ratio: 0}}\n    root_alpha_deg: 4\n    washout_deg: 1",
            "w.yaml: field `aero.design.chord.tapered.taper_ratio`: 0 is out of range: must be in (0, 1]",
        ),
        (
            "    case: direct\n    chord: elliptic\n    root_alpha_deg: .nan\n    washout_deg: 1",
            "w.yaml: field `aero.design.root_alpha_deg`: NaN deg is out of range: must be finite",
        ),
        (
            "    case: inverse_twist\n    chord: rectangular\n    c_l: -0.2",
            "w.yaml: field `aero.design.c_l`: -0.2 is out of range: must be finite and > 0",
        ),
        (
            "    case: inverse_chord\n    lift: {points: [[0, 1], [0.8, 0.5], [0.6, 0.2], [1, 0]]}\n    c_l: 0.5\n    washout_deg: 1",
            "w.yaml: field `aero.design.lift.points[2][0]`: η = 0.6 must be above the previous sample's 0.8",
        ),
        (
            "    case: inverse_chord\n    lift: {points: [[0, 1], [0.9, 0.5]]}\n    c_l: 0.5\n    washout_deg: 1",
            "w.yaml: field `aero.design.lift.points`: the samples span η = 0…0.9: they must run from 0 (root) to 1 (tip)",
        ),
        (
            "    case: inverse_chord\n    lift: {points: [[0, 1], [0.5, 0], [1, 0]]}\n    c_l: 0.5\n    washout_deg: 1",
            "w.yaml: field `aero.design.lift.points[1][1]`: 0 is out of range: must be finite and > 0 (lift inboard of the tip)",
        ),
        (
            "    case: two_lift\n    first: {lift: elliptic, c_l: 0.3}\n    second: {lift: bell, c_l: 0}",
            "w.yaml: field `aero.design.second.c_l`: 0 is out of range: must be finite and > 0",
        ),
        (
            "    case: two_cl\n    first: {local_c_l: {constant: 0.3}}\n    second: {local_c_l: {linear: {root: 1.0, tip: .inf}}}",
            "w.yaml: field `aero.design.second.local_c_l.linear.tip`: inf is out of range: must be finite",
        ),
        (
            "    case: lift_and_cl\n    first: {c_l: 0.3}\n    second: {local_c_l: {points: [[0, 1.0]]}}",
            "w.yaml: field `aero.design.second.local_c_l.points`: 1 is out of range: must be in [2, 1000] ([η, value] samples (MAX_SAMPLES))",
        ),
        // Rules that need the stations: reported by the design, which its callers prefix with
        // the file.
        (
            "    case: two_lift\n    first: {lift: elliptic, c_l: 0.3}\n    second: {lift: bell, c_l: 1.0}",
            "field `aero.design.second`: ℓ₂ − ℓ₁ must keep one sign along the span (two-point inverse #1)",
        ),
        (
            "    case: two_cl\n    first: {local_c_l: {constant: 0.5}}\n    second: {local_c_l: {linear: {root: 0.9, tip: 0.1}}}",
            "field `aero.design.second.local_c_l`: c_ℓ2 − c_ℓ1 must be non-zero with one sign along the span",
        ),
        // Inputs no wing can meet: the solve says which case and where.
        (
            "    case: two_cl\n    first: {local_c_l: {constant: 0.5}}\n    second: {local_c_l: {linear: {root: 0.9, tip: 0.5}}}",
            "lifting line (two-point inverse #2): chord at station 25 is -0.0068",
        ),
    ];
    let wrong: Vec<String> = cases
        .iter()
        .map(|(design, want)| (design, want, error(design)))
        .filter(|(_, want, e)| !e.starts_with(*want))
        .map(|(design, want, e)| format!("{design}\n got: {e}\nwant: {want}…"))
        .collect();
    assert!(wrong.is_empty(), "{}", wrong.join("\n\n"));
    // A sample list past the cap (stations × samples is the work).
    let samples = |k: usize| {
        let p: Vec<String> = (0..k)
            .map(|i| format!("[{}, 1]", i as f64 / (k - 1) as f64))
            .collect();
        format!(
            "    case: inverse_chord\n    lift: {{points: [{}]}}\n    c_l: 0.5\n    washout_deg: 0",
            p.join(", ")
        )
    };
    let e = error(&samples(1001));
    assert!(
        e.starts_with("w.yaml: field `aero.design.lift.points`: 1001 is out of range")
            && e.contains("MAX_SAMPLES"),
        "{e}"
    );
    assert!(WingSpec::from_yaml_str(&spec_text(&samples(1000)), "w.yaml").is_ok());
    // Unknown cases and fields are the parser's, with the line.
    let e = error("    case: three_point\n    c_l: 0.3");
    assert!(
        e.contains("w.yaml") && e.contains("three_point") && e.contains("two_lift"),
        "{e}"
    );
    let e =
        error("    case: two_cl\n    first: {local_c_l: {constant: 0.3}}\n    second: {c_l: 1.0}");
    assert!(e.contains("w.yaml") && e.contains("c_l"), "{e}");
}

/// Sampled inputs and defaults: a lift given as samples at the stations is the one designed,
/// and `lift` defaults to elliptic.
#[test]
fn sampled_lift_and_the_elliptic_default() {
    let sampled = "    case: inverse_twist\n    chord: rectangular\n    lift: {points: [[0, 1.0], [0.5, 0.9], [1, 0.0]]}\n    c_l: 0.6";
    let spec = WingSpec::from_yaml_str(&spec_text(sampled), "w.yaml").unwrap();
    let wing = Wing::design(spec).unwrap();
    let (c, alpha) = built(&wing);
    let g = analyse(std::f64::consts::TAU, &c, &alpha);
    let e = eta(100);
    let shape = e.map(|e| {
        if e <= 0.5 {
            1.0 - 0.2 * e
        } else {
            0.9 * (1.0 - e) / 0.5
        }
    });
    assert!(rel(&(&g / g.max()), &(&shape / shape.max())) < 1e-9);
    assert!((2.0 * g.sum() / c.sum() - 0.6).abs() < 1e-9);
    let default = "    case: inverse_chord\n    c_l: 0.4\n    washout_deg: 0";
    let wing =
        Wing::design(WingSpec::from_yaml_str(&spec_text(default), "w.yaml").unwrap()).unwrap();
    // Elliptic lift without washout: the elliptic chord, constant c_ℓ = c_L.
    let (c, alpha) = built(&wing);
    let g = analyse(std::f64::consts::TAU, &c, &alpha);
    let cl = g.component_div(&c) * 2.0;
    assert!(cl.iter().all(|v| (v - 0.4).abs() < 1e-9), "{cl}");
}

/// Two-point inverse #2 with the same c_ℓ difference everywhere: W(ĉ·Δc_ℓ) = aΔα·e − Δc_ℓ makes
/// ĉ ∝ W⁻¹e = Q⁻¹e, the elliptic chord (the example spec asks for exactly that).
#[test]
fn a_uniform_cl_difference_gives_the_elliptic_chord() {
    let wing = Wing::design(WingSpec::load(config("two-point-cl.yaml")).unwrap()).unwrap();
    let (c, _) = built(&wing);
    let n = c.len();
    let ellipse = q(n).lu().solve(&DVector::repeat(n, 1.0)).unwrap();
    assert!(rel(&(&c / c.sum()), &(&ellipse / ellipse.sum())) < 1e-9);
}
