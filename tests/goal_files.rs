//! Files named in goals and requests (issue 23, item 3): real `emitter` and `slicer` processes
//! on a real DDS domain, a client in this process. Paths to `/etc/passwd`, `/dev/zero`, a FIFO
//! in a data directory, a symlink leading out of it and a file over the size cap are refused
//! at once with the reason; a file inside that does not parse is named without its contents;
//! no answer (nor the node's log) holds a line of `/etc/passwd`; the nodes keep serving good
//! goals. The rules themselves: `cell_runtime::data_files`.

mod common;

use std::{
    path::{Path, PathBuf},
    process::Command,
    time::{Duration, Instant},
};

use cell_msgs::{EmitProgramRequest, EmitProgramResponse, SliceFeedback, SliceGoal, SliceResult};
use cell_runtime::action::{ActionClient, GoalStatusEnum};
use common::node_process::NodeProcess;
use common::{discover_action_server, fresh_domain, node, rectangle_cut, within, DELIVERY_TIMEOUT};

/// A refusal must come back well before a hung read would be noticed.
const QUICK: Duration = Duration::from_secs(10);

/// `cell node <name>` on `domain` with `params`, on loopback, logging at info.
fn start_node(name: &str, domain: u16, params: &Path) -> NodeProcess {
    let mut command = Command::new(env!("CARGO_BIN_EXE_cell"));
    command
        .args(["node", name, "--ros-args", "--params-file"])
        .arg(params)
        .env("CELL_DDS_NETWORK", "loopback")
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env("RUST_LOG", "info");
    NodeProcess::spawn(name, command)
}

/// The lines of `/etc/passwd` (the secret the answers must not hold).
fn passwd_lines() -> Vec<String> {
    std::fs::read_to_string("/etc/passwd")
        .unwrap()
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(str::to_owned)
        .collect()
}

/// Fails if `text` holds `root:` or any line (or the first field of a line, `name:x`) of
/// `/etc/passwd`.
fn assert_no_passwd(text: &str, what: &str) {
    assert!(!text.contains("root:"), "{what} quotes /etc/passwd: {text}");
    for line in passwd_lines() {
        assert!(!text.contains(&line), "{what} quotes {line:?}: {text}");
        let head: String = line.split(':').take(2).collect::<Vec<_>>().join(":");
        assert!(!text.contains(&head), "{what} quotes {head:?}: {text}");
    }
}

/// The data directory of the tests: good files, a FIFO, links leading out, a big file and a
/// copy of `/etc/passwd` under names the nodes would read.
struct DataDir {
    _root: tempfile::TempDir,
    dir: PathBuf,
    params: PathBuf,
}

