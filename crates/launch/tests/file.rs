//! Reading launch files, rendering command lines and planning.

use std::path::{Path, PathBuf};

use cell_launch::{
    default_resolver, parse_launch_arg, LaunchError, LaunchFile, Param, ParamValue, Program, Remap,
};

const EXAMPLE: &str = r#"
launch:
- arg: {name: "domain", default: "0", description: "DDS domain"}
- let: {name: "cfg", value: "config"}
- node:
    pkg: "cellsuite"
    exec: "monitor"
    name: "monitor"
    namespace: "/cell"
    output: "screen"
    args: "--rerun off --label 'two words'"
    param:
    - {name: "expect_toolpaths", value: 1}
    - {name: "rate_hz", value: 2.5}
    - {name: "labels", value: ["a", "b"]}
    - {name: "id", value: "42"}
    - {name: "domain", value: "$(var domain)"}
    - {from: "$(var cfg)/monitor.yaml"}
    remap:
    - {from: "/toolpath", to: "/plan/toolpath"}
    env:
    - {name: "RUST_LOG", value: "info"}
    - {name: "ROS_DOMAIN_ID", value: "$(var domain)"}
- node:
    pkg: "cellsuite"
    exec: "planner"
    ns: "cell"
"#;

/// A temporary directory with `demo.launch.yaml` (holding `text`) and
/// `config/monitor.yaml`.
fn setup(text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("config")).unwrap();
    std::fs::write(dir.path().join("config/monitor.yaml"), "monitor: {}\n").unwrap();
    let path = dir.path().join("demo.launch.yaml");
    std::fs::write(&path, text).unwrap();
    (dir, path)
}

fn load(text: &str, args: &[(&str, &str)]) -> Result<LaunchFile, LaunchError> {
    let (_dir, path) = setup(text);
    let args: Vec<(String, String)> = args
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    LaunchFile::load(&path, &args)
}

fn error(text: &str) -> String {
    let e = load(text, &[]).expect_err("should not load").to_string();
    assert!(e.contains("demo.launch.yaml"), "no file name in: {e}");
    e
}

#[test]
fn parses_the_example() {
    let (dir, path) = setup(EXAMPLE);
    let file = LaunchFile::load(&path, &[]).unwrap();
    assert_eq!(file.args.len(), 1);
    assert_eq!(file.args[0].name, "domain");
    assert_eq!(file.args[0].value, "0");
    assert_eq!(file.args[0].description.as_deref(), Some("DDS domain"));
    assert_eq!(file.nodes.len(), 2);

    let monitor = &file.nodes[0];
    assert_eq!(monitor.at, "launch[2].node");
    assert_eq!(monitor.pkg, "cellsuite");
    assert_eq!(monitor.exec, "monitor");
    assert_eq!(monitor.label(), "monitor");
    assert_eq!(monitor.namespace.as_deref(), Some("/cell"));
    assert_eq!(monitor.output.as_deref(), Some("screen"));
    assert_eq!(monitor.args, ["--rerun", "off", "--label", "two words"]);
    let params_file = dir.path().join("config/monitor.yaml");
    assert_eq!(
        monitor.params,
        [
            Param::Value {
                name: "expect_toolpaths".into(),
                value: ParamValue::Int(1)
            },
            Param::Value {
                name: "rate_hz".into(),
                value: ParamValue::Float(2.5)
            },
            Param::Value {
                name: "labels".into(),
                value: ParamValue::List(vec![
                    ParamValue::String("a".into()),
                    ParamValue::String("b".into())
                ])
            },
            Param::Value {
                name: "id".into(),
                value: ParamValue::String("42".into())
            },
            // A substituted value is typed as YAML, as in ROS 2.
            Param::Value {
                name: "domain".into(),
                value: ParamValue::Int(0)
            },
            Param::File(params_file.clone()),
        ]
    );
    assert_eq!(
        monitor.remaps,
        [Remap {
            from: "/toolpath".into(),
            to: "/plan/toolpath".into()
        }]
    );
    assert_eq!(
        monitor.env,
        [
            ("RUST_LOG".to_string(), "info".to_string()),
            ("ROS_DOMAIN_ID".to_string(), "0".to_string())
        ]
    );
    assert_eq!(
        monitor.command_args(),
        [
            "--rerun",
            "off",
            "--label",
            "two words",
            "--ros-args",
            "-r",
            "__node:=monitor",
            "-r",
            "__ns:=/cell",
            "-p",
            "expect_toolpaths:=1",
            "-p",
            "rate_hz:=2.5",
            "-p",
            "labels:=[a, b]",
            "-p",
            "id:='42'",
            "-p",
            "domain:=0",
            "--params-file",
            params_file.to_str().unwrap(),
            "-r",
            "/toolpath:=/plan/toolpath",
        ]
    );

    let planner = &file.nodes[1];
    assert_eq!(planner.label(), "planner");
    assert_eq!(
        planner.namespace.as_deref(),
        Some("/cell"),
        "`ns` gets a leading /"
    );
    assert_eq!(planner.command_args(), ["--ros-args", "-r", "__ns:=/cell"]);
}

