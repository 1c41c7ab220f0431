use super::search::Search;
use super::*;
use crate::cost::CostParams;
use crate::fixtures::{grid, scattered};
use crate::policy::{construct, Policy};
use crate::precedence::PrecedenceMode;
use crate::thermal::ThermalParams;
use proptest::prelude::*;

/// [`improve`] from an evaluated plan with knobs `params` and no hooks: the improved plan.
fn improved(
    eval: &Evaluator,
    start: &CutPlan,
    params: &ImproveParams,
) -> Result<CutPlan, SequencerParamError> {
    let options = ImproveOptions {
        params: params.clone(),
        ..Default::default()
    };
    improve(eval, Start::Plan(start), options).map(|r| r.best)
}

/// [`improve`] from an order not evaluated yet, no hooks: (start plan, improved plan).
fn improved_cuts(
    eval: &Evaluator,
    cuts: &[Cut],
    params: &ImproveParams,
) -> Result<(CutPlan, CutPlan), SequencerParamError> {
    let options = ImproveOptions {
        params: params.clone(),
        ..Default::default()
    };
    improve(eval, Start::Cuts(cuts), options).map(|r| (r.start, r.best))
}

fn quick() -> ImproveParams {
    ImproveParams {
        max_iterations: 30,
        local_sweeps: 2,
        ..Default::default()
    }
}

/// The O(1) idle deltas the window sweep prunes with equal the idle change of the moves
/// themselves (a wrong delta would drop improving moves unseen).
#[test]
fn move_idle_deltas_match_the_moves() {
    let problem = scattered(40, 9);
    let eval = Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
    let start = construct(&eval, Policy::Random, 5).unwrap();
    let mut s = Search::new(&eval, &start.cuts, &quick());
    let n = s.seq.len();
    let idle = |s: &Search| s.span_idle(0, n - 1);
    let before = idle(&s);
    for (lo, split, hi) in [
        (0, 1, 5),
        (3, 6, 20),
        (10, 13, 39),
        (0, 20, 39),
        (38, 39, 39),
    ] {
        let delta = s.swap_blocks_idle_delta(lo, split, hi);
        s.seq[lo..=hi].rotate_left(split - lo);
        assert!(
            (idle(&s) - before - delta).abs() < 1e-9,
            "{lo} {split} {hi}"
        );
        s.seq[lo..=hi].rotate_right(split - lo);
    }
    for (lo, hi) in [(0, 4), (7, 30), (20, 39), (0, 39)] {
        let delta = s.reverse_idle_delta(lo, hi);
        s.seq[lo..=hi].reverse();
        assert!((idle(&s) - before - delta).abs() < 1e-9, "{lo} {hi}");
        s.seq[lo..=hi].reverse();
    }
}

#[test]
fn thermal_off_improvement_shortens_nearest_neighbour() {
    let problem = scattered(120, 3);
    let cost = CostParams {
        thermal: false,
        ..Default::default()
    };
    let eval = Evaluator::new(&problem, ThermalParams::default(), cost).unwrap();
    let nn = construct(&eval, Policy::Nearest, 0).unwrap();
    let mut reports = 0;
    let options = ImproveOptions {
        feedback: Some(&mut |_| reports += 1),
        ..Default::default()
    };
    let better = improve(&eval, Start::Plan(&nn), options).unwrap().best;
    assert_eq!(reports, ImproveParams::default().max_iterations);
    assert!(
        better.idle_mm < 0.97 * nn.idle_mm,
        "{} vs nearest {}",
        better.idle_mm,
        nn.idle_mm
    );
    assert_eq!(problem.precedence.check_order(&better.order()), Ok(()));
}

#[test]
fn improvement_is_deterministic_for_a_seed() {
    let problem = grid(4, 3, 58.0, true, true, PrecedenceMode::Strict);
    let eval = Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
    let start = construct(&eval, Policy::Nearest, 0).unwrap();
    let a = improved(&eval, &start, &quick()).unwrap();
    let b = improved(&eval, &start, &quick()).unwrap();
    assert_eq!(a, b);
    assert!(a.cost <= start.cost);
}

