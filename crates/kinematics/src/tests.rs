//! Forward/inverse round trips, configurations and path errors on the IRB 2600 and 1600.

use crate::*;

fn irb2600(base: Frame) -> Robot {
    Robot::new(OpwGeometry::abb_irb2600_165(), IRB2600_LIMITS_DEG, base).unwrap()
}

fn irb1600(base: Frame) -> Robot {
    Robot::new(OpwGeometry::abb_irb1600_145(), IRB1600_LIMITS_DEG, base).unwrap()
}

/// A deterministic sequence in [0, 1) (64-bit LCG, Knuth's constants).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

const TORCH: Frame = Frame {
    trans_mm: [0.0, 0.0, 400.0],
    quat: [1.0, 0.0, 0.0, 0.0],
};
/// Tool z pointing down (−Z), tool x along +X.
const DOWN: [f64; 4] = [0.0, 1.0, 0.0, 0.0];

#[test]
fn calibration_position_is_abb_tool0() {
    // IRB 2600 at all axes 0: flange at x = a1 + c3 + c4 = 1030 mm, z = c1 + c2 + 115 =
    // 1260 mm, tool0 z along base x and x down: [0.7071, 0, 0.7071, 0].
    let r = irb2600(Frame::IDENTITY);
    let f = r.flange_in_base(&[0.0; 6]).unwrap();
    let expected = Frame::new(
        [1030.0, 0.0, 1260.0],
        [0.5f64.sqrt(), 0.0, 0.5f64.sqrt(), 0.0],
    );
    assert!(f.distance_mm(&expected) < 1e-9, "{f:?}");
    assert!(f.angle_to(&expected) < 1e-12, "{f:?}");
    let f = irb1600(Frame::IDENTITY).flange_in_base(&[0.0; 6]).unwrap();
    let expected = Frame::new([815.0, 0.0, 1186.5], expected.quat);
    assert!(f.distance_mm(&expected) < 1e-9, "{f:?}");
}

#[test]
fn the_presets_are_the_published_parameters() {
    // rs-opw-kinematics ships the IRB 2600-12/1.65 set; ours is the same arm.
    let ours = OpwGeometry::abb_irb2600_165();
    let theirs = rs_opw_kinematics::parameters::opw_kinematics::Parameters::irb2600_12_165();
    for (a, b) in [
        (ours.a1_mm, theirs.a1),
        (ours.a2_mm, theirs.a2),
        (ours.b_mm, theirs.b),
        (ours.c1_mm, theirs.c1),
        (ours.c2_mm, theirs.c2),
        (ours.c3_mm, theirs.c3),
        (ours.c4_mm, theirs.c4),
    ] {
        assert!((a / 1000.0 - b).abs() < 1e-12, "{a} mm vs {b} m");
    }
    for (a, b) in ours.offsets_deg.iter().zip(theirs.offsets) {
        assert!((a.to_radians() - b).abs() < 1e-12);
    }
}

/// FK(IK(FK(q))) = FK(q) for every solution, and q itself is among the in-range solutions.
fn round_trips(robot: &Robot, seed: u64, tool: &Frame) {
    let mut rng = Lcg(seed);
    let mut checked = 0;
    for _ in 0..400 {
        let q: Joints = std::array::from_fn(|a| {
            let [lo, hi] = robot.limits_rad()[a];
            lo + (hi - lo) * rng.next()
        });
        // Stay off the wrist singularity (axis 5 = 0), where axes 4 and 6 are not unique.
        if q[4].abs() < 0.05 {
            continue;
        }
        let target = robot.forward(&q, tool).unwrap();
        let all = robot.inverse(&target, tool);
        assert!(!all.is_empty(), "no solution for FK({q:?})");
        for s in &all {
            let back = robot.forward(s, tool).unwrap();
            assert!(
                back.distance_mm(&target) < 1e-6,
                "{s:?}: {back:?} vs {target:?}"
            );
            assert!(back.angle_to(&target) < 1e-6);
        }
        let within = robot.inverse_within_limits(&target, tool);
        assert!(within.iter().all(|s| robot.within_limits(s)));
        assert!(
            within
                .iter()
                .any(|s| s.iter().zip(&q).all(|(a, b)| (a - b).abs() < 1e-6)),
            "{q:?} not among {within:?}"
        );
        checked += 1;
    }
    assert!(checked > 300);
}