#[test]
fn a_node_without_ros_arguments_gets_no_ros_args() {
    let file = load(
        "launch:\n- node: {pkg: p, exec: sh, args: \"-c 'echo hi'\"}\n",
        &[],
    )
    .unwrap();
    assert_eq!(file.nodes[0].command_args(), ["-c", "echo hi"]);
}

#[test]
fn substitutions() {
    let text = r#"
launch:
- arg: {name: a, default: "x-$(env CELL_LAUNCH_SURELY_UNSET_1 dflt)"}
- let: {name: b, value: "$(var a)/$(optenv CELL_LAUNCH_SURELY_UNSET_2)"}
- node:
    pkg: p
    exec: "$(var b)"
    name: "$(env PATH)"
    param:
    - {name: "dir", value: "$(dirname)"}
    - {name: "flag", value: "$(var t)"}
"#;
    let text = text.replace("launch:\n", "launch:\n- let: {name: t, value: \"true\"}\n");
    let (dir, path) = setup(&text);
    let file = LaunchFile::load(&path, &[]).unwrap();
    let node = &file.nodes[0];
    assert_eq!(file.args[0].value, "x-dflt");
    assert_eq!(node.exec, "x-dflt/");
    assert_eq!(
        node.name.as_deref(),
        Some(std::env::var("PATH").unwrap().as_str())
    );
    let dir = std::path::absolute(dir.path()).unwrap();
    assert_eq!(
        node.params,
        [
            Param::Value {
                name: "dir".into(),
                value: ParamValue::String(dir.display().to_string())
            },
            Param::Value {
                name: "flag".into(),
                value: ParamValue::Bool(true)
            },
        ]
    );
}

#[test]
fn caller_arguments_override_defaults() {
    let file = load(EXAMPLE, &[("domain", "7")]).unwrap();
    assert_eq!(file.args[0].value, "7");
    assert_eq!(file.args[0].default.as_deref(), Some("0"));
    assert!(file.nodes[0]
        .command_args()
        .contains(&"domain:=7".to_string()));
    assert!(file.nodes[0]
        .env
        .contains(&("ROS_DOMAIN_ID".to_string(), "7".to_string())));

    let e = load(EXAMPLE, &[("domian", "7")]).unwrap_err().to_string();
    assert!(e.contains("\"domian:=7\""), "{e}");
    assert!(
        e.contains("demo.launch.yaml declares no argument \"domian\""),
        "{e}"
    );
    assert!(e.contains("declared: domain"), "{e}");

    let required = "launch:\n- arg: {name: robot}\n- node: {pkg: p, exec: \"$(var robot)\"}\n";
    let e = load(required, &[]).unwrap_err().to_string();
    assert!(
        e.contains("demo.launch.yaml: launch[0].arg: argument \"robot\" has no default"),
        "{e}"
    );
    assert_eq!(
        load(required, &[("robot", "r1")]).unwrap().nodes[0].exec,
        "r1"
    );

    assert_eq!(
        parse_launch_arg("domain:=a:=b").unwrap(),
        ("domain".to_string(), "a:=b".to_string())
    );
    let e = parse_launch_arg("domain=3").unwrap_err().to_string();
    assert!(e.contains("expected NAME:=VALUE"), "{e}");
}

