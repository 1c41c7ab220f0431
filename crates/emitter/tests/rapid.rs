//! The RAPID writer (seed 004 §4.7): every program is run through the RAPID lexer and
//! structure checker in `rapid_check/` (which has its own negative tests below), golden files
//! pin the exact text (`tests/snapshots/`, insta; CI fails on a difference instead of writing
//! a new snapshot), and the orientation, speeddata, splitting, injection and bad-input rules
//! are tested one by one.

mod rapid_check;

use cell_emitter::rapid::{self, orientation_from_normal};
use cell_emitter::EmitError;
use cell_msgs::geometry_msgs::{Point, Vector3};
use cell_msgs::{ProgramFile, Toolpath, ToolpathSegment};
use cell_profiles::rapid::{RobotWare, WeldDataSource, WeldMode};
use cell_profiles::MachineProfile;
use rapid_check::{check_pgf, check_program, lex, Summary, Tok};

const DEPOSIT: u8 = ToolpathSegment::KIND_DEPOSIT;
const TRAVEL: u8 = ToolpathSegment::KIND_TRAVEL;
/// Wire feed of every deposit point, m/min (seed 004 Chart 2's highest, the process default).
const WIRE_FEED: f32 = 5.53;

fn profile(name: &str) -> MachineProfile {
    MachineProfile::resolve(name).unwrap()
}

/// A segment; deposit points carry the wire feed as their power, travel points 0.
fn seg(kind: u8, pts: &[(f64, f64, f64)], feed: f32) -> ToolpathSegment {
    let wire_feed = if kind == TRAVEL { 0.0 } else { WIRE_FEED };
    ToolpathSegment {
        kind,
        points: pts.iter().map(|&(x, y, z)| Point { x, y, z }).collect(),
        feed_mm_s: vec![feed; pts.len()],
        power: vec![wire_feed; pts.len()],
        ..Default::default()
    }
}

fn with_normals(mut s: ToolpathSegment, n: (f64, f64, f64)) -> ToolpathSegment {
    s.normals = vec![
        Vector3 {
            x: n.0,
            y: n.1,
            z: n.2
        };
        s.points.len()
    ];
    s
}

fn toolpath(segments: Vec<ToolpathSegment>) -> Toolpath {
    Toolpath {
        power_unit: Toolpath::POWER_WIRE_FEED_M_MIN,
        segments,
        ..Default::default()
    }
}

fn points(tp: &Toolpath) -> usize {
    tp.segments.iter().map(|s| s.points.len()).sum()
}

/// Names the controller has (the profile's weld data with `data: controller`, or signal);
/// tools and work objects without a value too.
fn externals(p: &MachineProfile) -> Vec<String> {
    let r = p.rapid.as_ref().unwrap();
    let mut out = vec![
        r.tool.name.clone(),
        r.wobj.name.clone(),
        r.zone.name.clone(),
    ];
    match &r.weld {
        WeldMode::Arc {
            seam,
            weld,
            data: WeldDataSource::Controller,
            ..
        } => out.extend([seam.clone(), weld.clone()]),
        WeldMode::Arc { .. } => {}
        WeldMode::DigitalOutput { signal } => out.push(signal.clone()),
    }
    out.retain(|n| match n.as_str() {
        n if n == r.tool.name => r.tool.value.is_none(),
        n if n == r.wobj.name => r.wobj.value.is_none(),
        n if n == r.zone.name => r.zone.value.is_none(),
        _ => true,
    });
    out
}

/// Checks the files of one program: modules through the checker, the `.pgf` lists them in
/// order with the generation's encoding and extension.
fn check(files: &[ProgramFile], p: &MachineProfile) -> Summary {
    let r = p.rapid.as_ref().unwrap();
    let (modules, pgf): (Vec<_>, Vec<_>) = files.iter().partition(|f| !f.name.ends_with(".pgf"));
    assert_eq!(pgf.len(), 1, "one .pgf");
    assert_eq!(files.last().unwrap().name, pgf[0].name, ".pgf comes last");
    let (encoding, ext) = match r.robotware {
        RobotWare::Rw6 => ("ISO-8859-1", ".mod"),
        RobotWare::Rw7 => ("UTF-8", ".modx"),
    };
    for f in files {
        assert!(f.text.is_ascii(), "{}: ASCII only", f.name);
        assert!(!f.text.contains('\r'), "{}: LF line ends", f.name);
        assert!(f.text.ends_with(">\n") || f.text.ends_with("ENDMODULE\n"));
        assert!(
            f.text.lines().all(|l| l == l.trim_end()),
            "{}: no trailing blanks",
            f.name
        );
    }
    let listed = check_pgf(&pgf[0].text, encoding).unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<String> = modules.iter().map(|f| f.name.clone()).collect();
    assert_eq!(listed, names, ".pgf lists every module in order");
    assert!(names.iter().all(|n| n.ends_with(ext)), "{names:?}");
    assert_eq!(
        pgf[0].name,
        names[0].replace(ext, ".pgf"),
        "the .pgf is named after the main module"
    );
    let ext_names = externals(p);
    let ext_refs: Vec<&str> = ext_names.iter().map(String::as_str).collect();
    let texts: Vec<(&str, &str)> = modules
        .iter()
        .map(|f| (f.name.as_str(), f.text.as_str()))
        .collect();
    check_program(&texts, &ext_refs).unwrap_or_else(|e| {
        panic!(
            "RAPID check failed: {e}\n{}",
            texts.iter().map(|(_, t)| *t).collect::<String>()
        )
    })
}

fn moves(s: &Summary) -> usize {
    ["MoveL", "ArcLStart", "ArcL", "ArcLEnd"]
        .iter()
        .map(|i| s.count(i))
        .sum()
}

/// Two beads of a small WAAM wall with a travel move between, torch down.
fn arc_path() -> Toolpath {
    toolpath(vec![
        seg(TRAVEL, &[(50.0, 50.0, 50.0), (100.0, 100.0, 20.0)], 100.0),
        with_normals(
            seg(
                DEPOSIT,
                &[
                    (100.0, 100.0, 2.0),
                    (200.0, 100.0, 2.0),
                    (200.0, 150.0, 2.0),
                ],
                8.0,
            ),
            (0.0, 0.0, 1.0),
        ),
        seg(TRAVEL, &[(200.0, 150.0, 20.0), (100.0, 100.0, 20.0)], 100.0),
        {
            let mut s = with_normals(
                seg(
                    DEPOSIT,
                    &[
                        (100.0, 100.0, 3.6),
                        (200.0, 100.0, 3.6),
                        (200.0, 150.0, 3.6),
                    ],
                    8.0,
                ),
                (0.0, 0.0, 1.0),
            );
            s.feed_mm_s = vec![10.0, 10.0, 12.5];
            s.layer = 1;
            s
        },
    ])
}

