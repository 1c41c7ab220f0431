//! RAPID robtargets with a profile's robot: computed configurations under `ConfL \On`, every
//! written robtarget reached by forward kinematics of the joint solution its `robconf`
//! names, and an unreachable point named by layer, segment and point.

use cell_emitter::rapid::{self, reach::RobotCell};
use cell_emitter::EmitError;
use cell_kinematics::{Frame, ReachProblem};
use cell_msgs::geometry_msgs::{Point, Vector3};
use cell_msgs::{Toolpath, ToolpathSegment};
use cell_profiles::MachineProfile;

const DEPOSIT: u8 = ToolpathSegment::KIND_DEPOSIT;
const TRAVEL: u8 = ToolpathSegment::KIND_TRAVEL;
/// Wire feed of the weld points, m/min (the program's welddata take it).
const WIRE_FEED: f32 = 5.53;

fn segment(kind: u8, layer: u32, pts: &[[f64; 3]], normals: &[[f64; 3]]) -> ToolpathSegment {
    let weld = kind != TRAVEL;
    ToolpathSegment {
        kind,
        layer,
        points: pts.iter().map(|&[x, y, z]| Point { x, y, z }).collect(),
        normals: normals
            .iter()
            .map(|&[x, y, z]| Vector3 { x, y, z })
            .collect(),
        feed_mm_s: vec![if weld { 7.0 } else { 50.0 }; pts.len()],
        power: vec![if weld { WIRE_FEED } else { 0.0 }; pts.len()],
        ..Default::default()
    }
}

/// Layers of circular beads of radius 40 mm around `centre` (work object frame), 1.6 mm
/// apart from `z0`, the torch pushed 10° ahead along the travel, with travels between the layers.
fn waam_loops(centre: [f64; 2], z0: f64, layers: u32) -> Toolpath {
    let lead = 10f64.to_radians();
    let mut segments = Vec::new();
    for layer in 0..layers {
        let z = z0 + 1.6 * f64::from(layer + 1);
        let (mut pts, mut normals) = (Vec::new(), Vec::new());
        for i in 0..=72 {
            let a = std::f64::consts::TAU * f64::from(i) / 72.0;
            pts.push([centre[0] + 40.0 * a.cos(), centre[1] + 40.0 * a.sin(), z]);
            // Travel direction (counter-clockwise) t = (−sin a, cos a); axis = n − tan(lead)·t.
            let (tx, ty) = (-a.sin(), a.cos());
            let (x, y) = (-lead.tan() * tx, -lead.tan() * ty);
            let n = (x * x + y * y + 1.0).sqrt();
            normals.push([x / n, y / n, 1.0 / n]);
        }
        let start = pts[0];
        segments.push(segment(
            TRAVEL,
            layer,
            &[[start[0], start[1], z + 20.0], start],
            &[normals[0], normals[0]],
        ));
        segments.push(segment(DEPOSIT, layer, &pts, &normals));
    }
    Toolpath {
        process: Toolpath::PROCESS_WAAM,
        power_unit: Toolpath::POWER_WIRE_FEED_M_MIN,
        segments,
        ..Default::default()
    }
}

/// (position, quaternion, robconf) of every robtarget declared in `text`, in order.
fn robtargets(text: &str) -> Vec<([f64; 3], [f64; 4], [i32; 4])> {
    text.lines()
        .filter(|l| l.contains("CONST robtarget p"))
        .map(|l| {
            let value = &l[l.find(":=").unwrap() + 2..];
            let nums: Vec<f64> = value
                .split(['[', ']', ',', ';', ' '])
                .filter(|t| !t.is_empty())
                .map(|t| t.parse().unwrap())
                .collect();
            (
                [nums[0], nums[1], nums[2]],
                [nums[3], nums[4], nums[5], nums[6]],
                [nums[7], nums[8], nums[9], nums[10]].map(|v| v as i32),
            )
        })
        .collect()
}

