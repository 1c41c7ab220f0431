//! The controllers without ROS: `GrblController` against the GRBL simulator over loopback TCP
//! with the emitter's programs.

use std::time::Duration;

use cell_bridge::config::ControllerSpec;
use cell_bridge::controller::Controller;
use cell_grbl::program::{CleanOptions, Program};
use cell_grbl::sim::{self, Faults, SimConfig, SimHandle};
use cell_msgs::{ExecuteProgramResult as R, MachineProgram};

fn emitted(profile: &str, toolpath: &str, job: &str) -> MachineProgram {
    let text = std::fs::read_to_string(format!(
        "{}/../../tests/data/toolpaths/{toolpath}.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let tp = cell_msgs::json::from_str(&text).unwrap();
    let profile = cell_profiles::MachineProfile::resolve(profile).unwrap();
    cell_emitter::emit_program(&tp, &profile, job).unwrap()
}

async fn grbl(faults: Faults, extra: &str) -> (SimHandle, Controller, tempfile::TempDir) {
    let sim = sim::start(SimConfig {
        time_scale: 20.0,
        axes: vec!['X', 'Y', 'U', 'V'],
        faults,
        ..SimConfig::default()
    });
    let addr = sim.listen_tcp("127.0.0.1:0").await.unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.yaml");
    std::fs::write(
        &path,
        format!(
            "id: c\nprotocol: grbl\nmachine_profile: grbl-xyuv\naxes: XYUV\nendpoint: {{tcp: '{addr}'}}\n{extra}"
        ),
    )
    .unwrap();
    let spec = ControllerSpec::load(&path).unwrap();
    let c = Controller::start(spec).await.unwrap();
    let Controller::Grbl(g) = &c else { panic!() };
    assert!(g.wait_connected(Duration::from_secs(30)).await);
    (sim, c, dir)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_emitted_panel_runs_line_for_line() {
    let (sim, c, _dir) = grbl(Faults::default(), "").await;
    let program = emitted("grbl-xyuv", "wing", "wing");
    let out = tokio::time::timeout(Duration::from_secs(120), c.execute(&program, 0))
        .await
        .expect("finishes");
    assert!(out.success, "{}", out.message);
    let sent = Program::parse(&program.files[0].text, CleanOptions::default()).unwrap();
    let texts: Vec<String> = sent.lines().iter().map(|l| l.text.clone()).collect();
    assert_eq!(sim.executed_lines(), texts);
    assert_eq!(out.outcome, R::OUTCOME_FINISHED);
}

/// What the `machine_bridge` node rejects a goal for, before it is accepted: each reason names
/// the dialect, the controller or the line, and nothing reaches the machine.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_program_a_controller_cannot_take_is_named_before_anything_is_sent() {
    let (sim, c, _dir) = grbl(Faults::default(), "").await;
    let program = emitted("grbl-xyuv", "wing", "wing");
    assert_eq!(c.check_program(&program, 0), Ok(()));
    let linuxcnc = emitted("linuxcnc-xyuv", "wing", "wrong-dialect");
    let why = c.check_program(&linuxcnc, 0).unwrap_err();
    assert!(why.contains("\"linuxcnc\""), "{why}");
    let why = c.check_program(&program, 1_000_000).unwrap_err();
    assert!(why.contains("start_line 1000000"), "{why}");
    let controllers = [c];
    let why = cell_bridge::controller::choose(&controllers, 0, "lathe", &program).unwrap_err();
    assert!(
        why.contains("\"lathe\"") && why.contains("(it has c)"),
        "{why}"
    );

    let robot = Controller::start(ControllerSpec::resolve("abb-irb2600-waam-sim").unwrap())
        .await
        .unwrap();
    let why = robot.check_program(&program, 0).unwrap_err();
    assert!(why.contains("RAPID"), "{why}");
    assert_eq!(
        robot.check_program(&emitted("abb-irb2600-waam", "wall", "wall"), 0),
        Ok(())
    );
    assert!(sim.executed_lines().is_empty(), "nothing was sent");
}

/// A program line that is a controller command (`$RST=*` wipes GRBL's settings, `$N0=…` stores
/// a start-up block) is refused before anything is sent, naming the file, line and text; a
/// command the controller file allows (`$H`) passes, and the file's list holds only controller
/// commands.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn controller_commands_in_a_program_are_refused_before_anything_is_sent() {
    let (sim, c, _dir) = grbl(Faults::default(), "").await;
    let mut program = emitted("grbl-xyuv", "wing", "wing");
    let mut lines: Vec<&str> = program.files[0].text.lines().collect();
    lines.insert(3, "$RST=*");
    program.files[0].text = lines.join("\n");
    let why = c.check_program(&program, 0).unwrap_err();
    let file = &program.files[0].name;
    assert!(
        why.starts_with(&format!("{file}: line 4: `$RST=*` is a controller command")),
        "{why}"
    );
    let out = c.execute(&program, 0).await;
    assert!(
        !out.success && out.message.contains("`$RST=*`"),
        "{}",
        out.message
    );
    assert!(sim.executed_lines().is_empty(), "nothing was sent");

    let (_sim, homing, _dir) = grbl(Faults::default(), "allowed_commands: ['$H']\n").await;
    let mut homed = emitted("grbl-xyuv", "wing", "wing");
    homed.files[0].text = format!("$H\n{}", homed.files[0].text);
    assert_eq!(homing.check_program(&homed, 0), Ok(()));
    let mut startup = homed.clone();
    startup.files[0].text = format!("$N0=M3S1000\n{}", startup.files[0].text);
    let why = homing.check_program(&startup, 0).unwrap_err();
    assert!(why.contains("line 1: `$N0=M3S1000`"), "{why}");

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.yaml");
    std::fs::write(
        &path,
        "id: c\nprotocol: grbl\nendpoint: {tcp: '127.0.0.1:1'}\nallowed_commands: [G28]\n",
    )
    .unwrap();
    let err = ControllerSpec::load(&path).unwrap_err().to_string();
    assert!(
        err.contains("bad.yaml") && err.contains("allowed_commands") && err.contains("\"G28\""),
        "{err}"
    );
}

/// An operator's resume after an abort: the controller, reset by the safe stop, gets the
/// program's state back before the resumed line (the G93 feed mode and the wire heated as the
/// program heated it, at the line's start point), and every line runs once. A start line whose
/// state cannot be restored is refused before anything is sent, naming the line.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_operator_resume_restores_the_programs_state_before_the_resumed_line() {
    use cell_grbl::protocol::MachineState;
    use cell_msgs::MachineCommand;

    let (sim, c, _dir) = grbl(Faults::default(), "").await;
    let program = emitted("grbl-xyuv", "wing", "wing");
    let sent = Program::parse(&program.files[0].text, CleanOptions::default()).unwrap();
    let texts: Vec<String> = sent.lines().iter().map(|l| l.text.clone()).collect();
    let run = {
        let (c, program) = (c.clone(), program.clone());
        tokio::spawn(async move { c.execute(&program, 0).await })
    };
    sim.wait_for(Duration::from_secs(120), |s| {
        s.state == MachineState::Run && s.spindle_on && s.executed > texts.len() / 3
    })
    .await
    .expect("the cut runs");
    let abort = MachineCommand {
        command: MachineCommand::COMMAND_ABORT,
        ..MachineCommand::default()
    };
    c.command(&abort).await.unwrap();
    let out = run.await.unwrap();
    assert_eq!(out.outcome, R::OUTCOME_ABORTED, "{}", out.message);
    let stopped = sim.executed_lines();
    let done = stopped.len() - 1;
    assert_eq!(stopped[..done], texts[..done], "the lines before the stop");
    assert_eq!(stopped[done], "M5", "the safe stop's M5");
    let reset = sim.parser_state();
    assert_eq!(
        (reset.feed_mode.as_str(), reset.spindle.as_str()),
        ("G94", "M5")
    );

    let from = sent.lines()[done].number;
    let out = tokio::time::timeout(Duration::from_secs(120), c.execute(&program, from as u32))
        .await
        .expect("finishes");
    assert!(out.success, "{}", out.message);
    let preamble = cell_grbl::resume::preamble(&sent, from).unwrap();
    let heat_on = texts.iter().find(|t| t.starts_with("M3 S")).unwrap();
    assert!(preamble.contains(heat_on), "{preamble:?}");
    let log = sim.executed();
    let expected: Vec<String> = texts[..done]
        .iter()
        .cloned()
        .chain(["M5".to_string()])
        .chain(preamble.iter().cloned())
        .chain(texts[done..].iter().cloned())
        .collect();
    let got: Vec<String> = log.iter().map(|l| l.text.clone()).collect();
    assert_eq!(
        got, expected,
        "the preamble before the resumed line; every line once"
    );
    // The resumed line runs in the state of the line before it in the first run.
    let before = &log[done - 1].parser;
    let resumed = &log[done + 1 + preamble.len()].parser;
    let groups = |s: &cell_grbl::sim::ParserState| {
        [
            s.coordinate_system.clone(),
            s.plane.clone(),
            s.units.clone(),
            s.distance.clone(),
            s.feed_mode.clone(),
            s.spindle.clone(),
            s.spindle_speed.clone(),
        ]
    };
    assert_eq!(groups(resumed), groups(before));
    assert_eq!(
        (resumed.feed_mode.as_str(), resumed.spindle.as_str()),
        ("G93", "M3")
    );

    // An abort while the state is being restored ends the run there: the safe stop, and no
    // program line.
    let before_abort = sim.executed().len();
    let run = {
        let (c, program) = (c.clone(), program.clone());
        tokio::spawn(async move { c.execute(&program, from as u32).await })
    };
    sim.wait_for(Duration::from_secs(120), |s| {
        s.spindle_on && s.executed > before_abort
    })
    .await
    .expect("the preamble switches the heat on");
    c.command(&abort).await.unwrap();
    let out = tokio::time::timeout(Duration::from_secs(120), run)
        .await
        .expect("the run ends")
        .unwrap();
    assert_eq!(out.outcome, R::OUTCOME_ABORTED, "{}", out.message);
    let after: Vec<String> = sim.executed_lines().split_off(before_abort);
    assert!(
        after.iter().all(|l| preamble.contains(l) || l == "M5"),
        "{after:?}"
    );
    assert_eq!(sim.parser_state().spindle, "M5");
    assert!(!sim.snapshot().spindle_on);

    // A state the resume cannot rebuild: a tool length offset before the start line.
    let mut offset = program.clone();
    let mut lines: Vec<&str> = offset.files[0].text.lines().collect();
    lines.insert(3, "G43.1 Z1");
    offset.files[0].text = lines.join("\n");
    let why = c.check_program(&offset, 10).unwrap_err();
    assert!(
        why.starts_with(&format!(
            "{}: cannot resume from line 10: line 4 (`G43.1 Z1`): G43.1",
            offset.files[0].name
        )),
        "{why}"
    );
    let executed = sim.executed().len();
    let out = c.execute(&offset, 10).await;
    assert_eq!(out.outcome, R::OUTCOME_REFUSED, "{}", out.message);
    assert_eq!(sim.executed().len(), executed, "nothing was sent");
}
