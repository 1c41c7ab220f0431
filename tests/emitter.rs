//! The emitter end to end: the `emitter` node in process (Toolpath topic in, MachineProgram
//! topic out, the `emit_program` service, bad input refused while the node keeps running, the
//! planner → emitter chain), and the one-shot `cell emit` and `cell hotwire --profile`
//! commands (files written, errors naming the profile or the segment and point, nothing
//! written on error).

mod common;

use std::process::{Command, Output};

use cell_msgs::{
    geometry_msgs::Point, EmitProgramRequest, EmitProgramResponse, MachineProgram,
    PlanHotwireFeedback, PlanHotwireGoal, PlanHotwireResult, Toolpath, ToolpathSegment,
};
use cell_profiles::MachineProfile;
use cell_runtime::QosPreset;
use common::{discover_action_server, follow_goal, fresh_domain, node, within, DELIVERY_TIMEOUT};
use emitter::{run, EmitterParams};

/// A closed 100 × 70 mm rectangle cut inside grbl-xy's travel, with a lead-in.
fn rectangle(job_id: &str) -> Toolpath {
    let p = |x: f64, y: f64| Point { x, y, z: 0.0 };
    let cut = [
        p(50.0, 50.0),
        p(150.0, 50.0),
        p(150.0, 120.0),
        p(50.0, 120.0),
        p(50.0, 50.0),
    ];
    let segment = |kind, points: Vec<Point>| ToolpathSegment {
        kind,
        feed_mm_s: vec![8.0; points.len()],
        power: vec![2.5; points.len()],
        points,
        ..Default::default()
    };
    Toolpath {
        job_id: job_id.into(),
        process: Toolpath::PROCESS_HOTWIRE,
        power_unit: Toolpath::POWER_WIRE_CURRENT_A,
        segments: vec![
            segment(
                ToolpathSegment::KIND_LEAD,
                vec![p(40.0, 50.0), p(50.0, 50.0)],
            ),
            segment(ToolpathSegment::KIND_CUT, cut.to_vec()),
        ],
        ..Default::default()
    }
}

/// The rectangle with a NaN at segment 1, point 2.
fn with_nan(job_id: &str) -> Toolpath {
    let mut t = rectangle(job_id);
    t.segments[1].points[2].x = f64::NAN;
    t
}

