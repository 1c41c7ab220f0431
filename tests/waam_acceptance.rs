//! Acceptance of WAAM near-net deposition (issue 20), checked independently of the slicer and
//! the emitter: `cell slice --process waam` runs on a mesh with the WAAM robot profile as a user
//! would; the RAPID modules it writes are read back with this test's own reader
//! (`common/rapid_reader.rs`), the beads rebuilt from the moves with the bead model written out
//! again from seed 004 (`common/beads.rs`: eq. 14 width, eq. 28 height, the wire feed from the
//! weld data or else from the process file used), and the part voxelised from the STL with its
//! own ray-parity test (`common/voxels.rs`). It asserts that
//!
//! - the beads contain the part with at least the process's machining allowance minus 0.2 mm
//!   (every inside voxel centre in the deposit; at every surface point the deposit reaches at
//!   least that far in every direction measured);
//! - the modules read as one program in which every name an instruction uses is declared (or
//!   predefined by ABB), and the program runs on the in-repo RWS simulator (`cell stream`).
//!
//! Meshes: the 20 mm cube, `plate_holes.STL`, `idler_riser.STL` (drawn in inches: the test
//! scales it by 25.4 as a user would; unscaled it is 0.6 mm high, which must be an error, not an
//! empty program), a 3 mm thin-walled box and a 5 mm pin (generated here).
//!
//! The checker's one assumption about the emitter's convention is [`TOOL_POINT`]: where the
//! robtarget sits on the bead it lays. The first layer's beads must then sit on the plate, which
//! the test asserts, so a changed convention shows up as that failure.

#[path = "common/beads.rs"]
mod beads;
#[path = "common/rapid_reader.rs"]
mod rapid_reader;
#[path = "common/stl_gen.rs"]
mod stl_gen;
#[path = "common/voxels.rs"]
mod voxels;

use std::path::{Path, PathBuf};
use std::time::Instant;

use beads::{beads_of, Deposit, ProcessFacts, ToolPoint};
use rapid_reader::SourceFile;
use voxels::Mesh;

const CELL: &str = env!("CARGO_BIN_EXE_cell");
/// The machine profile of the runs and its simulated controller.
const PROFILE: &str = "abb-irb2600-waam";
const SIM_CONTROLLER: &str = "abb-irb2600-waam-sim";
/// The process of the runs (`--process waam` is this file, built in).
const PROCESS_FILE: &str = "config/processes/waam.yaml";
/// The robtarget's place on its bead (see the module documentation): the top of the bead, or
/// the process's contact-tip-to-work distance above it ([`tool_point`]).
const TOOL_POINT: ToolPoint = ToolPoint::BeadTop;
/// Allowance the issue lets the measure fall short of the process's (mm).
const ALLOWANCE_SLACK_MM: f64 = 0.2;
/// Allowance when the process file names none (the example default).
const DEFAULT_ALLOWANCE_MM: f64 = 1.0;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// A top-level `key: number` of a flat YAML file (the process file's scalars).
fn yaml_number(text: &str, key: &str) -> Option<f64> {
    text.lines().find_map(|l| {
        let (k, v) = l.split_once(':')?;
        (k == key).then(|| v.split('#').next()?.trim().parse().ok())?
    })
}

/// [`TOOL_POINT`], raised by the process file's `torch: ctwd_mm` when it gives one.
fn tool_point() -> ToolPoint {
    let text = std::fs::read_to_string(repo(PROCESS_FILE)).unwrap();
    let ctwd = text.lines().find_map(|l| {
        let v = l.trim_start().strip_prefix("ctwd_mm:")?;
        v.split('#').next()?.trim().parse::<f64>().ok()
    });
    match (TOOL_POINT, ctwd) {
        (ToolPoint::BeadTop, Some(d)) => ToolPoint::AboveBeadTop(d),
        (t, _) => t,
    }
}

/// The process facts and allowance of the process file.
fn process() -> (ProcessFacts, f64) {
    let text = std::fs::read_to_string(repo(PROCESS_FILE)).unwrap();
    let facts = ProcessFacts {
        wire_feed_m_min: yaml_number(&text, "wire_feed_m_min").expect("wire_feed_m_min"),
        wire_diameter_mm: yaml_number(&text, "wire_diameter_mm").expect("wire_diameter_mm"),
    };
    let allowance = yaml_number(&text, "machining_allowance_mm").unwrap_or(DEFAULT_ALLOWANCE_MM);
    (facts, allowance)
}

/// Longest a `cell` run may take before the test fails naming it (a debug build on two busy
/// cores slices these meshes in seconds).
const CELL_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(300);