/// A small DO-mode program: one flat bead without normals and one on a 45° flank.
fn do_path() -> Toolpath {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    toolpath(vec![
        seg(TRAVEL, &[(600.0, 0.0, 300.0)], 50.0),
        seg(DEPOSIT, &[(600.0, 0.0, 200.0), (700.0, 0.0, 200.0)], 6.0),
        with_normals(
            seg(DEPOSIT, &[(700.0, 0.0, 200.0), (750.0, 0.0, 250.0)], 6.0),
            (-h, 0.0, h),
        ),
        seg(TRAVEL, &[(750.0, 0.0, 350.0)], 50.0),
    ])
}

// ---- golden files ------------------------------------------------------------------------

#[test]
fn golden_arc_mode_program_rw6() {
    let p = profile("abb-irb2600-waam");
    let tp = arc_path();
    let files = rapid::emit(&tp, &p, "wall-42").unwrap();
    let names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["WAAM_wall_42.mod", "WAAM_wall_42.pgf"]);
    let s = check(&files, &p);
    assert_eq!(moves(&s), points(&tp));
    insta::assert_snapshot!("arc_rw6_main", files[0].text);
    insta::assert_snapshot!("arc_rw6_pgf", files[1].text);
}

#[test]
fn golden_digital_output_program_rw7() {
    let p = profile("abb-irb1600-rw7-do");
    let tp = do_path();
    let files = rapid::emit(&tp, &p, "flank").unwrap();
    let names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["flank.modx", "flank.pgf"]);
    let s = check(&files, &p);
    assert_eq!(moves(&s), points(&tp));
    // Off at the start, then on and off once per run.
    assert_eq!(s.count("SetDO"), 1 + 2);
    insta::assert_snapshot!("do_rw7_main", files[0].text);
    insta::assert_snapshot!("do_rw7_pgf", files[1].text);
}

fn split_profile(robotware: RobotWare) -> MachineProfile {
    let mut p = profile("abb-irb2600-waam");
    let r = p.rapid.as_mut().unwrap();
    r.max_targets_per_module = 4;
    r.robotware = robotware;
    p.validate("test").unwrap();
    p
}

#[test]
fn golden_split_program_main_module_and_pgf_rw6_and_rw7() {
    let tp = arc_path();
    for (rw, tag) in [(RobotWare::Rw6, "rw6"), (RobotWare::Rw7, "rw7")] {
        let p = split_profile(rw);
        let files = rapid::emit(&tp, &p, "wall-42").unwrap();
        check(&files, &p);
        insta::assert_snapshot!(format!("split_{tag}_main"), files[0].text);
        insta::assert_snapshot!(format!("split_{tag}_pgf"), files.last().unwrap().text);
    }
}

// ---- speeds, moves, splitting --------------------------------------------------------------

#[test]
fn one_speeddata_per_distinct_rounded_speed_named_in_order_of_first_use() {
    let p = profile("abb-irb2600-waam");
    let mut s = seg(
        DEPOSIT,
        &[
            (100.0, 100.0, 2.0),
            (110.0, 100.0, 2.0),
            (120.0, 100.0, 2.0),
            (130.0, 100.0, 2.0),
            (140.0, 100.0, 2.0),
            (150.0, 100.0, 2.0),
        ],
        8.0,
    );
    // 8.04 rounds onto 8 (speed_decimals: 1); travel runs at the profile's 100 mm/s, and so
    // does the approach to the weld start (its 9.5 is never a bead speed).
    s.feed_mm_s = vec![9.5, 8.0, 8.04, 8.1, 12.0, 8.0];
    let tp = toolpath(vec![seg(TRAVEL, &[(100.0, 100.0, 30.0)], 150.0), s]);
    let files = rapid::emit(&tp, &p, "speeds").unwrap();
    let summary = check(&files, &p);
    let speeds = summary.declared("speeddata");
    // Distinct: 100 (travel and approach), 8, 8.1, 12.
    assert_eq!(speeds, ["vTS1", "vTS2", "vTS3", "vTS4"]);
    assert!(!text_has_speed(&files[0].text, "9.5"));
    let text = &files[0].text;
    for (name, v) in [
        ("vTS1", "100"),
        ("vTS2", "8"),
        ("vTS3", "8.1"),
        ("vTS4", "12"),
    ] {
        let decl = format!("LOCAL CONST speeddata {name} := [{v},500,5000,1000];");
        assert!(text.contains(&decl), "{decl}\n{text}");
    }
    // In order of first use.
    let used: Vec<&str> = text
        .lines()
        .filter_map(|l| l.split(", ").nth(1))
        .filter(|w| w.starts_with("vTS"))
        .collect();
    let mut first = Vec::new();
    for u in used {
        if !first.contains(&u) {
            first.push(u);
        }
    }
    assert_eq!(first, ["vTS1", "vTS2", "vTS3", "vTS4"]);
}

fn text_has_speed(text: &str, v: &str) -> bool {
    text.contains(&format!(":= [{v},"))
}

#[test]
fn a_long_run_is_split_into_modules_called_once_each_in_order() {
    let mut p = profile("abb-irb2600-waam");
    p.rapid.as_mut().unwrap().max_targets_per_module = 10;
    let pts: Vec<(f64, f64, f64)> = (0..25)
        .map(|i| (10.0 + i as f64 * 10.0, 100.0, 2.0))
        .collect();
    let tp = toolpath(vec![seg(DEPOSIT, &pts, 8.0)]);
    let files = rapid::emit(&tp, &p, "long").unwrap();
    let names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "WAAM_long.mod",
            "WAAM_long_1.mod",
            "WAAM_long_2.mod",
            "WAAM_long_3.mod",
            "WAAM_long.pgf"
        ]
    );
    let s = check(&files, &p);
    assert_eq!(moves(&s), 25);
    // main calls the parts once each, in order, after its set-up statements.
    let calls: Vec<&str> = s.statements["main"]
        .iter()
        .map(|(h, _)| h.as_str())
        .filter(|h| h.starts_with("WAAM_long_"))
        .collect();
    assert_eq!(
        calls,
        ["WAAM_long_1_run", "WAAM_long_2_run", "WAAM_long_3_run"]
    );
    // 10 + 10 + 5 targets, each part declaring its own.
    for (module, n) in [("WAAM_long_1", 10), ("WAAM_long_2", 10), ("WAAM_long_3", 5)] {
        let count = s
            .declarations
            .iter()
            .filter(|(m, t, _)| m == module && t == "robtarget")
            .count();
        assert_eq!(count, n, "{module}");
        assert!(s
            .declarations
            .iter()
            .any(|(m, t, _)| m == module && t == "speeddata"));
    }
    // The run goes on across the calls: one ArcLStart, one ArcLEnd.
    assert_eq!((s.count("ArcLStart"), s.count("ArcLEnd")), (1, 1));
}