/// The start's raster run alongside the search gives exactly the sequential results.
#[test]
fn concurrent_start_run_matches_the_sequential_one() {
    let problem = grid(3, 3, 58.0, true, true, PrecedenceMode::Strict);
    let eval = Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
    let cuts = crate::policy::construct_cuts(&eval, Policy::Nearest, 0).unwrap();
    let start = eval.evaluate(&cuts);
    let (start2, better2) = improved_cuts(&eval, &cuts, &quick()).unwrap();
    assert_eq!(start2, start);
    assert_eq!(better2, improved(&eval, &start, &quick()).unwrap());
    assert!(better2.cost <= start.cost);
    // With nothing to search, the start comes back evaluated.
    let none = ImproveParams {
        max_iterations: 0,
        local_sweeps: 0,
        ..quick()
    };
    let (s3, b3) = improved_cuts(&eval, &cuts, &none).unwrap();
    assert_eq!(s3, start);
    assert_eq!(b3, start);
}

#[test]
fn bad_params_name_the_field() {
    let problem = grid(1, 1, 60.0, false, false, PrecedenceMode::Strict);
    let eval = Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
    let start = construct(&eval, Policy::Nearest, 0).unwrap();
    let p = ImproveParams {
        window: 0,
        ..Default::default()
    };
    let e = improved(&eval, &start, &p).unwrap_err().to_string();
    assert!(e.contains("window"), "{e}");
}