fn data_dir() -> DataDir {
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("data");
    std::fs::create_dir(&dir).unwrap();
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::copy(
        repo.join("config/machines/grbl-xy.yaml"),
        dir.join("my-grbl.yaml"),
    )
    .unwrap();
    std::fs::copy(
        repo.join("tests/data/stl/20mm-xyz-cube.stl"),
        dir.join("cube.stl"),
    )
    .unwrap();
    std::fs::copy("/etc/passwd", dir.join("passwd.yaml")).unwrap();
    std::fs::copy("/etc/passwd", dir.join("passwd.stl")).unwrap();
    std::fs::write(root.path().join("outside.yaml"), "name: outside\n").unwrap();
    std::os::unix::fs::symlink("/etc/passwd", dir.join("escape.yaml")).unwrap();
    std::os::unix::fs::symlink(root.path().join("outside.yaml"), dir.join("up.yaml")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.stl")).unwrap();
    // Over the 1 MiB cap the nodes get.
    std::fs::write(dir.join("big.yaml"), vec![b'#'; 2 << 20]).unwrap();
    std::fs::write(dir.join("big.stl"), vec![0u8; 2 << 20]).unwrap();
    for fifo in ["pipe.yaml", "pipe.stl"] {
        let made = Command::new("mkfifo")
            .arg(dir.join(fifo))
            .status()
            .expect("mkfifo");
        assert!(made.success());
    }
    let params = root.path().join("params.yaml");
    std::fs::write(
        &params,
        format!(
            "/**:\n  ros__parameters:\n    data_dirs: ['{}']\n    max_file_mib: 1\n",
            dir.display()
        ),
    )
    .unwrap();
    DataDir {
        _root: root,
        dir,
        params,
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn emit_program_refuses_host_paths_without_quoting_them_and_keeps_serving() {
    let domain = fresh_domain();
    let data = data_dir();
    let mut emitter = start_node("emitter", domain, &data.params);
    let client_node = node("operator", domain, false);
    let service = client_node
        .service_client::<EmitProgramRequest, EmitProgramResponse>("/emit_program")
        .unwrap();
    assert!(
        client_node
            .wait_for_service("/emit_program", DELIVERY_TIMEOUT)
            .await,
        "emit_program never discovered:\n{}",
        emitter.log()
    );
    let emit = |machine_profile: String| {
        let service = &service;
        async move {
            let started = Instant::now();
            let answer = service
                .call(
                    EmitProgramRequest {
                        toolpath: rectangle_cut("rect"),
                        machine_profile,
                        job_id: "files".into(),
                        publish: false,
                    },
                    DELIVERY_TIMEOUT,
                )
                .await
                .expect("the emitter answers");
            (answer, started.elapsed())
        }
    };

    let fifo = data.dir.join("pipe.yaml").display().to_string();
    let refusals = [
        (
            "/etc/passwd".to_string(),
            "outside the node's data directories",
        ),
        ("/dev/zero".into(), "outside the node's data directories"),
        (
            "/etc/../etc/passwd".into(),
            "outside the node's data directories",
        ),
        ("escape.yaml".into(), "outside the node's data directories"),
        ("up.yaml".into(), "outside the node's data directories"),
        (fifo, "not a regular file (a FIFO)"),
        ("pipe.yaml".into(), "not a regular file (a FIFO)"),
        (
            "big.yaml".into(),
            "larger than the node's 1048576-byte limit",
        ),
        // Inside and read, but not a profile: the place, not the contents.
        ("passwd.yaml".into(), "machine_profile: passwd.yaml:"),
    ];
    for (profile, reason) in refusals {
        let (answer, took) = emit(profile.clone()).await;
        assert!(!answer.success, "{profile}: {}", answer.message);
        assert!(
            answer.message.contains(reason) && answer.message.contains(&profile),
            "{profile}: expected {reason:?} in {:?}",
            answer.message
        );
        assert!(took < QUICK, "{profile}: answered after {took:?}");
        assert_no_passwd(&answer.message, &profile);
        if reason.ends_with(".yaml:") {
            let after = answer.message.split(reason).nth(1).unwrap_or("");
            assert!(
                after.starts_with(|c: char| c.is_ascii_digit()),
                "a line: {}",
                answer.message
            );
        }
    }

    // Still up, and a profile inside the data directory works, by relative and absolute path.
    for profile in [
        "my-grbl.yaml".to_string(),
        data.dir.join("my-grbl.yaml").display().to_string(),
    ] {
        let (answer, _) = emit(profile.clone()).await;
        assert!(answer.success, "{profile}: {}", answer.message);
        assert!(
            answer.program.line_count > 5,
            "{profile}: {:?}",
            answer.program
        );
    }
    assert!(emitter.is_running(), "the emitter must stay up");
    assert_no_passwd(&emitter.log(), "the emitter's log");
}

type SliceClient = ActionClient<SliceGoal, SliceResult, SliceFeedback>;

/// Whether the slicer accepts `goal`, and how long it took to say so.
async fn sent(client: &SliceClient, goal: SliceGoal) -> (bool, Duration) {
    let started = Instant::now();
    let (_, response) = within(client.async_send_goal(goal)).await.expect("sent");
    (response.accepted, started.elapsed())
}

/// Sends an accepted goal and waits for its end.
async fn finished(client: &SliceClient, goal: SliceGoal) -> (GoalStatusEnum, SliceResult) {
    let (goal_id, response) = within(client.async_send_goal(goal)).await.expect("sent");
    assert!(response.accepted, "goal rejected");
    cell_runtime::action::request_result(
        client,
        goal_id,
        Duration::from_secs(3),
        3 * DELIVERY_TIMEOUT,
    )
    .await
    .expect("result")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn slice_goals_naming_host_paths_are_rejected_without_quoting_them() {
    let domain = fresh_domain();
    let data = data_dir();
    let mut slicer = start_node("slicer", domain, &data.params);
    let client_node = node("operator", domain, false);
    let client: SliceClient = client_node.action_client("/slice").unwrap();
    discover_action_server(&client_node, "/slice").await;

    let stl = |name: &str| SliceGoal {
        job_id: format!("files-{name}"),
        stl_file: name.into(),
        ..Default::default()
    };
    let refusals = [
        (
            stl("/etc/passwd"),
            "stl_file: /etc/passwd: outside the node's data directories",
        ),
        (
            stl("/dev/zero"),
            "stl_file: /dev/zero: outside the node's data directories",
        ),
        (
            stl("zero.stl"),
            "stl_file: zero.stl: outside the node's data directories",
        ),
        (
            stl("pipe.stl"),
            "stl_file: pipe.stl: not a regular file (a FIFO)",
        ),
        (
            stl("big.stl"),
            "stl_file: big.stl: larger than the node's 1048576-byte limit",
        ),
        (
            SliceGoal {
                job_id: "files-spec".into(),
                wing_spec_file: "escape.yaml".into(),
                ..Default::default()
            },
            "wing_spec_file: escape.yaml: outside the node's data directories",
        ),
        (
            SliceGoal {
                process_file: "/etc/passwd".into(),
                ..stl("cube.stl")
            },
            "process_file: /etc/passwd: outside the node's data directories",
        ),
        (
            SliceGoal {
                process_file: "passwd.yaml".into(),
                ..stl("cube.stl")
            },
            "process_file: passwd.yaml:",
        ),
        (
            SliceGoal {
                machine_profile: "/etc/passwd".into(),
                ..stl("cube.stl")
            },
            "machine_profile: /etc/passwd: outside the node's data directories",
        ),
    ];
    for (goal, reason) in refusals {
        let what = format!("{goal:?}");
        let (accepted, took) = sent(&client, goal).await;
        assert!(!accepted, "{what}");
        assert!(took < QUICK, "{what}: answered after {took:?}");
        // ROS 2 rejections carry no text: the reason is the node's log line (and /rosout).
        slicer.logged(reason).await;
    }

    // A copy of /etc/passwd inside the data directory is read and fails as an STL: the result
    // names the file, not its lines.
    let (status, result) = finished(&client, stl("passwd.stl")).await;
    assert_eq!(status, GoalStatusEnum::Aborted, "{}", result.message);
    assert!(result.message.contains("passwd.stl"), "{}", result.message);
    assert_no_passwd(&result.message, "the result");

    // Still serving: the cube inside the data directory slices.
    let (status, result) = finished(&client, stl("cube.stl")).await;
    assert_eq!(status, GoalStatusEnum::Succeeded, "{}", result.message);
    assert!(!result.layer_stack.layers.is_empty());
    assert!(slicer.is_running(), "the slicer must stay up");
    assert_no_passwd(&slicer.log(), "the slicer's log");
}