fn sha256_hex(text: &str) -> String {
    use sha2::Digest as _;
    sha2::Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// A program's invariants: line count and checksum match its text.
fn assert_consistent(program: &MachineProgram) {
    let text: String = program.files.iter().map(|f| f.text.as_str()).collect();
    assert_eq!(program.line_count as usize, text.lines().count());
    assert_eq!(program.sha256, sha256_hex(&text));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn emitter_node_publishes_programs_serves_requests_and_survives_bad_input() {
    let domain = fresh_domain();
    let emitter_node = node("emitter", domain, false);
    let client_node = node("operator", domain, false);
    let out = tempfile::tempdir().unwrap();
    let params = EmitterParams {
        machine_profile: "grbl-xy".into(),
        output_dir: out.path().display().to_string(),
        ..EmitterParams::default()
    };
    let emitter = tokio::spawn(run(emitter_node, params));

    let toolpaths = client_node
        .publisher::<Toolpath>("/toolpath", QosPreset::Plan)
        .unwrap();
    let mut programs = client_node
        .subscriber::<MachineProgram>("/machine_program", QosPreset::Plan)
        .unwrap();
    let client = client_node
        .service_client::<EmitProgramRequest, EmitProgramResponse>("/emit_program")
        .unwrap();
    assert!(
        client_node
            .wait_for_service("/emit_program", DELIVERY_TIMEOUT)
            .await,
        "emitter service never discovered"
    );
    assert!(toolpaths.wait_for_subscribers(1, DELIVERY_TIMEOUT).await);

    // A bad toolpath on the topic: refused, nothing published; then a good one.
    toolpaths.publish(with_nan("topic-bad")).await.unwrap();
    toolpaths.publish(rectangle("topic-1")).await.unwrap();
    let program = within(programs.recv())
        .await
        .expect("program topic")
        .message;
    assert_eq!(program.job_id, "topic-1", "the bad toolpath was published");
    assert_eq!(
        (program.dialect.as_str(), program.machine_profile.as_str()),
        ("grbl", "grbl-xy")
    );
    assert_eq!(program.files.len(), 1);
    assert_eq!(program.files[0].name, "topic-1.ngc");
    assert_consistent(&program);
    let expected = cell_emitter::emit_program(
        &rectangle("topic-1"),
        &MachineProfile::resolve("grbl-xy").unwrap(),
        "topic-1",
    )
    .unwrap();
    assert_eq!(program.files, expected.files);
    // output_dir: the published program's file, written atomically (no temporaries left).
    let written = out.path().join("topic-1.ngc");
    assert_eq!(
        std::fs::read_to_string(&written).unwrap(),
        program.files[0].text
    );
    assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 1);

    let call = |request: EmitProgramRequest| client.call(request, DELIVERY_TIMEOUT);

    // A NaN through the service: refused with the segment and point, nothing published.
    let bad = call(EmitProgramRequest {
        toolpath: with_nan("svc-bad"),
        publish: true,
        ..Default::default()
    })
    .await
    .expect("bad request answered");
    assert!(!bad.success);
    assert!(
        bad.message.contains("segment 1 point 2") && bad.message.contains("not finite"),
        "{}",
        bad.message
    );
    assert_eq!(bad.program, MachineProgram::default());

    // An unknown profile: refused, naming it.
    let unknown = call(EmitProgramRequest {
        toolpath: rectangle("svc-unknown"),
        machine_profile: "mill_9000".into(),
        publish: true,
        ..Default::default()
    })
    .await
    .expect("answered");
    assert!(
        !unknown.success && unknown.message.contains("mill_9000"),
        "{}",
        unknown.message
    );

    // Outside the machine's travel: refused.
    let mut far = rectangle("svc-far");
    far.segments[1].points[1].x = 900.0;
    let far = call(EmitProgramRequest {
        toolpath: far,
        publish: true,
        ..Default::default()
    })
    .await
    .expect("answered");
    assert!(
        !far.success && far.message.contains("segment 1 point 1"),
        "{}",
        far.message
    );

    // A good request after the bad ones: answered, with another profile and job id, and
    // published because it asks to be.
    let good = call(EmitProgramRequest {
        toolpath: rectangle("ignored"),
        machine_profile: "linuxcnc-xyuv".into(),
        job_id: "svc-1".into(),
        publish: true,
    })
    .await
    .expect("good request answered");
    assert!(good.success, "{}", good.message);
    assert_eq!(good.program.job_id, "svc-1");
    assert_eq!(good.program.dialect, "linuxcnc");
    assert!(
        good.message.contains(&good.program.sha256),
        "{}",
        good.message
    );
    assert_consistent(&good.program);
    let published = within(programs.recv())
        .await
        .expect("program topic")
        .message;
    assert_eq!(published.job_id, "svc-1", "a refused request was published");
    assert_eq!(published.files, good.program.files);

    // Without `publish`: answered only.
    let quiet = call(EmitProgramRequest {
        toolpath: rectangle("svc-quiet"),
        ..Default::default()
    })
    .await
    .expect("answered");
    assert!(quiet.success && quiet.program.job_id == "svc-quiet");
    toolpaths.publish(rectangle("topic-2")).await.unwrap();
    let next = within(programs.recv())
        .await
        .expect("program topic")
        .message;
    assert_eq!(
        next.job_id, "topic-2",
        "an unpublished request was published"
    );

    assert!(!emitter.is_finished(), "the emitter node must stay up");
    emitter.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn planner_and_emitter_turn_a_goal_into_a_program() {
    let domain = fresh_domain();
    let planner_node = node("planner", domain, false);
    let emitter_node = node("emitter", domain, false);
    let client_node = node("operator", domain, false);
    let planner = tokio::spawn(planner::run(
        planner_node,
        planner::PlannerParams {
            panels: 40,
            particles: 6,
            feedback_every: 5,
            ..Default::default()
        },
    ));
    let emitter = tokio::spawn(run(emitter_node, EmitterParams::default()));
    let mut programs = client_node
        .subscriber::<MachineProgram>("/machine_program", QosPreset::Plan)
        .unwrap();
    let client = client_node
        .action_client::<PlanHotwireGoal, PlanHotwireResult, PlanHotwireFeedback>("/plan_hotwire")
        .unwrap();
    discover_action_server(&client_node, "/plan_hotwire").await;
    let goal = PlanHotwireGoal {
        job_id: "wing-7".into(),
        root_airfoil: "s1223".into(),
        root_chord_mm: 150.0,
        iterations: 10,
        seed: 1,
        ..Default::default()
    };
    let followed = follow_goal(&client, goal).await.expect("accepted");
    assert!(followed.result.success, "{}", followed.result.message);
    let program = within(programs.recv())
        .await
        .expect("program topic")
        .message;
    assert_eq!(program.job_id, "wing-7");
    assert_eq!(
        (program.dialect.as_str(), program.machine_profile.as_str()),
        ("linuxcnc", "linuxcnc-xyuv")
    );
    assert_consistent(&program);
    let expected = cell_emitter::emit_program(
        &followed.result.toolpath,
        &MachineProfile::resolve("linuxcnc-xyuv").unwrap(),
        "wing-7",
    )
    .unwrap();
    assert_eq!(program.files, expected.files);
    planner.abort();
    emitter.abort();
}

const CELL: &str = env!("CARGO_BIN_EXE_cell");

fn cell(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(CELL)
        .args(args)
        .env_remove("RUST_LOG")
        .output()
        .expect("run cell")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The one `error:` line of a failed run, after checking there is no panic.
fn error_line(out: &Output) -> String {
    let text = stderr(out);
    assert!(!text.contains("panicked"), "{text}");
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1, "one line: {text}");
    assert!(lines[0].starts_with("error: "), "{text}");
    lines[0].to_owned()
}

fn write_json(path: &std::path::Path, toolpath: &Toolpath) {
    std::fs::write(path, serde_json::to_string_pretty(toolpath).unwrap()).unwrap();
}

#[test]
fn cell_emit_writes_the_program_and_refuses_bad_input_without_writing() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.json");
    write_json(&good, &rectangle("rect-1"));
    let out = dir.path().join("rect.ngc");
    let emit = |toolpath: &std::path::Path, profile: &str, out: &std::path::Path| {
        cell(&[
            "emit".as_ref(),
            "--toolpath".as_ref(),
            toolpath.as_os_str(),
            "--profile".as_ref(),
            profile.as_ref(),
            "--out".as_ref(),
            out.as_os_str(),
        ])
    };

    let run = emit(&good, "grbl-xy", &out);
    assert!(run.status.success(), "{}", stderr(&run));
    let expected = cell_emitter::emit_program(
        &rectangle("rect-1"),
        &MachineProfile::resolve("grbl-xy").unwrap(),
        "rect-1",
    )
    .unwrap();
    let text = std::fs::read_to_string(&out).unwrap();
    assert_eq!(text, expected.files[0].text);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    for needle in [
        "profile grbl-xy",
        "dialect grbl",
        &format!("{} lines", text.lines().count()),
        &format!("sha256 {}", sha256_hex(&text)),
        "rect.ngc",
    ] {
        assert!(stdout.contains(needle), "{needle:?} not in {stdout}");
    }

    // --out DIR/: the file under its own name.
    let into = dir.path().join("programs");
    let run = emit(&good, "linuxcnc-xyuv", &into.join(""));
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(std::fs::read_to_string(into.join("rect-1.ngc"))
        .unwrap()
        .contains("G93"));

    // An unknown profile: a usage error naming it, nothing written.
    let fresh = dir.path().join("fresh.ngc");
    let run = emit(&good, "mill_9000", &fresh);
    assert_eq!(run.status.code(), Some(64), "{}", stderr(&run));
    let line = error_line(&run);
    assert!(
        line.contains("--profile") && line.contains("mill_9000"),
        "{line}"
    );
    assert!(!fresh.exists());

    // A NaN (JSON null): refused naming the segment and point; no file created, an existing
    // one left as it was, no temporaries.
    let bad = dir.path().join("bad.json");
    write_json(&bad, &with_nan("rect-bad"));
    let run = emit(&bad, "grbl-xy", &fresh);
    assert_eq!(run.status.code(), Some(65), "{}", stderr(&run));
    let line = error_line(&run);
    assert!(
        line.contains("bad.json") && line.contains("segment 1 point 2: x is not finite"),
        "{line}"
    );
    assert!(!fresh.exists(), "no output file for a refused toolpath");
    let run = emit(&bad, "grbl-xy", &out);
    assert_eq!(run.status.code(), Some(65));
    assert_eq!(std::fs::read_to_string(&out).unwrap(), text, "untouched");
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");

    // Not a toolpath: the field path; not JSON: the line.
    let wrong = dir.path().join("wrong.json");
    let mut value = serde_json::to_value(rectangle("x")).unwrap();
    value["segments"][0]["feed_mm_s"] = serde_json::json!("fast");
    std::fs::write(&wrong, value.to_string()).unwrap();
    let run = emit(&wrong, "grbl-xy", &fresh);
    assert_eq!(run.status.code(), Some(65));
    assert!(error_line(&run).contains("segments[0].feed_mm_s"));
    std::fs::write(&wrong, "{\n\"job_id\": 1,,\n}").unwrap();
    let run = emit(&wrong, "grbl-xy", &fresh);
    assert_eq!(run.status.code(), Some(65));
    assert!(error_line(&run).contains("line 2"));
    let run = emit(&dir.path().join("missing.json"), "grbl-xy", &fresh);
    assert_eq!(run.status.code(), Some(64));
    assert!(error_line(&run).contains("missing.json"));
    assert!(!fresh.exists());
}

#[test]
fn cell_emit_writes_every_file_of_a_rapid_program_under_its_name() {
    let dir = tempfile::tempdir().unwrap();
    let p = |x: f64| Point {
        x,
        y: 100.0,
        z: 10.0,
    };
    let wall = Toolpath {
        job_id: "wall".into(),
        process: Toolpath::PROCESS_WAAM,
        // The wire feed the program's welddata take (m/min).
        power_unit: Toolpath::POWER_WIRE_FEED_M_MIN,
        segments: vec![ToolpathSegment {
            kind: ToolpathSegment::KIND_DEPOSIT,
            points: vec![p(100.0), p(150.0), p(200.0)],
            feed_mm_s: vec![8.0; 3],
            power: vec![5.53; 3],
            ..Default::default()
        }],
        ..Default::default()
    };
    let json = dir.path().join("wall.json");
    write_json(&json, &wall);
    let expected = cell_emitter::emit_program(
        &wall,
        &MachineProfile::resolve("abb-irb2600-waam").unwrap(),
        "wall",
    )
    .unwrap();
    let names: Vec<&str> = expected.files.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["WAAM_wall.mod", "WAAM_wall.pgf"]);
    let emit = |out: &std::path::Path| {
        cell(&[
            "emit".as_ref(),
            "--toolpath".as_ref(),
            json.as_os_str(),
            "--profile".as_ref(),
            "abb-irb2600-waam".as_ref(),
            "--out".as_ref(),
            out.as_os_str(),
        ])
    };

    // Renaming the main module would break the .pgf that lists it: refused, nothing written.
    let out = dir.path().join("robot");
    let run = emit(&out.join("wall.mod"));
    assert_eq!(run.status.code(), Some(64), "{}", stderr(&run));
    let line = error_line(&run);
    assert!(
        line.contains("WAAM_wall.mod") && line.contains("DIR/"),
        "{line}"
    );
    assert!(!out.exists());

    // A directory, or the main module's own name: every file under its own name.
    for target in [out.join(""), out.join("WAAM_wall.mod")] {
        let run = emit(&target);
        assert!(run.status.success(), "{}", stderr(&run));
        for f in &expected.files {
            assert_eq!(std::fs::read_to_string(out.join(&f.name)).unwrap(), f.text);
        }
        assert!(String::from_utf8_lossy(&run.stdout).contains("dialect rapid"));
    }
}