#[test]
fn splits_fall_between_weld_runs_when_they_fit() {
    let tp = arc_path(); // blocks: 2 travel, run of 3, 2 travel, run of 3 = 10 targets
    let p = split_profile(RobotWare::Rw6);
    let files = rapid::emit(&tp, &p, "w").unwrap();
    let s = check(&files, &p);
    assert_eq!(moves(&s), points(&tp));
    // Limit 4: [T T] [R R R T] [T R R R]: no run is cut, so every part has matched
    // ArcLStart/ArcLEnd.
    let parts: Vec<&str> = s.procs.iter().skip(1).map(String::as_str).collect();
    assert_eq!(parts.len(), 3, "{parts:?}");
    let sizes: Vec<usize> = parts.iter().map(|p| s.statements[*p].len()).collect();
    assert_eq!(sizes, [2, 4, 4]);
    for part in &parts {
        let st = &s.statements[*part];
        assert!(st.len() <= 4);
        let starts = st.iter().filter(|(h, _)| h == "ArcLStart").count();
        let ends = st.iter().filter(|(h, _)| h == "ArcLEnd").count();
        assert_eq!(starts, ends, "{part}: {st:?}");
    }
}

#[test]
fn arc_mode_maps_runs_to_arclstart_arcl_arclend_with_fine_ends() {
    let p = profile("abb-irb2600-waam");
    let files = rapid::emit(&arc_path(), &p, "w").unwrap();
    let body: Vec<&str> = files[0]
        .text
        .lines()
        .map(str::trim)
        .skip_while(|l| *l != "PROC main()")
        .collect();
    let heads: Vec<&str> = body
        .iter()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert_eq!(
        heads,
        [
            "PROC",
            "TPWrite",
            "ConfL",
            "MoveL",
            "MoveL",
            "ArcLStart",
            "ArcL",
            "ArcLEnd",
            "MoveL",
            "MoveL",
            "ArcLStart",
            "ArcL",
            "ArcLEnd",
            "ENDPROC",
            "ENDMODULE"
        ]
    );
    for l in &body {
        if l.starts_with("ArcLStart") || l.starts_with("ArcLEnd") {
            assert!(l.contains(", fine, tWAAM\\WObj:=wobjPlate;"), "{l}");
        }
        if l.starts_with("ArcL ") {
            // data: program: the bead's own welddata, weldWAAM1, weldWAAM2, …
            assert!(
                l.contains(", seamWAAM, weldWAAM") && l.contains(", z1, "),
                "{l}"
            );
        }
    }
}

// ---- welding data --------------------------------------------------------------------------

/// The welddata each weld instruction names, in order: (instruction, target, welddata).
fn weld_calls(text: &str) -> Vec<(String, String, String)> {
    text.lines()
        .map(str::trim)
        .filter(|l| l.starts_with("ArcL"))
        .map(|l| {
            let (head, args) = l.split_once(' ').unwrap();
            let args: Vec<&str> = args.split(", ").collect();
            (head.to_string(), args[0].to_string(), args[3].to_string())
        })
        .collect()
}

/// The value of the declaration `LOCAL PERS <ty> <name> := <value>;` in `text`.
fn pers_value<'a>(text: &'a str, ty: &str, name: &str) -> Option<&'a str> {
    let head = format!("LOCAL PERS {ty} {name} := ");
    text.lines()
        .map(str::trim)
        .find_map(|l| l.strip_prefix(head.as_str()))
        .map(|v| v.trim_end_matches(';'))
}

/// The numbers of a RAPID aggregate, flattened.
fn numbers(value: &str) -> Vec<f64> {
    value
        .split(['[', ']', ','])
        .filter(|t| !t.is_empty())
        .map(|t| t.parse().unwrap())
        .collect()
}

#[test]
fn the_program_declares_one_welddata_per_distinct_bead_with_its_speed_and_wire_feed() {
    let p = profile("abb-irb2600-waam");
    // Beads: run 1 at 8 mm/s; run 2 at 10, 10 and 12.5 mm/s, its first bead with another
    // wire feed (4.39 m/min) at the same speed as the run's start point, whose own values
    // belong to the approach and weld nothing.
    let mut tp = arc_path();
    tp.segments[3].power[1] = 4.39;
    let files = rapid::emit(&tp, &p, "beads").unwrap();
    let s = check(&files, &p);
    let text = &files[0].text;
    assert_eq!(s.declared("seamdata"), ["seamWAAM"]);
    assert_eq!(
        s.declared("welddata"),
        ["weldWAAM1", "weldWAAM2", "weldWAAM3"],
        "{text}"
    );
    // Every weld instruction welds its own point's bead (the run's first: the first bead),
    // with the toolpath's speed and wire feed in the welddata.
    let calls = weld_calls(text);
    let expected = [
        ("ArcLStart", "p3", 8.0, 5.53),
        ("ArcL", "p4", 8.0, 5.53),
        ("ArcLEnd", "p5", 8.0, 5.53),
        ("ArcLStart", "p8", 10.0, 4.39),
        ("ArcL", "p9", 10.0, 4.39),
        ("ArcLEnd", "p10", 12.5, 5.53),
    ];
    assert_eq!(calls.len(), expected.len(), "{text}");
    let arc = |welddata: &str| numbers(pers_value(text, "welddata", welddata).unwrap());
    for ((head, target, weld), (want_head, want_target, speed, wire_feed)) in
        calls.iter().zip(expected)
    {
        assert_eq!((head.as_str(), target.as_str()), (want_head, want_target));
        let v = arc(weld);
        // [weld_speed, org_weld_speed, [sched, mode, voltage, wirefeed, control, current, …],
        //  org_arc]: the profile's synergic job 1, voltage and current from the job.
        assert_eq!(v.len(), 2 + 9 + 9, "{weld}: {v:?}");
        assert_eq!((v[0], v[1]), (speed, speed), "{weld}");
        assert_eq!(
            &v[2..11],
            &[1.0, 0.0, 0.0, wire_feed, 0.0, 0.0, 0.0, 0.0, 0.0],
            "{weld}"
        );
        assert_eq!(&v[2..11], &v[11..20], "org_arc = main_arc");
    }
    // The welddata of 10 mm/s at 4.39 and 12.5 mm/s at 5.53 are distinct from the first.
    let distinct: std::collections::BTreeSet<&str> =
        calls.iter().map(|(_, _, w)| w.as_str()).collect();
    assert_eq!(distinct.len(), 3, "{calls:?}");
    let seam = numbers(pers_value(text, "seamdata", "seamWAAM").unwrap());
    // 16 components, 4 of them arcdata: 12 + 4 * 9 numbers; purge, preflow, postflow first
    // and last as the profile gives them.
    assert_eq!(seam.len(), 12 + 4 * 9);
    assert_eq!((seam[0], seam[1], seam[seam.len() - 1]), (0.2, 0.05, 0.05));
    // Speeddata stay as they were for the moves.
    assert_eq!(s.declared("speeddata"), ["vTS1", "vTS2", "vTS3", "vTS4"]);
}