#[test]
fn bad_input_names_file_and_key() {
    let node = |body: &str| {
        format!("launch:\n- arg: {{name: a, default: x}}\n- node: {{pkg: p, exec: e}}\n- node: {body}\n")
    };
    let cases: &[(String, &str)] = &[
        (
            node("{pkg: p, exec: e, remaps: []}"),
            "launch[2].node: unknown key \"remaps\"",
        ),
        (
            node("{pkg: p, name: n}"),
            "launch[2].node: missing key \"exec\"",
        ),
        (node("{exec: e}"), "launch[2].node: missing key \"pkg\""),
        (
            node("{pkg: p, exec: ''}"),
            "launch[2].node.exec: must not be empty",
        ),
        (
            node("{pkg: p, exec: [e]}"),
            "launch[2].node.exec: expected a string, found a list",
        ),
        (
            node("{pkg: p, exec: e, param: x}"),
            "launch[2].node.param: expected a list, found a string",
        ),
        (
            node("{pkg: p, exec: e, param: [x]}"),
            "launch[2].node.param[0]: expected a mapping",
        ),
        (
            node("{pkg: p, exec: e, param: [{name: n}]}"),
            "launch[2].node.param[0]: missing key \"value\"",
        ),
        (
            node("{pkg: p, exec: e, param: [{value: 1}]}"),
            "launch[2].node.param[0]: missing key \"name\"",
        ),
        (
            node("{pkg: p, exec: e, param: [{name: n, value: {a: 1}}]}"),
            "launch[2].node.param[0].value: a mapping is not a parameter value",
        ),
        (
            node("{pkg: p, exec: e, param: [{name: n, value: [1, a]}]}"),
            "launch[2].node.param[0].value: item [1] is string but item [0] is integer",
        ),
        (
            node("{pkg: p, exec: e, param: [{name: n, value: null}]}"),
            "launch[2].node.param[0].value: null is not a parameter value",
        ),
        (
            node("{pkg: p, exec: e, param: [{from: f.yaml, name: n}]}"),
            "launch[2].node.param[0]: give either `from`",
        ),
        (
            node("{pkg: p, exec: e, param: [{from: missing.yaml}]}"),
            "launch[2].node.param[0].from: params file",
        ),
        (
            node("{pkg: p, exec: e, remap: [{from: a}]}"),
            "launch[2].node.remap[0]: missing key \"to\"",
        ),
        (
            node("{pkg: p, exec: e, env: {A: b}}"),
            "launch[2].node.env: expected a list, found a mapping",
        ),
        (
            node("{pkg: p, exec: e, env: [{name: A}]}"),
            "launch[2].node.env[0]: missing key \"value\"",
        ),
        (
            node("{pkg: p, exec: e, env: [{name: 'A=B', value: c}]}"),
            "launch[2].node.env[0].name: \"A=B\" is not a valid environment variable name",
        ),
        (
            node("{pkg: p, exec: e, ns: a, namespace: b}"),
            "launch[2].node: give either `namespace` or `ns`",
        ),
        (
            node("{pkg: p, exec: e, args: \"'open\"}"),
            "launch[2].node.args: cannot split",
        ),
        (
            node("{pkg: p, exec: \"$(find-pkg-share p)\"}"),
            "launch[2].node.exec: unknown substitution \"find-pkg-share\"",
        ),
        (
            node("{pkg: p, exec: \"$(var nope)\"}"),
            "launch[2].node.exec: undefined launch argument \"nope\"",
        ),
        (
            node("{pkg: p, exec: \"$(env CELL_LAUNCH_SURELY_UNSET_3)\"}"),
            "launch[2].node.exec: environment variable \"CELL_LAUNCH_SURELY_UNSET_3\" is not set",
        ),
        (
            node("{pkg: p, exec: \"$(var a\"}"),
            "launch[2].node.exec: missing closing `)`",
        ),
        (
            node("[pkg, exec]"),
            "launch[2].node: expected a mapping with keys pkg, exec",
        ),
        (
            "launch:\n- include: {file: x}\n".into(),
            "launch[0]: unknown action \"include\" (expected one of: arg, let, node)",
        ),
        (
            "launch:\n- node: {pkg: p, exec: e}\n  arg: {name: a}\n".into(),
            "launch[0]: an action is a mapping with exactly one key",
        ),
        (
            "launch:\n- just text\n".into(),
            "launch[0]: expected an action",
        ),
        (
            "launch:\n- arg: {default: x}\n".into(),
            "launch[0].arg: missing key \"name\"",
        ),
        (
            "launch:\n- arg: {name: a, default: x, choices: [x]}\n".into(),
            "launch[0].arg: unknown key \"choices\"",
        ),
        (
            "launch:\n- arg: {name: a, default: x}\n- arg: {name: a, default: y}\n".into(),
            "launch[1].arg: argument \"a\" is declared twice",
        ),
        (
            "launch:\n- let: {name: a}\n".into(),
            "launch[0].let: missing key \"value\"",
        ),
        (
            "launch: {node: {}}\n".into(),
            "launch: expected a list, found a mapping",
        ),
        ("nodes: []\n".into(), "top level: unknown key \"nodes\""),
        ("{}\n".into(), "top level: missing key \"launch\""),
        (
            "- node: {}\n".into(),
            "top level: expected a mapping with the key `launch`, found a list",
        ),
        (
            "".into(),
            "top level: expected a mapping with the key `launch`, found null",
        ),
        ("launch: [\n".into(), "not valid YAML"),
    ];
    for (text, expected) in cases {
        let e = error(text);
        assert!(
            e.contains(&format!("demo.launch.yaml: {expected}")),
            "for\n{text}\nexpected {expected:?} in:\n{e}"
        );
    }
    // The location follows the file name directly.
    let e = error(&node("{pkg: p, exec: e, remaps: []}"));
    assert!(e.ends_with("demo.launch.yaml: launch[2].node: unknown key \"remaps\" (expected one of: pkg, exec, name, namespace, ns, output, args, param, remap, env)"), "{e}");
}