/// Runs `cell` with `args`; a run past [`CELL_TIMEOUT`] is killed and fails the test.
fn cell(args: &[&str]) -> std::process::Output {
    let dir = tempfile::tempdir().unwrap();
    let (out, err) = (dir.path().join("stdout"), dir.path().join("stderr"));
    let mut child = std::process::Command::new(CELL)
        .args(args)
        .env_remove("RUST_LOG")
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .expect("run cell");
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > CELL_TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("cell {} did not finish in {CELL_TIMEOUT:?}", args.join(" "));
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    std::process::Output {
        status,
        stdout: std::fs::read(&out).unwrap(),
        stderr: std::fs::read(&err).unwrap(),
    }
}

/// The program files `cell slice` wrote into `out`, in the `.pgf`'s order, then the `.pgf`.
fn program_files(out: &Path) -> Vec<(String, String)> {
    let pgf = std::fs::read_dir(out)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|e| e == "pgf"))
        .expect("a .pgf");
    let pgf_text = std::fs::read_to_string(&pgf).unwrap();
    let mut files: Vec<(String, String)> = pgf_text
        .split("<Module>")
        .skip(1)
        .map(|s| {
            let name = s.split("</Module>").next().unwrap().trim().to_string();
            let text = std::fs::read_to_string(out.join(&name)).unwrap_or_else(|e| {
                panic!("{name} listed in {} but not readable: {e}", pgf.display())
            });
            (name, text)
        })
        .collect();
    let written = std::fs::read_dir(out)
        .unwrap()
        .filter(|e| {
            e.as_ref().is_ok_and(|e| {
                e.path()
                    .extension()
                    .is_some_and(|x| x == "mod" || x == "modx")
            })
        })
        .count();
    assert_eq!(
        written,
        files.len(),
        "{}: every module written is listed",
        pgf.display()
    );
    files.push((
        pgf.file_name().unwrap().to_string_lossy().into_owned(),
        pgf_text,
    ));
    files
}

/// The figures of one mesh, and what failed.
struct Outcome {
    failures: Vec<String>,
}