#[test]
fn a_width_change_in_the_plan_is_a_welddata_change() {
    // One run whose second half is planned narrower (faster, seed 004 eq. 14).
    let p = profile("abb-irb2600-waam");
    let mut s = seg(
        DEPOSIT,
        &[
            (100.0, 100.0, 2.0),
            (150.0, 100.0, 2.0),
            (200.0, 100.0, 2.0),
            (250.0, 100.0, 2.0),
        ],
        7.0,
    );
    s.feed_mm_s = vec![7.0, 7.0, 9.5, 9.5];
    let files = rapid::emit(&toolpath(vec![s]), &p, "w").unwrap();
    check(&files, &p);
    let text = &files[0].text;
    let welds: Vec<String> = weld_calls(text).into_iter().map(|c| c.2).collect();
    assert_eq!(welds, ["weldWAAM1", "weldWAAM1", "weldWAAM2", "weldWAAM2"]);
    assert_eq!(
        numbers(pers_value(text, "welddata", "weldWAAM1").unwrap())[0],
        7.0
    );
    assert_eq!(
        numbers(pers_value(text, "welddata", "weldWAAM2").unwrap())[0],
        9.5
    );
}

#[test]
fn controller_data_are_named_and_not_declared() {
    let mut p = profile("abb-irb2600-waam");
    if let WeldMode::Arc {
        data,
        arc,
        seam_value,
        ..
    } = &mut p.rapid.as_mut().unwrap().weld
    {
        *data = WeldDataSource::Controller;
        *arc = None;
        *seam_value = None;
    }
    p.validate("test").unwrap();
    // The wire feed is not needed either.
    let mut tp = arc_path();
    tp.power_unit = cell_msgs::Toolpath::POWER_ARC_ON;
    let files = rapid::emit(&tp, &p, "w").unwrap();
    let text = &files[0].text;
    assert!(
        !text.contains("seamdata") && !text.contains("welddata"),
        "{text}"
    );
    assert!(weld_calls(text).iter().all(|c| c.2 == "weldWAAM"));
    check(&files, &p);
    // Without the controller's data the program does not stand on its own.
    let modules: Vec<(&str, &str)> = files[..1]
        .iter()
        .map(|f| (f.name.as_str(), f.text.as_str()))
        .collect();
    let e = check_program(&modules, &[]).unwrap_err();
    assert!(e.contains("seamWAAM is used before it is declared"), "{e}");
}

#[test]
fn split_modules_declare_the_weld_data_they_use() {
    let p = split_profile(RobotWare::Rw6);
    let files = rapid::emit(&arc_path(), &p, "w").unwrap();
    let s = check(&files, &p);
    // Parts [T T] [R R R T] [T R R R]: the main module and the first part do not weld.
    let welding: Vec<&String> = s
        .declarations
        .iter()
        .filter(|(_, t, _)| t == "seamdata")
        .map(|(m, _, _)| m)
        .collect();
    assert_eq!(welding, ["WAAM_w_2", "WAAM_w_3"]);
    // A welddata has one number and one value across the program.
    let mut values: std::collections::BTreeMap<String, &str> = Default::default();
    for f in &files[1..files.len() - 1] {
        for (name, _) in weld_calls(&f.text).iter().map(|c| (c.2.clone(), ())) {
            let v = pers_value(&f.text, "welddata", &name).unwrap();
            assert_eq!(*values.entry(name).or_insert(v), v);
        }
    }
    assert_eq!(values.len(), 3, "{values:?}");
}

#[test]
fn program_weld_data_need_the_wire_feed() {
    let p = profile("abb-irb2600-waam");
    let mut tp = arc_path();
    tp.power_unit = cell_msgs::Toolpath::POWER_ARC_ON;
    let e = rapid::emit(&tp, &p, "w").unwrap_err();
    assert!(
        matches!(
            e,
            EmitError::WeldData {
                segment: 1,
                point: 0,
                ..
            }
        ) && e.to_string().contains("POWER_WIRE_FEED_M_MIN"),
        "{e}"
    );
    let mut tp = arc_path();
    tp.segments[3].power[2] = 0.0;
    let e = rapid::emit(&tp, &p, "w").unwrap_err();
    assert_eq!(
        e.to_string(),
        "segment 3 point 2: wire feed 0 m/min on a weld point; it must be > 0"
    );
    let mut tp = arc_path();
    tp.segments[1].power.clear();
    let e = rapid::emit(&tp, &p, "w").unwrap_err();
    assert!(e.to_string().contains("wire feed missing"), "{e}");
}

#[test]
fn module_names_never_take_a_welddata_name() {
    let mut p = profile("abb-irb2600-waam");
    p.rapid.as_mut().unwrap().module_prefix = String::new();
    for (job, module) in [
        ("weldWAAM2", "J_weldWAAM2.mod"),
        ("weldWAAMx", "weldWAAMx.mod"),
    ] {
        let files = rapid::emit(&arc_path(), &p, job).unwrap();
        assert_eq!(files[0].name, module);
        check(&files, &p);
    }
}