#[test]
fn knobs_are_capped() {
    type Set = fn(&mut ImproveParams, usize);
    let knobs: [(&str, usize, &str, Set); 5] = [
        (
            "max_iterations",
            MAX_IMPROVE_ITERATIONS,
            "MAX_IMPROVE_ITERATIONS",
            |p, v| p.max_iterations = v,
        ),
        ("window", MAX_WINDOW, "MAX_WINDOW", |p, v| p.window = v),
        (
            "or_opt_max_len",
            MAX_OR_OPT_LEN,
            "MAX_OR_OPT_LEN",
            |p, v| p.or_opt_max_len = v,
        ),
        (
            "local_sweeps",
            MAX_LOCAL_SWEEPS,
            "MAX_LOCAL_SWEEPS",
            |p, v| p.local_sweeps = v,
        ),
        ("lns_remove", MAX_LNS_REMOVE, "MAX_LNS_REMOVE", |p, v| {
            p.lns_remove = v
        }),
    ];
    for (field, limit, constant, set) in knobs {
        let mut p = ImproveParams::default();
        set(&mut p, limit);
        assert_eq!(p.validate(), Ok(()), "{field} at {limit}");
        for over in [limit + 1, usize::MAX] {
            set(&mut p, over);
            let e = p.validate().unwrap_err().to_string();
            assert!(
                e.starts_with(&format!("parameter `{field}` = {over}: must be in ["))
                    && e.ends_with(&format!(", {limit}] ({constant})")),
                "{e}"
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Every contour cut once, no precedence violation in either mode, never worse than
    /// the start, and the thermal evaluation is bit-for-bit repeatable.
    #[test]
    fn improvement_keeps_the_rules_and_never_worsens(
        nx in 1usize..4, ny in 1usize..4, nest: bool, free: bool, strict: bool,
        thermal: bool, policy in 0usize..5, seed in 0u64..1000,
    ) {
        let mode = if strict { PrecedenceMode::Strict } else { PrecedenceMode::Relaxed };
        let problem = grid(nx, ny, 57.0, nest, free, mode);
        prop_assert_eq!(problem.precedence.check_acyclic(), Ok(()));
        let cost = CostParams { thermal, ..Default::default() };
        let eval = Evaluator::new(&problem, ThermalParams::default(), cost).unwrap();
        let start = construct(&eval, Policy::ALL[policy], seed).unwrap();
        prop_assert_eq!(problem.precedence.check_order(&start.order()), Ok(()));
        // A thermal policy's own raster run is the evaluator's.
        prop_assert_eq!(&eval.evaluate(&start.cuts), &start);
        let params = ImproveParams { seed, ..quick() };
        let better = improved(&eval, &start, &params).unwrap();
        prop_assert_eq!(better.cuts.len(), problem.contours.len());
        prop_assert_eq!(problem.precedence.check_order(&better.order()), Ok(()));
        prop_assert!(better.cost <= start.cost);
        let again = eval.evaluate(&better.cuts);
        prop_assert_eq!(again.max_temp_c.to_bits(), better.max_temp_c.to_bits());
        prop_assert_eq!(again, better);
    }
}

/// The local feasibility check of a permuted span agrees with the whole-order check, groups
/// of any size included (a perforated panel's group holds hundreds of contours).
#[test]
fn feasible_span_agrees_with_the_whole_order_check() {
    use rand::{Rng, SeedableRng};
    let layout = crate::generator::generate(&crate::generator::GeneratorConfig {
        seed: 3,
        contours: 120,
        ..Default::default()
    });
    let problem = layout
        .to_problem(
            PrecedenceMode::Strict,
            &crate::layout::PierceOptions::default(),
        )
        .unwrap();
    let eval = Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
    let start = crate::policy::construct_cuts(&eval, Policy::Nearest, 0).unwrap();
    let mut s = Search::new(&eval, &start, &quick());
    let n = s.seq.len();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let (mut feasible, mut infeasible) = (0, 0);
    for _ in 0..3000 {
        let lo = rng.random_range(0..n);
        let hi = (lo + rng.random_range(1..12)).min(n - 1);
        let saved = s.seq.clone();
        // A random permutation of the span: a swap, a rotation or a reversal.
        match rng.random_range(0..3) {
            0 => s.seq.swap(lo, hi),
            1 => s.seq[lo..=hi].rotate_left(1),
            _ => s.seq[lo..=hi].reverse(),
        }
        s.reindex(lo, hi);
        let local = s.feasible_span(lo, hi);
        assert_eq!(
            local,
            problem.precedence.check_order(&s.order()).is_ok(),
            "{lo}..={hi}"
        );
        if local {
            feasible += 1;
        } else {
            infeasible += 1;
        }
        s.seq = saved;
        s.reindex(lo, hi);
    }
    assert!(
        feasible > 100 && infeasible > 100,
        "{feasible} {infeasible}"
    );
}

/// The pierce table's test of a polyline edge against the overheat test's window of cells.
#[test]
fn segments_meet_boxes_where_they_cross_them() {
    use super::proxy::segment_meets_box;
    let (lo, hi) = ([0.0, 0.0], [12.0, 12.0]);
    assert!(
        segment_meets_box([-5.0, 6.0], [20.0, 6.0], lo, hi),
        "through"
    );
    assert!(segment_meets_box([3.0, 3.0], [4.0, 5.0], lo, hi), "inside");
    assert!(
        segment_meets_box([-1.0, 11.0], [1.0, 13.0], lo, hi),
        "across a corner"
    );
    assert!(
        !segment_meets_box([-1.0, 12.5], [1.0, 14.5], lo, hi),
        "past a corner"
    );
    assert!(
        !segment_meets_box([13.0, -5.0], [13.0, 20.0], lo, hi),
        "beside it"
    );
    assert!(
        segment_meets_box([12.0, -5.0], [12.0, 20.0], lo, hi),
        "along its edge"
    );
}

/// Issue 19's target on dense perforated layouts (the bench has the 5000-contour one): at
/// least 50 % fewer overheats than the nearest order within 1.5× its idle length, with a fixed
/// iteration budget.
#[test]
fn dense_perforated_layouts_halve_the_overheats_within_the_idle_budget() {
    for seed in [1, 4] {
        let layout = crate::generator::generate_perforated(&crate::generator::PerforatedConfig {
            seed,
            contours: 300,
            ..Default::default()
        });
        let problem = layout
            .to_problem(
                PrecedenceMode::Strict,
                &crate::layout::PierceOptions::default(),
            )
            .unwrap();
        let eval =
            Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
        let cuts = crate::policy::construct_cuts(&eval, Policy::Nearest, 1).unwrap();
        let params = ImproveParams {
            max_iterations: 200,
            ..Default::default()
        };
        let (nearest, better) = improved_cuts(&eval, &cuts, &params).unwrap();
        assert!(
            nearest.overheats >= 50,
            "seed {seed}: a dense layout overheats"
        );
        assert!(
            2 * better.overheats <= nearest.overheats,
            "seed {seed}: {} overheats against nearest's {}",
            better.overheats,
            nearest.overheats
        );
        assert!(
            better.idle_mm <= 1.5 * nearest.idle_mm,
            "seed {seed}: idle {} against nearest's {}",
            better.idle_mm,
            nearest.idle_mm
        );
        assert_eq!(problem.precedence.check_order(&better.order()), Ok(()));
    }
}