#[test]
fn params_files_resolve_against_the_launch_file_directory() {
    let (dir, path) = setup("launch:\n- node: {pkg: p, exec: e, param: [{from: config/monitor.yaml}, {from: ./config/../config/monitor.yaml}]}\n");
    // Load from another working directory's point of view: the path is
    // absolute, and the params file is not next to the test's cwd.
    assert!(!Path::new("config/monitor.yaml").exists());
    let file = LaunchFile::load(&path, &[]).unwrap();
    let expected = dir.path().join("config/monitor.yaml");
    assert_eq!(file.nodes[0].params[0], Param::File(expected.clone()));
    match &file.nodes[0].params[1] {
        Param::File(p) => assert_eq!(p.canonicalize().unwrap(), expected.canonicalize().unwrap()),
        other => panic!("{other:?}"),
    }
    let absolute = format!(
        "launch:\n- node: {{pkg: p, exec: e, param: [{{from: '{}'}}]}}\n",
        expected.display()
    );
    let file = LaunchFile::parse(&absolute, "/elsewhere/x.launch.yaml", &[]).unwrap();
    assert_eq!(file.nodes[0].params[0], Param::File(expected));
}

#[test]
fn command_line_values_read_back_as_the_same_yaml() {
    let text = r#"
launch:
- node:
    pkg: p
    exec: e
    param:
    - {name: i, value: -3}
    - {name: f, value: 1.0}
    - {name: big, value: 1.0e+20}
    - {name: b, value: false}
    - {name: s, value: "hello"}
    - {name: num_string, value: "42"}
    - {name: bool_string, value: "yes"}
    - {name: float_string, value: "2.5"}
    - {name: empty, value: ""}
    - {name: spaced, value: "a b: c, d"}
    - {name: quote, value: "it's \"x\""}
    - {name: newline, value: "a\nb"}
    - {name: strings, value: ["1", "x, y", "", "true"]}
    - {name: floats, value: [0.5, 1.0]}
    - {name: ints, value: [1, 2]}
    - {name: empty_list, value: []}
"#;
    let file = load(text, &[]).unwrap();
    let node = &file.nodes[0];
    let argv = node.command_args();
    let rendered: Vec<&str> = argv
        .windows(2)
        .filter(|w| w[0] == "-p")
        .map(|w| w[1].as_str())
        .collect();
    assert_eq!(rendered.len(), node.params.len());
    for (param, text) in node.params.iter().zip(rendered) {
        let Param::Value { name, value } = param else {
            panic!("{param:?}")
        };
        let (key, yaml) = text.split_once(":=").unwrap();
        assert_eq!(key, name);
        let back: serde_norway::Value = serde_norway::from_str(yaml).unwrap();
        assert_eq!(back, to_yaml(value), "{name} rendered as {yaml:?}");
    }
}