/// A WAAM layer without a lift: a two-point travel runs from one bead's end straight to the
/// next bead's start, so both its points coincide with weld points and are dropped. The arc
/// must still go off between the beads (it once ran on across the travel).
#[test]
fn a_travel_without_lift_still_splits_the_weld_runs() {
    let p = profile("abb-irb2600-waam");
    // Two beads at x0..x0 + 100, joined by a travel at bead height.
    let path = |x0: f64| {
        let bead = |y: f64| {
            with_normals(
                seg(DEPOSIT, &[(x0, y, 200.0), (x0 + 100.0, y, 200.0)], 8.0),
                (0.0, 0.0, 1.0),
            )
        };
        toolpath(vec![
            seg(TRAVEL, &[(x0, 50.0, 250.0), (x0, 100.0, 200.0)], 100.0),
            bead(100.0),
            seg(
                TRAVEL,
                &[(x0 + 100.0, 100.0, 200.0), (x0, 120.0, 200.0)],
                100.0,
            ),
            bead(120.0),
        ])
    };
    let tp = path(100.0);
    let files = rapid::emit(&tp, &p, "w").unwrap();
    let s = check(&files, &p);
    assert_eq!(s.count("ArcLStart"), 2, "{}", files[0].text);
    assert_eq!(s.count("ArcLEnd"), 2, "{}", files[0].text);
    let body: Vec<&str> = files[0]
        .text
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with("Arc") || l.starts_with("MoveL"))
        .collect();
    let heads: Vec<&str> = body
        .iter()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert_eq!(
        heads,
        ["MoveL", "ArcLStart", "ArcLEnd", "ArcLStart", "ArcLEnd"],
        "{}",
        files[0].text
    );
    // The second bead is approached at the travel's speed, not the bead's.
    let approach = body[3];
    let travel_speed = body[0].split(", ").nth(1).unwrap();
    assert_eq!(
        approach.split(", ").nth(1).unwrap(),
        travel_speed,
        "{approach}"
    );
    // The DO mode switches the signal off and on between the beads too.
    let p = profile("abb-irb1600-rw7-do");
    let files = rapid::emit(&path(600.0), &p, "w").unwrap();
    let sets: Vec<&str> = files[0]
        .text
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with("SetDO"))
        .collect();
    assert_eq!(sets.len(), 5, "{}", files[0].text); // off at start, on/off per bead
}

#[test]
fn splitting_starts_above_the_limit() {
    let mut p = profile("abb-irb2600-waam");
    p.rapid.as_mut().unwrap().max_targets_per_module = 10;
    for (n, modules) in [(2, 1), (10, 1), (11, 2), (20, 2), (21, 3)] {
        let pts: Vec<(f64, f64, f64)> = (0..n).map(|i| (10.0 + i as f64, 100.0, 2.0)).collect();
        let files = rapid::emit(&toolpath(vec![seg(DEPOSIT, &pts, 8.0)]), &p, "n").unwrap();
        let s = check(&files, &p);
        let parts = if modules == 1 { 0 } else { modules };
        assert_eq!(files.len(), 1 + parts + 1, "{n} points");
        assert_eq!(s.modules.len(), 1 + parts);
        assert_eq!(moves(&s), n);
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(96))]

    /// Any valid toolpath, any limit, either weld mode: the program passes the checker, has one
    /// move per point, parts of at most `limit` targets called once each in order, and one
    /// ArcLStart/ArcLEnd (or SetDO on/off) pair per weld run.
    #[test]
    fn random_toolpaths_give_checked_programs(
        segs in proptest::collection::vec(
            (proptest::bool::ANY, 2usize..7, 0u8..4, proptest::bool::ANY, 0usize..4),
            0..8,
        ),
        limit in 1usize..9,
        do_mode in proptest::bool::ANY,
        rw7 in proptest::bool::ANY,
    ) {
        let mut p = profile("abb-irb2600-waam");
        let r = p.rapid.as_mut().unwrap();
        r.max_targets_per_module = limit;
        r.robotware = if rw7 { RobotWare::Rw7 } else { RobotWare::Rw6 };
        if do_mode {
            r.weld = WeldMode::DigitalOutput { signal: "doWeld".into() };
        }
        let feeds = [4.0f32, 8.0, 8.01, 12.5];
        let mut tp = toolpath(vec![]);
        let mut runs = 0;
        let mut prev_welded = false;
        for (i, &(welded, n, feed, normals, tilt)) in segs.iter().enumerate() {
            let n = if welded { n } else { n - 1 };
            let pts: Vec<(f64, f64, f64)> = (0..n)
                .map(|k| (10.0 + 30.0 * i as f64 + k as f64, 50.0 + 5.0 * k as f64, 2.0 + i as f64))
                .collect();
            let mut s = seg(if welded { DEPOSIT } else { TRAVEL }, &pts, feeds[usize::from(feed)]);
            if normals {
                s = with_normals(s, (0.1 * tilt as f64, -0.2 * tilt as f64, 1.0));
            }
            if welded && !prev_welded {
                runs += 1;
            }
            prev_welded = welded;
            tp.segments.push(s);
        }
        let files = rapid::emit(&tp, &p, "prop").unwrap();
        let s = check(&files, &p);
        proptest::prop_assert_eq!(moves(&s), points(&tp));
        if do_mode {
            proptest::prop_assert_eq!(s.count("SetDO"), 1 + 2 * runs);
        } else {
            proptest::prop_assert_eq!(s.count("ArcLStart"), runs);
            proptest::prop_assert_eq!(s.count("ArcLEnd"), runs);
        }
        if s.modules.len() > 1 {
            let parts: Vec<String> = (1..s.modules.len()).map(|i| format!("WAAM_prop_{i}_run")).collect();
            let calls: Vec<String> = s.statements["main"]
                .iter()
                .map(|(h, _)| h.clone())
                .filter(|h| h.starts_with("WAAM_prop_"))
                .collect();
            proptest::prop_assert_eq!(calls, parts);
            for m in &s.modules[1..] {
                let targets = s.declarations.iter().filter(|(mm, t, _)| mm == m && t == "robtarget").count();
                proptest::prop_assert!(targets >= 1 && targets <= limit);
            }
        } else {
            let distinct: std::collections::BTreeSet<String> = tp
                .segments
                .iter()
                .flat_map(|s| {
                    let travel = s.kind == TRAVEL;
                    s.feed_mm_s.iter().map(move |f| if travel { "100".to_string() } else { format!("{:.1}", f) })
                })
                .map(|v| v.trim_end_matches(".0").to_string())
                .collect();
            proptest::prop_assert_eq!(s.declared("speeddata").len(), distinct.len());
        }
    }
}