/// Slices `stl` with the CLI, reads the program back, and checks it. Prints the figures.
fn accept(label: &str, stl: &Path) -> Outcome {
    let started = Instant::now();
    let (facts, allowance) = process();
    let margin = allowance - ALLOWANCE_SLACK_MM;
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("out");
    let out = cell(&[
        "slice",
        "--stl",
        &stl.display().to_string(),
        "--out",
        &out_dir.display().to_string(),
        "--process",
        "waam",
        "--profile",
        PROFILE,
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        out.status.success(),
        "{label}: cell slice failed ({:?}): {stderr}",
        out.status.code()
    );
    let sliced = started.elapsed().as_secs_f64();
    let mut failures = Vec::new();

    // The RAPID structure: one program, every name declared.
    let files = program_files(&out_dir);
    let sources: Vec<SourceFile> = files
        .iter()
        .filter(|(n, _)| !n.ends_with(".pgf"))
        .map(|(n, t)| SourceFile { name: n, text: t })
        .collect();
    let program = match rapid_reader::read(&sources) {
        Ok(p) => p,
        Err(problems) => panic!("{label}: the reader cannot read the program: {problems:#?}"),
    };
    let problems = program.structure_problems();
    if !problems.is_empty() {
        let mut names: Vec<String> = problems
            .iter()
            .map(|p| {
                p.message
                    .split('`')
                    .nth(1)
                    .unwrap_or(&p.message)
                    .to_string()
            })
            .collect();
        names.sort();
        names.dedup();
        failures.push(format!(
            "RAPID structure: {} problems, e.g. {}; names: {names:?}",
            problems.len(),
            problems[0]
        ));
    }

    // The program on the simulated controller, as a user would run it.
    let paths: Vec<String> = files
        .iter()
        .map(|(n, _)| out_dir.join(n).display().to_string())
        .collect();
    let mut args = vec!["stream", "--controller", SIM_CONTROLLER, "--program"];
    args.extend(paths.iter().map(String::as_str));
    let streamed = cell(&args);
    if !streamed.status.success() {
        failures.push(format!(
            "RWS simulator: {}",
            String::from_utf8_lossy(&streamed.stderr).trim()
        ));
    }

    // The beads.
    let run = program
        .run_main()
        .unwrap_or_else(|p| panic!("{label}: {p}"));
    let tool = tool_point();
    let beads = beads_of(&run, facts, tool).unwrap_or_else(|e| panic!("{label}: {e}"));
    assert!(!beads.is_empty(), "{label}: the program lays no bead");
    let lowest = beads.iter().map(|b| b.z_base).fold(f64::INFINITY, f64::min);
    if lowest.abs() > 0.3 {
        failures.push(format!(
            "the lowest bead's base is at z = {lowest:.3} mm, not on the plate: is the tool point \
             convention {tool:?} still the emitter's?"
        ));
    }
    let wobjs: std::collections::BTreeSet<&str> =
        run.motions.iter().map(|m| m.wobj.as_str()).collect();
    assert_eq!(wobjs.len(), 1, "{label}: one work object: {wobjs:?}");

    // Reachability: every robtarget has a joint solution in its written robconf, and forward
    // kinematics of that solution gives the robtarget back (the robot model, tool and work
    // object of the profile, through `cell_kinematics`).
    let profile = cell_profiles::MachineProfile::resolve(PROFILE).unwrap();
    let robot_cell = cell_emitter::rapid::reach::RobotCell::of(&profile)
        .unwrap()
        .expect("the WAAM profile has a robot");
    assert_eq!(run.confl, vec!["On".to_string()], "{label}: ConfL \\On");
    for m in &run.motions {
        let t = &m.target;
        let conf = t.conf.map(|c| c as i32);
        let world = robot_cell.target_in_world(t.pos, t.quat);
        let solutions = robot_cell
            .robot
            .solutions_with_confdata(&world, &robot_cell.tool, conf);
        let Some(q) = solutions.first() else {
            failures.push(format!(
                "{} ({}:{}): no joint solution in robconf {conf:?}",
                m.target_name, m.file, m.line
            ));
            break;
        };
        let back = robot_cell.robot.forward(q, &robot_cell.tool).unwrap();
        if back.distance_mm(&world) > 1e-6 || back.angle_to(&world) > 1e-6 {
            failures.push(format!(
                "{}: forward kinematics gives {back:?}, not the robtarget",
                m.target_name
            ));
            break;
        }
    }
    let widths = beads
        .iter()
        .map(|b| 2.0 * b.half_width)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), w| {
            (lo.min(w), hi.max(w))
        });
    let heights = beads
        .iter()
        .map(|b| b.z_top - b.z_base)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), h| {
            (lo.min(h), hi.max(h))
        });

    // The part where the CLI put it: report.json's offset, checked to put it on the plate.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("report.json")).unwrap())
            .unwrap();
    let offset: Vec<f64> = report["offset_mm"]
        .as_array()
        .expect("offset_mm")
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let part = Mesh::read(stl)
        .unwrap()
        .translated([offset[0], offset[1], offset[2]]);
    let (lo, hi) = part.bounds();
    assert!(
        lo[2].abs() < 1e-3,
        "{label}: the part's bottom at z = {}",
        lo[2]
    );
    let size: f64 = (0..3).map(|i| hi[i] - lo[i]).product();
    let spacing = (size / 300_000.0).cbrt().max(0.5);
    let deposit = Deposit::new(beads);
    let c = voxels::measure(&part, &deposit, spacing, margin);
    if c.voxels_outside > 0 {
        failures.push(format!(
            "{} of {} part voxels ({:.1} %) outside the beads, e.g. at {:?}",
            c.voxels_outside,
            c.part_voxels,
            100.0 * c.voxels_outside as f64 / c.part_voxels as f64,
            c.voxels_outside_at
        ));
    }
    if c.surface_below_margin > 0 {
        failures.push(format!(
            "allowance below {margin:.2} mm at {} of {} surface points ({} outside the beads); \
             min {:.3} mm at {:?}; at heights {:?}",
            c.surface_below_margin,
            c.surface_samples,
            c.surface_outside,
            c.min_allowance_mm,
            c.min_allowance_at,
            truncate(&c.short_heights, 12)
        ));
    }
    if c.odd_columns > 0 {
        failures.push(format!(
            "{} voxel columns crossed the mesh an odd number of times",
            c.odd_columns
        ));
    }
    eprintln!(
        "{label}: {} beads (width {:.2}..{:.2} mm, height {:.2}..{:.2} mm), {} moves, {} modules; \
         part {:.0} mm³, deposited {:.0} mm³ (voxels; {:.0} mm³ swept), ratio {:.3}; \
         allowance min {}{:.3} mm (asked {allowance} − {ALLOWANCE_SLACK_MM}), {}/{} surface points \
         short, {}/{} voxels uncovered; grid {spacing:.2} mm; slice {sliced:.1} s, total {:.1} s",
        deposit.beads.len(),
        widths.0,
        widths.1,
        heights.0,
        heights.1,
        run.motions.len(),
        sources.len(),
        c.part_volume_mm3,
        c.deposited_volume_mm3,
        deposit.swept_volume_mm3(),
        c.deposited_volume_mm3 / c.part_volume_mm3,
        // Allowances are measured up to the margin + 1 mm.
        if c.min_allowance_mm >= margin + 1.0 {
            "≥ "
        } else {
            ""
        },
        c.min_allowance_mm,
        c.surface_below_margin,
        c.surface_samples,
        c.voxels_outside,
        c.part_voxels,
        started.elapsed().as_secs_f64()
    );
    for f in &failures {
        eprintln!("{label}: FAIL {f}");
    }
    Outcome { failures }
}