/// The parameter as a plain YAML value, built independently of the
/// renderer.
fn to_yaml(value: &ParamValue) -> serde_norway::Value {
    use serde_norway::Value;
    match value {
        ParamValue::Bool(b) => Value::Bool(*b),
        ParamValue::Int(i) => Value::Number((*i).into()),
        ParamValue::Float(f) => Value::Number((*f).into()),
        ParamValue::String(s) => Value::String(s.clone()),
        ParamValue::List(items) => Value::Sequence(items.iter().map(to_yaml).collect()),
    }
}

#[test]
fn planning_resolves_every_exec_first() {
    let text = "launch:\n- node: {pkg: cellsuite, exec: sh, name: a}\n- node: {pkg: cellsuite, exec: sh}\n- node: {pkg: cellsuite, exec: sh}\n- node: {pkg: cellsuite, exec: no-such-exec-xyz, name: ghost}\n";
    let file = load(text, &[]).unwrap();
    let e = file.plan(default_resolver).unwrap_err().to_string();
    assert!(
        e.ends_with("demo.launch.yaml: launch[3].node: node \"ghost\": no executable found for exec \"no-such-exec-xyz\" of package \"cellsuite\""),
        "{e}"
    );

    let file = load(&text.replace("no-such-exec-xyz", "sh"), &[]).unwrap();
    let plan = file.plan(default_resolver).unwrap();
    let labels: Vec<&str> = plan.iter().map(|p| p.label.as_str()).collect();
    assert_eq!(labels, ["a", "sh", "sh-2", "ghost"]);
    assert!(plan[1].program.ends_with("sh") && plan[1].program.is_absolute());

    // A resolver that runs built-in nodes through another program.
    let plan = file
        .plan(|pkg, exec| {
            Some(Program {
                program: "/usr/bin/cell".into(),
                leading_args: vec!["node".into(), format!("{pkg}/{exec}")],
            })
        })
        .unwrap();
    assert_eq!(plan[0].program, Path::new("/usr/bin/cell"));
    assert_eq!(
        plan[0].args,
        ["node", "cellsuite/sh", "--ros-args", "-r", "__node:=a"]
    );
    assert_eq!(
        plan[0].command_line(),
        "/usr/bin/cell node cellsuite/sh --ros-args -r '__node:=a'"
    );
}

#[test]
fn default_resolver_takes_paths_and_path_lookups() {
    let sh = default_resolver("any", "sh").expect("sh on PATH");
    assert!(sh.leading_args.is_empty());
    assert_eq!(
        default_resolver("any", sh.program.to_str().unwrap()),
        Some(sh)
    );
    assert_eq!(default_resolver("any", "/nonexistent/sh"), None);
    assert_eq!(default_resolver("any", "no-such-exec-xyz"), None);
    // Not executable: a directory, a plain file.
    assert_eq!(default_resolver("any", "/tmp"), None);
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain");
    std::fs::write(&plain, "").unwrap();
    assert_eq!(default_resolver("any", plain.to_str().unwrap()), None);
}