// ---- orientation ---------------------------------------------------------------------------

/// `v` rotated by the unit quaternion `q` = [w, x, y, z].
fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let [w, x, y, z] = q;
    let u = [x, y, z];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let t = cross(u, v).map(|c| 2.0 * c);
    let ut = cross(u, t);
    [
        v[0] + w * t[0] + ut[0],
        v[1] + w * t[1] + ut[1],
        v[2] + w * t[2] + ut[2],
    ]
}

fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
    a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= tol)
}

#[test]
fn normal_up_gives_the_tool_z_axis_down_and_tool_x_along_x() {
    let q = orientation_from_normal([0.0, 0.0, 1.0]).unwrap();
    assert!(
        close([q[0], q[1], q[2]], [0.0, 1.0, 0.0], 1e-12) && q[3].abs() < 1e-12,
        "{q:?}"
    );
    assert!(close(rotate(q, [0.0, 0.0, 1.0]), [0.0, 0.0, -1.0], 1e-12));
    assert!(close(rotate(q, [1.0, 0.0, 0.0]), [1.0, 0.0, 0.0], 1e-12));
}

#[test]
fn tilted_normals_give_the_tool_axis_against_the_normal() {
    for n in [
        [1.0, 0.0, 1.0],
        [0.3, -0.5, 0.8],
        [0.0, 1.0, 0.2],
        [-0.2, 0.1, -1.0],
        [1.0, 0.0, 0.0], // degenerate: tool z along -X, tool x falls back to +Y
    ] {
        let q = orientation_from_normal(n).unwrap();
        let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!((norm - 1.0).abs() < 1e-12 && q[0] >= 0.0, "{q:?}");
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let tool_z = rotate(q, [0.0, 0.0, 1.0]);
        assert!(
            close(tool_z, n.map(|v| -v / len), 1e-12),
            "{n:?}: {tool_z:?}"
        );
        // Tool x: perpendicular to the tool axis, in the plane of +X and the axis (y = 0 in
        // the plane's frame), pointing towards +X.
        let tool_x = rotate(q, [1.0, 0.0, 0.0]);
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        assert!(dot(tool_x, tool_z).abs() < 1e-12);
        if n != [1.0, 0.0, 0.0] {
            assert!(tool_x[0] > 0.0, "{n:?}: {tool_x:?}");
            let x_proj = [
                1.0 - tool_z[0] * tool_z[0],
                -tool_z[0] * tool_z[1],
                -tool_z[0] * tool_z[2],
            ];
            let l = dot(x_proj, x_proj).sqrt();
            assert!(close(tool_x, x_proj.map(|v| v / l), 1e-12), "{n:?}");
        } else {
            assert!(close(tool_x, [0.0, 1.0, 0.0], 1e-12), "{tool_x:?}");
        }
    }
    assert_eq!(orientation_from_normal([0.0, 0.0, 0.0]), None);
    assert_eq!(orientation_from_normal([f64::NAN, 0.0, 1.0]), None);
}

#[test]
fn written_robtargets_carry_the_normal_orientation() {
    let p = profile("abb-irb1600-rw7-do");
    let files = rapid::emit(&do_path(), &p, "flank").unwrap();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    // p4 and p5 are the flank points, normal (-h, 0, h); p2 has no normal: the default.
    for (target, normal) in [
        ("p2", [0.0, 0.0, 1.0]),
        ("p4", [-h, 0.0, h]),
        ("p5", [-h, 0.0, h]),
    ] {
        let line = files[0]
            .text
            .lines()
            .find(|l| l.contains(&format!("robtarget {target} :=")))
            .unwrap();
        let toks = lex(line).unwrap();
        let nums: Vec<f64> = toks
            .windows(2)
            .filter_map(|w| match (&w[0].tok, &w[1].tok) {
                (Tok::Punct(m), Tok::Num(n)) if m == "-" => Some(-n.parse::<f64>().unwrap()),
                (Tok::Punct(_), Tok::Num(n)) => Some(n.parse::<f64>().unwrap()),
                _ => None,
            })
            .collect();
        let q = [nums[3], nums[4], nums[5], nums[6]];
        let tool_z = rotate(q, [0.0, 0.0, 1.0]);
        assert!(
            close(tool_z, normal.map(|v| -v), 1e-5),
            "{line}: {tool_z:?}"
        );
    }
}

// ---- user text -----------------------------------------------------------------------------

#[test]
fn job_ids_cannot_inject_code() {
    let evil = [
        "x\"; ENDPROC\nPROC evil()\n    MoveL p1, v1000, fine, tool0;\nENDPROC\n! ",
        "ENDMODULE",
        "main",
        "p1",
        "vTS1",
        "123",
        "\\",
        "\"",
        "a\r\nb\u{2028}c",
        "",
        "Düse ✓ «job»",
        "tTorch",
        "doWeld_1_run",
        "!comment",
        "%\"x\"%",
    ];
    let long = "y\"".repeat(120);
    for (p, tp) in [
        (profile("abb-irb2600-waam"), arc_path()),
        (profile("abb-irb1600-rw7-do"), arc_path_do()),
    ] {
        for job in evil.iter().copied().chain([long.as_str()]) {
            let files = rapid::emit(&tp, &p, job).unwrap_or_else(|e| panic!("{job:?}: {e}"));
            let s = check(&files, &p);
            assert_eq!(s.procs, ["main"], "{job:?}");
            assert_eq!(s.count("TPWrite"), 1);
            assert_eq!(moves(&s), points(&tp), "{job:?}");
            // The string round-trips: the job id itself, cut to 80 characters, non-ASCII as ?.
            let want: String = job
                .chars()
                .take(80)
                .map(|c| if c.is_ascii() { c } else { '?' })
                .collect();
            assert_eq!(s.strings[0], want, "{job:?}");
            // Comments stay on their line.
            for l in files[0].text.lines() {
                let t = l.trim_start();
                assert!(
                    t.starts_with('!')
                        || t.starts_with("MODULE")
                        || t.starts_with("ENDMODULE")
                        || t.starts_with("PROC")
                        || t.starts_with("ENDPROC")
                        || t.ends_with(';')
                        || t.is_empty(),
                    "{job:?}: {l}"
                );
            }
        }
    }
    // Clashes get J_ in front; a leading digit gets J.
    let p = profile("abb-irb1600-rw7-do");
    for (job, module) in [
        ("main", "J_main.modx"),
        ("p1", "J_p1.modx"),
        ("ENDMODULE", "J_ENDMODULE.modx"),
        ("tTorch", "J_tTorch.modx"),
        ("123", "J123.modx"),
        ("", "job.modx"),
    ] {
        let files = rapid::emit(&arc_path_do(), &p, job).unwrap();
        assert_eq!(files[0].name, module, "{job:?}");
    }
    let files = rapid::emit(&arc_path(), &profile("abb-irb2600-waam"), &"z".repeat(50)).unwrap();
    assert_eq!(files[0].name, format!("WAAM_{}.mod", "z".repeat(17)));
}