#[test]
fn cell_hotwire_with_a_profile_writes_the_program_and_the_toolpath() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let args = |profile: &str| {
        let mut a: Vec<std::ffi::OsString> = [
            "hotwire",
            "--airfoil",
            "s1223",
            "--chord",
            "150",
            "--panels",
            "40",
            "--iterations",
            "10",
            "--particles",
            "6",
            "--profile",
            profile,
            "--out",
        ]
        .iter()
        .map(Into::into)
        .collect();
        a.push(out.clone().into());
        a
    };
    let run =
        |a: Vec<std::ffi::OsString>| cell(&a.iter().map(|s| s.as_os_str()).collect::<Vec<_>>());

    // --profile alone: planned on grbl-xy (2-axis) and emitted for it.
    let hotwire = run(args("grbl-xy"));
    assert!(hotwire.status.success(), "{}", stderr(&hotwire));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["machine"], "grbl-xy");
    let program = std::fs::read_to_string(out.join("program.ngc")).unwrap();
    assert!(program.contains("profile grbl-xy"), "{program}");
    let stdout = String::from_utf8_lossy(&hotwire.stdout);
    assert!(
        stdout.contains(&format!("sha256 {}", sha256_hex(&program))),
        "{stdout}"
    );

    // toolpath.json is what `cell emit` takes, and gives the same program.
    let toolpath: Toolpath =
        cell_msgs::json::from_str(&std::fs::read_to_string(out.join("toolpath.json")).unwrap())
            .unwrap();
    assert_eq!(toolpath.job_id, "hotwire-s1223");
    let again = dir.path().join("again.ngc");
    let emit = cell(&[
        "emit".as_ref(),
        "--toolpath".as_ref(),
        out.join("toolpath.json").as_os_str(),
        "--profile".as_ref(),
        "grbl-xy".as_ref(),
        "--out".as_ref(),
        again.as_os_str(),
    ]);
    assert!(emit.status.success(), "{}", stderr(&emit));
    assert_eq!(std::fs::read_to_string(&again).unwrap(), program);

    // The example: a 4-axis GRBL cutter plans and emits in inverse-time feeds.
    let hotwire = run(args("grbl-xyuv"));
    assert!(hotwire.status.success(), "{}", stderr(&hotwire));
    let program = std::fs::read_to_string(out.join("program.ngc")).unwrap();
    assert!(
        program.contains("profile grbl-xyuv") && program.contains("G93"),
        "{program}"
    );
    assert!(program
        .lines()
        .any(|l| l.contains(" U") && l.contains(" V")));

    // A profile that is not known: refused before planning.
    let run_bad = run(args("mill_9000"));
    assert_eq!(run_bad.status.code(), Some(64));
    let line = error_line(&run_bad);
    assert!(
        line.starts_with("error: --profile") && line.contains("mill_9000"),
        "{line}"
    );
}

#[test]
fn cell_node_emitter_takes_its_params_file_and_refuses_an_unknown_profile() {
    let params = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("config/emitter.yaml");
    let run = Command::new(CELL)
        .args(["node", "emitter", "--dds-network", "loopback", "--ros-args"])
        .arg("--params-file")
        .arg(&params)
        .args(["-p", "machine_profile:=mill_9000"])
        .env("ROS_DOMAIN_ID", fresh_domain().to_string())
        .env_remove("RUST_LOG")
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(64), "{}", stderr(&run));
    let line = error_line(&run);
    assert!(
        line.contains("machine_profile") && line.contains("mill_9000"),
        "{line}"
    );
}