#[test]
fn forward_of_every_inverse_solution_is_the_target() {
    let s = 0.5f64.sqrt();
    let base = Frame::new([-250.0, 400.0, 120.0], [s, 0.0, 0.0, s]);
    let tilted_tool = Frame::new([30.0, -10.0, 350.0], [0.9659258, 0.0, 0.258819, 0.0]);
    round_trips(&irb2600(Frame::IDENTITY), 1, &TORCH);
    round_trips(&irb2600(base), 2, &tilted_tool);
    round_trips(&irb1600(Frame::IDENTITY), 3, &TORCH);
    round_trips(&irb1600(base), 4, &tilted_tool);
}

#[test]
fn whole_turns_are_offered_within_the_ranges() {
    let r = irb2600(Frame::IDENTITY);
    // Axis 6 ±400°: 30° is also reachable as −330° and 390°; 100° as −260° (460° is out).
    let d = f64::to_radians;
    let v: Vec<f64> = r
        .turn_variants(5, d(30.0))
        .iter()
        .map(|x| x.to_degrees())
        .collect();
    assert_eq!(v.len(), 3, "{v:?}");
    assert!((v[0] + 330.0).abs() < 1e-9 && (v[1] - 30.0).abs() < 1e-9);
    assert!((v[2] - 390.0).abs() < 1e-9);
    assert_eq!(r.turn_variants(5, d(100.0)).len(), 2); // −260 and 100
    assert_eq!(r.turn_variants(0, d(170.0)).len(), 1);
    // IRB 1600 axis 3 reaches −200°, which the solver reports as 160°.
    let r = irb1600(Frame::IDENTITY);
    let v = r.turn_variants(2, d(160.0));
    assert_eq!(v.len(), 1);
    assert!((v[0].to_degrees() + 200.0).abs() < 1e-9);
}

/// A circle of `radius` mm around (cx, cy) at height z, torch down, `n` points.
fn circle(cx: f64, cy: f64, z: f64, radius: f64, n: usize) -> Vec<Frame> {
    (0..=n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            Frame::new([cx + radius * a.cos(), cy + radius * a.sin(), z], DOWN)
        })
        .collect()
}

#[test]
fn a_layer_loop_stays_in_one_configuration() {
    for robot in [irb2600(Frame::IDENTITY), irb1600(Frame::IDENTITY)] {
        let targets = circle(900.0, 0.0, 300.0, 150.0, 360);
        let path = robot.solve_path(&targets, &TORCH).unwrap();
        assert_eq!(path.len(), targets.len());
        let cfx = path[0].confdata[3];
        assert_eq!(cfx, 0, "the usual configuration first");
        for (i, (p, t)) in path.iter().zip(&targets).enumerate() {
            assert_eq!(p.confdata[3], cfx, "target {i}");
            assert_eq!(Some(p.confdata), robot.confdata(&p.joints));
            assert!(robot.within_limits(&p.joints));
            let back = robot.forward(&p.joints, &TORCH).unwrap();
            assert!(back.distance_mm(t) < 1e-6 && back.angle_to(t) < 1e-6);
        }
        for w in path.windows(2) {
            let step = w[0]
                .joints
                .iter()
                .zip(&w[1].joints)
                .map(|(a, b)| (a - b).abs().to_degrees())
                .fold(0.0, f64::max);
            assert!(step < 5.0, "joint step {step} deg between 2.6 mm targets");
        }
        // Axis 1 follows the circle's sides: it turns both ways, so cf1 is 0 and −1.
        let cf1: std::collections::BTreeSet<i32> = path.iter().map(|p| p.confdata[0]).collect();
        assert_eq!(cf1, [-1, 0].into_iter().collect());
    }
}