/// `arc_path` moved into the IRB 1600's world-frame volume.
fn arc_path_do() -> Toolpath {
    let mut tp = arc_path();
    for s in &mut tp.segments {
        for p in &mut s.points {
            p.x += 550.0;
            p.y -= 100.0;
            p.z += 150.0;
        }
    }
    tp
}

// ---- bad input -----------------------------------------------------------------------------

#[test]
fn bad_input_is_named_and_gives_no_program() {
    let p = profile("abb-irb2600-waam");
    let err = |tp: &Toolpath| rapid::emit(tp, &p, "j").unwrap_err();
    let mut tp = arc_path();
    tp.segments[1].points[2].y = f64::NAN;
    assert_eq!(err(&tp).to_string(), "segment 1 point 2: y is not finite");
    let mut tp = arc_path();
    tp.segments[3].normals[1].z = f64::INFINITY;
    assert_eq!(
        err(&tp).to_string(),
        "segment 3 point 1: normal z is not finite"
    );
    let mut tp = arc_path();
    tp.segments[3].normals[0] = Vector3::default();
    assert_eq!(
        err(&tp),
        EmitError::Normal {
            segment: 3,
            point: 0
        }
    );
    let mut tp = arc_path();
    tp.segments[1].feed_mm_s[1] = 0.0;
    assert!(matches!(
        err(&tp),
        EmitError::Feed {
            segment: 1,
            point: 1,
            ..
        }
    ));
    let mut tp = arc_path();
    tp.segments[1].feed_mm_s[1] = 0.04; // rounds to 0 at one decimal
    assert!(matches!(
        err(&tp),
        EmitError::Feed {
            segment: 1,
            point: 1,
            ..
        }
    ));
    let mut tp = arc_path();
    tp.segments[1].feed_mm_s[2] = 300.0;
    assert!(err(&tp)
        .to_string()
        .starts_with("segment 1 point 2: speed 300 mm/s is above"));
    let mut tp = arc_path();
    tp.segments[1].points[1].x = 700.0;
    assert!(
        err(&tp)
            .to_string()
            .starts_with("segment 1 point 1: X = 700.000"),
        "{}",
        err(&tp)
    );
    let mut tp = arc_path();
    tp.segments[1].feed_mm_s.pop();
    assert_eq!(
        err(&tp).to_string(),
        "segment 1: feed_mm_s has 2 entries, the segment has 3 points"
    );
    let mut tp = arc_path();
    tp.segments[1].normals.pop();
    assert!(matches!(
        err(&tp),
        EmitError::Length {
            segment: 1,
            what: "normals",
            ..
        }
    ));
    let tp = toolpath(vec![
        seg(TRAVEL, &[(10.0, 10.0, 10.0)], 50.0),
        seg(DEPOSIT, &[(10.0, 10.0, 2.0)], 8.0),
        seg(TRAVEL, &[(10.0, 10.0, 10.0)], 50.0),
    ]);
    assert_eq!(
        err(&tp),
        EmitError::ShortRun {
            segment: 1,
            point: 0
        }
    );
    let mut tp = arc_path();
    tp.segments[1].secondary_points = tp.segments[1].points.clone();
    tp.segments[1].secondary_points[0].x += 1.0;
    assert!(matches!(err(&tp), EmitError::NoAxis { .. }));
    // A machine without Z cannot take RAPID.
    let mut flat = p.clone();
    flat.axes.remove(&'Z');
    assert!(matches!(
        rapid::emit(&arc_path(), &flat, "j"),
        Err(EmitError::NoAxis { .. })
    ));
    // And no rapid section.
    let gcode = profile("grbl-xy");
    assert!(matches!(
        rapid::emit(&arc_path(), &gcode, "j"),
        Err(EmitError::MissingSection { .. })
    ));
}

#[test]
fn emit_program_dispatches_to_rapid() {
    let p = profile("abb-irb2600-waam");
    let prog = cell_emitter::emit_program(&arc_path(), &p, "wall-42").unwrap();
    assert_eq!(prog.dialect, "rapid");
    assert_eq!(prog.files.len(), 2);
    assert_eq!(prog.files[0].name, "WAAM_wall_42.mod");
    assert!(prog.line_count > 20);
}

#[test]
fn an_empty_toolpath_gives_an_empty_main() {
    let p = profile("abb-irb1600-rw7-do");
    let files = rapid::emit(&Toolpath::default(), &p, "empty").unwrap();
    let s = check(&files, &p);
    assert_eq!(moves(&s), 0);
    assert_eq!(s.count("SetDO"), 1);
}

// ---- the checker itself --------------------------------------------------------------------

