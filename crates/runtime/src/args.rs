//! The ROS 2 command line: `node [user args] --ros-args -r __node:=… -r __ns:=… -r old:=new
//! -p key:=value --params-file FILE [--]`.
//!
//! Hand-written because clap cannot express ROS 2's repeated `--ros-args … --` sections; the
//! grammar is the one `rcl` accepts (see `rcl/src/rcl/arguments.c`), minus the flags we have
//! no use for, which are rejected by name rather than ignored.

use std::path::PathBuf;

/// Everything the `--ros-args` sections of a command line asked for.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RosArgs {
    /// `-r __node:=NAME`: overrides the node's default name.
    pub node_name: Option<String>,
    /// `-r __ns:=NS`: the node's namespace (absolute).
    pub namespace: Option<String>,
    /// `-r FROM:=TO` topic/service remappings, in command-line order.
    pub remaps: Vec<(String, String)>,
    /// `-p KEY:=VALUE` overrides; VALUE is YAML text, as in ROS 2.
    pub params: Vec<(String, String)>,
    /// `--params-file FILE`, in order; later files override earlier ones.
    pub params_files: Vec<PathBuf>,
    /// `--log-level LEVEL` (a `tracing` filter directive such as `debug` or `planner=trace`).
    pub log_level: Option<String>,
    /// `-e`/`--enclave ENCLAVE`: the SROS2 enclave (absolute, like a namespace) whose keys the
    /// node uses when `ROS_SECURITY_ENABLE=true` (see [`crate::security`]).
    pub enclave: Option<String>,
}

/// A command line split into the node's own arguments and its ROS arguments.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NodeArgs {
    /// Arguments outside `--ros-args` sections, program name excluded.
    pub user: Vec<String>,
    /// What the `--ros-args` sections said.
    pub ros: RosArgs,
}

/// A `--ros-args` section that cannot be understood; names the flag at fault.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ArgsError {
    /// A flag that needs a value was last on the line.
    #[error("--ros-args: {flag} needs a value")]
    MissingValue {
        /// The flag.
        flag: String,
    },
    /// A `-r`/`-p` value without `:=`.
    #[error("--ros-args: {flag} {value:?}: expected NAME:=VALUE")]
    NoAssignment {
        /// The flag.
        flag: String,
        /// What followed it.
        value: String,
    },
    /// A `-r __ns:=` namespace that is not absolute, or an empty node name.
    #[error("--ros-args: -r {what}:={value:?}: {reason}")]
    BadName {
        /// `__node` or `__ns`.
        what: String,
        /// The offending value.
        value: String,
        /// Why it was refused.
        reason: String,
    },
    /// An `--enclave` that is not absolute (rcl validates it like a namespace).
    #[error("--ros-args: --enclave {0:?}: an enclave must be absolute (start with '/')")]
    RelativeEnclave(String),
    /// A flag ROS 2 knows but this runtime does not support, or an unknown flag.
    #[error(
        "--ros-args: unsupported argument {0:?} (supported: -r, -p, --params-file, --log-level, -e)"
    )]
    Unsupported(String),
}

impl NodeArgs {
    /// Parses `args`, which excludes the program name.
    pub fn parse<I, S>(args: I) -> Result<Self, ArgsError>
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        let mut out = NodeArgs::default();
        let mut iter = args.into_iter().map(Into::into);
        let mut in_ros = false;
        while let Some(arg) = iter.next() {
            if !in_ros {
                if arg == "--ros-args" {
                    in_ros = true;
                } else {
                    out.user.push(arg);
                }
                continue;
            }
            let mut value_of = |flag: &str| {
                iter.next().ok_or_else(|| ArgsError::MissingValue {
                    flag: flag.to_string(),
                })
            };
            match arg.as_str() {
                "--" => in_ros = false,
                "--ros-args" => {}
                "-r" | "--remap" => {
                    let value = value_of(&arg)?;
                    let (from, to) = split_assignment(&arg, &value)?;
                    out.ros.apply_remap(from, to)?;
                }
                "-p" | "--param" => {
                    let value = value_of(&arg)?;
                    let (key, yaml) = split_assignment(&arg, &value)?;
                    out.ros.params.push((key.to_string(), yaml.to_string()));
                }
                "--params-file" => out.ros.params_files.push(value_of(&arg)?.into()),
                "--log-level" => out.ros.log_level = Some(value_of(&arg)?),
                "-e" | "--enclave" => {
                    let value = value_of(&arg)?;
                    if !value.starts_with('/') {
                        return Err(ArgsError::RelativeEnclave(value));
                    }
                    out.ros.enclave = Some(value);
                }
                other => return Err(ArgsError::Unsupported(other.to_string())),
            }
        }
        Ok(out)
    }
}