#[test]
fn the_torch_spinning_past_axis_6_range_is_a_joint_limit() {
    // Rotating the torch about its own axis: axis 6 winds up and leaves ±400° after a bit
    // more than a turn from where it started, naming the target.
    let robot = irb2600(Frame::IDENTITY);
    let targets: Vec<Frame> = (0..=100)
        .map(|i| {
            let a = (i as f64 * 10.0).to_radians() / 2.0;
            // Half-turn about X (torch down) then a turn `2a` about the tool z axis.
            let spin = Frame::new([0.0; 3], [a.cos(), 0.0, 0.0, a.sin()]);
            let down = Frame::new([900.0, 0.0, 300.0], DOWN);
            down.then(&spin)
        })
        .collect();
    let err = robot.solve_path(&targets, &TORCH).unwrap_err();
    match err.problem {
        ReachProblem::JointLimit { axis, .. } => assert_eq!(axis, 6, "{err}"),
        ref p => panic!("expected a joint limit, got {p:?}"),
    }
    // 800° of range from a start near 0: at most ~40 ten-degree steps plus the start.
    assert!((30..=90).contains(&err.index), "{err}");
    assert!(err
        .to_string()
        .starts_with(&format!("target {}: axis 6", err.index)));
}

#[test]
fn turning_the_wrist_through_its_singularity_needs_another_configuration() {
    // The torch at one point, tilting from straight down to pointing forward and up: its
    // axis lines up with the forearm on the way (axis 5 = 0, the wrist singularity), where
    // axis 5 changes sign: cfx changes, or axes 4 and 6 flip half a turn to keep it. Neither
    // is possible under ConfL \On.
    let robot = irb2600(Frame::IDENTITY);
    let targets: Vec<Frame> = (0..=26)
        .map(|i| {
            let phi = -(i as f64 * 5.0).to_radians();
            let tilt = Frame::new(
                [1250.0, 0.0, 600.0],
                [(phi / 2.0).cos(), 0.0, (phi / 2.0).sin(), 0.0],
            );
            tilt.then(&Frame::new([0.0; 3], DOWN))
        })
        .collect();
    // Every target on its own is reachable within the ranges, in cfx 0 and in cfx 1.
    for t in &targets {
        let cfx: Vec<i32> = robot
            .inverse_within_limits(t, &TORCH)
            .iter()
            .filter_map(|q| robot.cfx(q))
            .collect();
        assert!(cfx.contains(&0) && cfx.contains(&1), "{cfx:?}");
    }
    let err = robot.solve_path(&targets, &TORCH).unwrap_err();
    assert!(
        matches!(
            err.problem,
            ReachProblem::ConfigurationChange { .. } | ReachProblem::JointJump { .. }
        ),
        "{err}"
    );
    // Axis 5 passes 0 between targets 11 and 13.
    assert!((11..=13).contains(&err.index), "{err}");
}

#[test]
fn unreachable_targets_name_their_index() {
    let robot = irb2600(Frame::IDENTITY);
    let mut targets = circle(900.0, 0.0, 300.0, 50.0, 8);
    targets.insert(4, Frame::new([3000.0, 0.0, 300.0], DOWN));
    let err = robot.solve_path(&targets, &TORCH).unwrap_err();
    assert_eq!(err.index, 4);
    assert_eq!(err.problem, ReachProblem::OutOfReach);
    targets[4] = Frame::new([f64::NAN, 0.0, 0.0], DOWN);
    assert_eq!(
        robot.solve_path(&targets, &TORCH).unwrap_err().problem,
        ReachProblem::NotFinite
    );
}

#[test]
fn joint_ranges_are_respected() {
    // Axis 1 limited to ±30°: a target at 90° to the side is reachable only outside it.
    let mut limits = IRB2600_LIMITS_DEG;
    limits[0] = [-30.0, 30.0];
    let robot = Robot::new(OpwGeometry::abb_irb2600_165(), limits, Frame::IDENTITY).unwrap();
    let targets = [
        Frame::new([900.0, 0.0, 300.0], DOWN),
        Frame::new([0.0, 900.0, 300.0], DOWN),
    ];
    let err = robot.solve_path(&targets, &TORCH).unwrap_err();
    assert_eq!(err.index, 1);
    match err.problem {
        ReachProblem::JointLimit {
            axis,
            value_deg,
            min_deg,
            max_deg,
        } => {
            assert_eq!((axis, min_deg, max_deg), (1, -30.0, 30.0));
            assert!(value_deg.abs() > 30.0, "{value_deg}");
        }
        p => panic!("{p:?}"),
    }
    // Bad models name the field.
    let mut bad = IRB2600_LIMITS_DEG;
    bad[4] = [10.0, -10.0];
    let e = Robot::new(OpwGeometry::abb_irb2600_165(), bad, Frame::IDENTITY).unwrap_err();
    assert!(e.to_string().starts_with("joint_limits_deg[4]"), "{e}");
}