fn check_reached(profile_name: &str, toolpath: &Toolpath) {
    let profile = MachineProfile::resolve(profile_name).unwrap();
    let files = rapid::emit(toolpath, &profile, "loops").unwrap();
    let text = &files[0].text;
    assert!(text.contains("        ConfL \\On;"), "{text}");
    assert!(!text.contains("ConfL \\Off"));
    let targets = robtargets(text);
    assert!(targets.len() > 200, "{}", targets.len());
    let cell = RobotCell::of(&profile).unwrap().unwrap();
    let mut confs = std::collections::BTreeSet::new();
    for (i, &(position, quat, robconf)) in targets.iter().enumerate() {
        confs.insert(robconf);
        let world = cell.target_in_world(position, quat);
        // The controller reaches a robtarget in its robconf: there is such a solution, and
        // forward kinematics of it gives back the robtarget.
        let solutions = cell
            .robot
            .solutions_with_confdata(&world, &cell.tool, robconf);
        assert!(
            !solutions.is_empty(),
            "p{}: no solution in {robconf:?}",
            i + 1
        );
        for q in &solutions {
            let back = cell.robot.forward(q, &cell.tool).unwrap();
            assert!(back.distance_mm(&world) < 1e-6, "p{}: {back:?}", i + 1);
            assert!(back.angle_to(&world) < 1e-6, "p{}", i + 1);
            // And in the work object, the written position.
            let local = cell.wobj.inverse().then(&back);
            let d = Frame::new(position, [1.0, 0.0, 0.0, 0.0]).distance_mm(&local);
            assert!(d < 1e-6, "p{}: {d} mm", i + 1);
        }
    }
    // One arm configuration throughout, cfx 0; not the old fixed [0, 0, 0, 0] everywhere.
    assert!(confs.iter().all(|c| c[3] == 0), "{confs:?}");
    assert!(confs.iter().any(|c| *c != [0, 0, 0, 0]), "{confs:?}");
}

#[test]
fn waam_robtargets_carry_their_computed_configuration() {
    // IRB 2600: the plate's middle, around world (1200, 0): axis 1 turns both ways.
    check_reached("abb-irb2600-waam", &waam_loops([300.0, 200.0], 0.0, 4));
    // IRB 1600 on wobj0 (the world, 400 mm above its base), on a 150 mm high part.
    check_reached("abb-irb1600-rw7-do", &waam_loops([700.0, 0.0], 150.0, 3));
}

#[test]
fn a_part_out_of_reach_is_an_error_naming_layer_segment_and_point() {
    let profile = MachineProfile::resolve("abb-irb2600-waam").unwrap();
    let mut tp = waam_loops([300.0, 200.0], 0.0, 2);
    // Layer 7 runs from the middle of the plate to its far top corner (world x 1490 mm,
    // z 695 mm): inside the build volume, beyond the arm's reach.
    let down = [0.0, 0.0, 1.0];
    tp.segments.push(segment(
        TRAVEL,
        7,
        &[[300.0, 200.0, 50.0], [300.0, 200.0, 295.0]],
        &[down; 2],
    ));
    tp.segments.push(segment(
        DEPOSIT,
        7,
        &[
            [300.0, 200.0, 295.0],
            [450.0, 300.0, 295.0],
            [590.0, 390.0, 295.0],
        ],
        &[down; 3],
    ));
    let e = rapid::emit(&tp, &profile, "far").unwrap_err();
    let segment = tp.segments.len() - 1;
    match &e {
        EmitError::Reach {
            layer,
            segment: s,
            point,
            problem,
            ..
        } => {
            assert_eq!((*layer, *s, *point), (7, segment, 2), "{e}");
            assert_eq!(*problem, ReachProblem::OutOfReach);
        }
        other => panic!("expected a reach error, got {other}"),
    }
    let text = e.to_string();
    assert!(
        text.starts_with(&format!(
            "layer 7, segment {segment} point 2 at (590.000, 390.000, 295.000) mm"
        )),
        "{text}"
    );
}

#[test]
fn without_a_robot_the_fixed_configuration_and_confl_off_remain() {
    let mut profile = MachineProfile::resolve("abb-irb2600-waam").unwrap();
    profile.robot = None;
    let files = rapid::emit(&waam_loops([300.0, 200.0], 0.0, 1), &profile, "fixed").unwrap();
    assert!(files[0].text.contains("ConfL \\Off;"));
    assert!(robtargets(&files[0].text)
        .iter()
        .all(|t| t.2 == [0, 0, 0, 0]));
}