fn truncate(v: &[f64], n: usize) -> Vec<f64> {
    v.iter().take(n).copied().collect()
}

fn assert_accepted(label: &str, stl: &Path) {
    let o = accept(label, stl);
    assert!(
        o.failures.is_empty(),
        "{label}:\n  {}",
        o.failures.join("\n  ")
    );
}

#[test]
fn the_20mm_cube_is_contained_with_its_allowance() {
    assert_accepted("20mm-xyz-cube", &repo("tests/data/stl/20mm-xyz-cube.stl"));
}

#[test]
fn plate_holes_is_contained_with_its_allowance() {
    assert_accepted("plate_holes", &repo("tests/data/stl/plate_holes.STL"));
}

#[test]
fn idler_riser_in_mm_is_contained_with_its_allowance() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("idler_riser_mm.stl");
    Mesh::read(&repo("tests/data/stl/idler_riser.STL"))
        .unwrap()
        .scaled(25.4)
        .write(&path)
        .unwrap();
    assert_accepted("idler_riser (× 25.4)", &path);
}

#[test]
fn idler_riser_as_drawn_is_too_thin_to_deposit_and_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let stl = repo("tests/data/stl/idler_riser.STL");
    let out = cell(&[
        "slice",
        "--stl",
        &stl.display().to_string(),
        "--out",
        &dir.path().join("out").display().to_string(),
        "--process",
        "waam",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "an empty program is an error: {err}");
    assert!(err.contains("idler_riser.STL"), "{err}");
}

#[test]
fn a_3mm_thin_walled_box_is_contained_with_its_allowance() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("thin_box.stl");
    stl_gen::thin_walled_box(40.0, 30.0, 3.0, 20.0)
        .write(&path)
        .unwrap();
    assert_accepted("thin-walled box 3 mm", &path);
}

#[test]
fn a_5mm_pin_is_contained_with_its_allowance() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pin.stl");
    stl_gen::pin(5.0, 30.0, 32).write(&path).unwrap();
    assert_accepted("pin 5 mm", &path);
}

// ---------------------------------------------------------------------------------------------
// The checker on hand-made cases.