impl RosArgs {
    fn apply_remap(&mut self, from: &str, to: &str) -> Result<(), ArgsError> {
        let bad = |what: &str, reason: &str| ArgsError::BadName {
            what: what.to_string(),
            value: to.to_string(),
            reason: reason.to_string(),
        };
        match from {
            "__node" | "__name" => {
                if to.is_empty() || to.contains('/') {
                    return Err(bad("__node", "a node name is non-empty and has no '/'"));
                }
                self.node_name = Some(to.to_string());
            }
            "__ns" => {
                if !to.starts_with('/') {
                    return Err(bad("__ns", "a namespace must be absolute (start with '/')"));
                }
                self.namespace = Some(to.to_string());
            }
            _ => self.remaps.push((from.to_string(), to.to_string())),
        }
        Ok(())
    }
}

fn split_assignment<'a>(flag: &str, value: &'a str) -> Result<(&'a str, &'a str), ArgsError> {
    match value.split_once(":=") {
        Some((name, rhs)) if !name.is_empty() => Ok((name, rhs)),
        _ => Err(ArgsError::NoAssignment {
            flag: flag.to_string(),
            value: value.to_string(),
        }),
    }
}

/// Resolves a topic name the way `rcl` does: absolute names stay, `~/x` is private to the node,
/// relative names join the namespace. Remappings match the fully qualified name or, for
/// convenience, the name as written.
pub fn resolve_topic(
    name: &str,
    namespace: &str,
    node_name: &str,
    remaps: &[(String, String)],
) -> String {
    let qualify = |n: &str| -> String {
        let ns = namespace.trim_end_matches('/');
        if n.starts_with('/') {
            n.to_string()
        } else if let Some(rest) = n.strip_prefix("~/") {
            format!("{ns}/{node_name}/{rest}")
        } else {
            format!("{ns}/{n}")
        }
    };
    let full = qualify(name);
    for (from, to) in remaps {
        if qualify(from) == full || from == name {
            return qualify(to);
        }
    }
    full
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_user_and_ros_sections() {
        let args = NodeArgs::parse([
            "--rerun",
            "off",
            "--ros-args",
            "-r",
            "__node:=cutter",
            "-r",
            "__ns:=/cell1",
            "-r",
            "toolpath:=/plan/toolpath",
            "-p",
            "rate_hz:=2.5",
            "--params-file",
            "config/planner.yaml",
            "--log-level",
            "debug",
            "--enclave",
            "/cell/planner",
            "--",
            "extra",
        ])
        .unwrap();
        assert_eq!(args.user, ["--rerun", "off", "extra"]);
        assert_eq!(args.ros.node_name.as_deref(), Some("cutter"));
        assert_eq!(args.ros.namespace.as_deref(), Some("/cell1"));
        assert_eq!(
            args.ros.remaps,
            [("toolpath".to_string(), "/plan/toolpath".to_string())]
        );
        assert_eq!(
            args.ros.params,
            [("rate_hz".to_string(), "2.5".to_string())]
        );
        assert_eq!(
            args.ros.params_files,
            [PathBuf::from("config/planner.yaml")]
        );
        assert_eq!(args.ros.log_level.as_deref(), Some("debug"));
        assert_eq!(args.ros.enclave.as_deref(), Some("/cell/planner"));
    }

    #[test]
    fn bad_flags_name_themselves() {
        let err = NodeArgs::parse(["--ros-args", "-p"]).unwrap_err();
        assert_eq!(err.to_string(), "--ros-args: -p needs a value");
        let err = NodeArgs::parse(["--ros-args", "-p", "rate=3"]).unwrap_err();
        assert!(err
            .to_string()
            .contains("-p \"rate=3\": expected NAME:=VALUE"));
        let err = NodeArgs::parse(["--ros-args", "--log-config-file", "x.conf"]).unwrap_err();
        assert!(err
            .to_string()
            .contains("unsupported argument \"--log-config-file\""));
        let err = NodeArgs::parse(["--ros-args", "-e", "enclave"]).unwrap_err();
        assert!(err.to_string().contains("must be absolute"), "{err}");
        let err = NodeArgs::parse(["--ros-args", "-r", "__ns:=cell"]).unwrap_err();
        assert!(err.to_string().contains("must be absolute"));
    }

    #[test]
    fn resolves_names_like_rcl() {
        let remaps = vec![("/cell/heat".to_string(), "/sheet/heat".to_string())];
        assert_eq!(
            resolve_topic("toolpath", "/cell", "n", &[]),
            "/cell/toolpath"
        );
        assert_eq!(resolve_topic("/abs", "/cell", "n", &[]), "/abs");
        assert_eq!(resolve_topic("~/status", "/", "n", &[]), "/n/status");
        assert_eq!(resolve_topic("heat", "/cell", "n", &remaps), "/sheet/heat");
        let relative = vec![("heat".to_string(), "other".to_string())];
        assert_eq!(
            resolve_topic("heat", "/cell", "n", &relative),
            "/cell/other"
        );
    }
}