const SAMPLE_MAIN: &str = "MODULE Sample
    ! a comment with \"quotes\", ENDPROC and PROC x()
    LOCAL CONST string s := \"a \"\"quoted\"\" \\\\ word\\0A\";
    PERS tooldata tA := [TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];
    LOCAL CONST speeddata vTS1 := [10,500,5000,1000];
    LOCAL CONST robtarget p1 := [[1,-2.5,3E2],[0,1,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];

    PROC main()
        TPWrite s;
        ConfL \\Off;
        MoveL p1, vTS1, fine, tA\\WObj:=wobj0;
        Part2;
    ENDPROC
ENDMODULE
";

const SAMPLE_PART: &str = "MODULE Sample_2
    LOCAL CONST robtarget p1 := [[1,2,3],[0,1,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];

    PROC Part2()
        MoveL p1, v100, z1, tA;
        SetDO doWeld, 1;
    ENDPROC
ENDMODULE
";

fn check_sample(main: &str, part: &str) -> Result<Summary, String> {
    check_program(&[("Sample.mod", main), ("Sample_2.mod", part)], &["doWeld"])
}

#[test]
fn checker_accepts_a_valid_program() {
    let s = check_sample(SAMPLE_MAIN, SAMPLE_PART).unwrap();
    assert_eq!(s.modules, ["Sample", "Sample_2"]);
    assert_eq!(s.procs, ["main", "Part2"]);
    assert_eq!(s.strings, ["a \"quoted\" \\ word\n"]);
    assert_eq!(s.count("MoveL"), 2);
}

#[test]
fn checker_rejects_broken_programs() {
    let long = "x".repeat(32);
    let cases: Vec<(String, String, &str)> = vec![
        // (main, part, expected message fragment)
        (SAMPLE_MAIN.replace("ENDMODULE\n", ""), SAMPLE_PART.into(), "ENDMODULE"),
        (SAMPLE_MAIN.replacen("    ENDPROC\n", "", 1), SAMPLE_PART.into(), "ENDPROC"),
        (SAMPLE_MAIN.into(), SAMPLE_PART.replace("    ENDPROC\n", ""), "ENDPROC"),
        (SAMPLE_MAIN.replace("MoveL p1", "MoveL p2"), SAMPLE_PART.into(), "p2 is used before it is declared"),
        (SAMPLE_MAIN.replace("tA\\WObj", "tB\\WObj"), SAMPLE_PART.into(), "tB is used before"),
        (SAMPLE_MAIN.replace("p1", &format!("p{long}")), SAMPLE_PART.into(), "33 characters"),
        (SAMPLE_MAIN.replace("vTS1", "ENDIF"), SAMPLE_PART.into(), "reserved word ENDIF"),
        (SAMPLE_MAIN.replace("PROC main", "PROC Module"), SAMPLE_PART.into(), "reserved word Module"),
        (SAMPLE_MAIN.replace("a \"\"quoted", &"z".repeat(80)), SAMPLE_PART.into(), "string of"),
        (SAMPLE_MAIN.replace("ConfL \\Off;", "ConfL \\Off"), SAMPLE_PART.into(), "expected ';'"),
        (SAMPLE_MAIN.replace("TPWrite s;", "TPWrite s"), SAMPLE_PART.into(), "expected ';'"),
        (SAMPLE_MAIN.replace("Part2;", "Part3;"), SAMPLE_PART.into(), "Part3 is neither"),
        (SAMPLE_MAIN.replace(" word", " wo\nrd"), SAMPLE_PART.into(), "line break inside a string"),
        (SAMPLE_MAIN.replace("\\\\ word", "\\q word"), SAMPLE_PART.into(), "bad escape"),
        (SAMPLE_MAIN.replace("\"a \"\"quoted\"\" \\\\ word\\0A\"", "\"a \"quoted\" word\""), SAMPLE_PART.into(), "expected ';'"),
        (
            SAMPLE_MAIN.replace("    PROC main", "    LOCAL CONST robtarget P1 := [[0,0,0],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n    PROC main"),
            SAMPLE_PART.into(),
            "declared twice",
        ),
        (SAMPLE_MAIN.replace("MODULE Sample\n", "MODULE Other\n"), SAMPLE_PART.into(), "is in file Sample.mod"),
        (SAMPLE_MAIN.replace("p1 :=", "_p1 :=").replace("MoveL p1", "MoveL _p1"), SAMPLE_PART.into(), "unexpected character '_'"),
        (SAMPLE_MAIN.replace("MoveL p1", "MoveL 1p"), SAMPLE_PART.into(), "runs into"),
        (SAMPLE_MAIN.replace("TPWrite s;", "TPWrite s; # x"), SAMPLE_PART.into(), "unexpected character '#'"),
        (format!("{SAMPLE_MAIN}MoveL p1;\n"), SAMPLE_PART.into(), "text after ENDMODULE"),
        (SAMPLE_MAIN.into(), SAMPLE_PART.replace("SetDO doWeld", "SetDO doBlast"), "doBlast is used before"),
        (SAMPLE_MAIN.replace("robtarget p1", "robtargot p1"), SAMPLE_PART.into(), "unknown data type"),
        (SAMPLE_MAIN.replace("PROC main()", "PROC main()\n        p1 := p1;"), SAMPLE_PART.into(), "neither an instruction"),
        (SAMPLE_MAIN.replace("Part2;", "main;"), SAMPLE_PART.replace("PROC Part2", "PROC main"), "PROC main defined twice"),
    ];
    for (main, part, want) in &cases {
        assert_ne!(
            (main.as_str(), part.as_str()),
            (SAMPLE_MAIN, SAMPLE_PART),
            "mutation for {want:?} changed nothing"
        );
        match check_sample(main, part) {
            Ok(_) => panic!("accepted a broken program ({want}):\n{main}{part}"),
            Err(e) => assert!(e.contains(want), "{want:?} not in {e:?}"),
        }
    }
    // Declarations before use, across modules: the part first uses tA before the main module
    // declares it.
    let e = check_program(
        &[("Sample_2.mod", SAMPLE_PART), ("Sample.mod", SAMPLE_MAIN)],
        &["doWeld"],
    )
    .unwrap_err();
    assert!(e.contains("tA is used before it is declared"), "{e}");
}

#[test]
fn pgf_checker_rejects_broken_files() {
    let good = "<?xml version=\"1.0\" encoding=\"UTF-8\" ?>\n<Program>\n    <Module>a.modx</Module>\n</Program>\n";
    assert_eq!(check_pgf(good, "UTF-8").unwrap(), ["a.modx"]);
    assert!(check_pgf(good, "ISO-8859-1").is_err());
    assert!(check_pgf(&good.replace("</Program>\n", ""), "UTF-8").is_err());
    assert!(check_pgf(&good.replace("a.modx", "a<b.modx"), "UTF-8").is_err());
    assert!(check_pgf(&format!("{good}<Module>x</Module>\n"), "UTF-8").is_err());
}