#[test]
fn the_reader_resolves_moves_and_finds_undeclared_names() {
    let main = "MODULE M ! a comment; with a semicolon
    PERS tooldata tT := [TRUE,[[0,0,400],[1,0,0,0]],[4.5,[0,0,150],[1,0,0,0],0,0,0]];
    LOCAL CONST speeddata vA := [7,500,5000,1000];
    LOCAL PERS welddata wA := [8,0,[0,0,22,5.5,0,0,0,0,0],[0,0,0,0,0,0,0,0,0]];
    LOCAL CONST robtarget p1 := [[0,0,1],[0,1,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
    LOCAL CONST robtarget p2 := [[10,0,1],[0,1,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
    PROC main()
        ConfL \\On;
        ArcLStart p1, v100, seamX, wA, fine, tT\\WObj:=wobj0;
        ArcLEnd p2, vA, seamX, wA, fine, tT\\WObj:=wobj0;
        M_2_run;
        WaitTime 2.5;
    ENDPROC
ENDMODULE
";
    let part = "MODULE M_2
    PROC M_2_run()
        MoveL Offs(p9, 0, 0, 5), v100, z1, tT;
    ENDPROC
ENDMODULE
";
    let program = rapid_reader::read(&[
        SourceFile {
            name: "M.mod",
            text: main,
        },
        SourceFile {
            name: "M_2.mod",
            text: part,
        },
    ])
    .unwrap();
    let problems: Vec<String> = program
        .structure_problems()
        .iter()
        .map(|p| p.to_string())
        .collect();
    // seamX is declared nowhere; p9 is used in M_2 and declared nowhere; p1 is LOCAL to M.
    assert_eq!(problems.len(), 3, "{problems:#?}");
    assert!(
        problems[0].starts_with("M.mod:9:") && problems[0].contains("`seamX`"),
        "{problems:#?}"
    );
    assert!(
        problems[2].starts_with("M_2.mod:3:") && problems[2].contains("`p9`"),
        "{problems:#?}"
    );
    let part_ok = part.replace("Offs(p9, 0, 0, 5)", "pX").replace(
        "    PROC",
        "    LOCAL CONST robtarget pX := [[10,5,9],[0,1,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n    PROC",
    );
    let main_ok = main.replace(
        "    LOCAL CONST speeddata",
        "    PERS seamdata seamX := [0,0];\n    LOCAL CONST speeddata",
    );
    let program = rapid_reader::read(&[
        SourceFile {
            name: "M.mod",
            text: &main_ok,
        },
        SourceFile {
            name: "M_2.mod",
            text: &part_ok,
        },
    ])
    .unwrap();
    assert_eq!(program.structure_problems(), vec![]);
    let run = program.run_main().unwrap();
    assert_eq!(run.motions.len(), 3);
    assert_eq!(run.confl, vec!["On".to_string()]);
    assert_eq!(run.wait_s, 2.5);
    let weld = run.motions[1].weld.unwrap();
    assert_eq!(
        (weld.weld_speed_mm_s, weld.wire_feed_m_min),
        (8.0, Some(5.5))
    );
    assert_eq!(run.motions[2].target.pos, [10.0, 5.0, 9.0]);
    // The weld data's speed and wire feed set the bead, not the speeddata.
    let facts = ProcessFacts {
        wire_feed_m_min: 4.0,
        wire_diameter_mm: 1.2,
    };
    let beads = beads_of(&run, facts, ToolPoint::BeadTop).unwrap();
    assert_eq!(beads.len(), 1);
    let w = beads::bead_width_mm(8.0, 5.5);
    // The model widens each bead by the program's 0.001 mm position resolution a side.
    assert!((2.0 * beads[0].half_width - w - 2e-3).abs() < 1e-12);
    let h = beads::bead_height_mm(8.0, 5.5, 1.2);
    assert!((beads[0].z_top - 1.0).abs() < 1e-12 && (beads[0].z_base - (1.0 - h)).abs() < 1e-12);
}

#[test]
fn the_deposit_measures_distances_across_touching_beads() {
    // Two 10 mm beads side by side, 1 mm high, tops at z = 1: together 20 mm wide.
    let bead = |y: f64| beads::Bead {
        a: [0.0, y],
        b: [50.0, y],
        half_width: 5.0,
        z_base: 0.0,
        z_top: 1.0,
        travel_speed_mm_s: 7.0,
        wire_feed_m_min: 5.53,
        line: 0,
    };
    let deposit = Deposit::new(vec![bead(0.0), bead(10.0)]);
    // From y = 1 towards +y: across the first bead into the second, out at y = 15.
    let d = deposit.exit_distance([25.0, 1.0, 0.5], [0.0, 1.0, 0.0], 100.0);
    assert!((d - 14.0).abs() < 1e-9, "{d}");
    // Up: out of the top at z = 1; down: into the substrate, as far as asked.
    assert!((deposit.exit_distance([25.0, 1.0, 0.5], [0.0, 0.0, 1.0], 100.0) - 0.5).abs() < 1e-9);
    assert_eq!(
        deposit.exit_distance([25.0, 1.0, 0.5], [0.0, 0.0, -1.0], 3.0),
        3.0
    );
    // Past the round end at x = 55.
    let d = deposit.exit_distance([50.0, 0.0, 0.5], [1.0, 0.0, 0.0], 100.0);
    assert!((d - 5.0).abs() < 1e-9, "{d}");
    assert!(!deposit.contains([25.0, 15.5, 0.5]) && deposit.contains([25.0, 14.5, 0.5]));

    // A 10 × 10 × 0.8 box over the seam of the two: 5 mm of deposit beside it, 0.2 above.
    let boxed = stl_gen::cuboid([10.0, 10.0, 0.8]).translated([20.0, 0.0, 0.0]);
    let c = voxels::measure(&boxed, &deposit, 0.5, 0.1);
    assert_eq!(c.voxels_outside, 0);
    assert!(
        (c.min_allowance_mm - 0.2).abs() < 1e-6,
        "{}",
        c.min_allowance_mm
    );
    assert_eq!(c.surface_below_margin, 0);
    assert!(
        (c.part_volume_mm3 - 80.0).abs() < 1e-9,
        "{}",
        c.part_volume_mm3
    );
}
