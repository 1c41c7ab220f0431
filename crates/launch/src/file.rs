//! Reading a launch file in ROS 2's YAML launch syntax.
//!
//! ```yaml
//! launch:
//! - arg: {name: "domain", default: "0", description: "..."}
//! - let: {name: "cfg", value: "config"}
//! - node:
//!     pkg: "cellsuite"
//!     exec: "monitor"
//!     name: "monitor"
//!     namespace: "/cell"            # or `ns`
//!     output: "screen"
//!     args: "--rerun off"
//!     param:
//!     - {name: "rate_hz", value: 2.5}
//!     - {from: "$(var cfg)/monitor.yaml"}
//!     remap:
//!     - {from: "/toolpath", to: "/plan/toolpath"}
//!     env:
//!     - {name: "RUST_LOG", value: "info"}
//! ```
//!
//! Actions are read in file order; `$(var NAME)` sees the `arg`s and `let`s
//! above it. Every string value may contain substitutions (see the crate
//! documentation), except the names of `arg`s and `let`s and descriptions.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_norway::{Mapping, Value};

use crate::param::ParamValue;
use crate::subst::{self, Scope};
use crate::LaunchError;

/// A launch file, read and with every substitution done.
#[derive(Debug, Clone, PartialEq)]
pub struct LaunchFile {
    /// The file as the caller named it (used in messages).
    pub path: PathBuf,
    /// The declared arguments, in file order, with the values they got.
    pub args: Vec<ArgDecl>,
    /// The nodes, in file order.
    pub nodes: Vec<NodeSpec>,
}

/// One `arg` action: a launch argument the caller may set with `NAME:=VALUE`.
#[derive(Debug, Clone, PartialEq)]
pub struct ArgDecl {
    /// The argument's name.
    pub name: String,
    /// Its default, if the file gives one (after substitution).
    pub default: Option<String>,
    /// Its description, if the file gives one.
    pub description: Option<String>,
    /// The value used: the caller's, else the default.
    pub value: String,
}

/// One `node` action.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeSpec {
    /// Where the node is declared, e.g. `launch[2].node` (used in messages).
    pub at: String,
    /// The package (`pkg`), handed to the executable resolver.
    pub pkg: String,
    /// The executable (`exec`), handed to the executable resolver.
    pub exec: String,
    /// The node name (`name`), passed as `-r __node:=NAME`.
    pub name: Option<String>,
    /// The namespace (`namespace` or `ns`), always starting with `/`,
    /// passed as `-r __ns:=NAMESPACE`.
    pub namespace: Option<String>,
    /// The `output` setting (`screen`, `log`, ...). Recorded only: output is
    /// always forwarded to our stdout/stderr.
    pub output: Option<String>,
    /// The `args` string split into words (shell-like).
    pub args: Vec<String>,
    /// Parameters and parameter files, in file order.
    pub params: Vec<Param>,
    /// Topic/service/name remappings, in file order.
    pub remaps: Vec<Remap>,
    /// Environment variables set for this node on top of ours.
    pub env: Vec<(String, String)>,
}

/// One entry of a node's `param` list.
#[derive(Debug, Clone, PartialEq)]
pub enum Param {
    /// `{name: NAME, value: VALUE}`, passed as `-p NAME:=VALUE`.
    Value {
        /// The parameter's name.
        name: String,
        /// Its value.
        value: ParamValue,
    },
    /// `{from: FILE}`, passed as `--params-file FILE`. Relative paths are
    /// resolved against the launch file's directory; the file exists.
    File(PathBuf),
}

/// One entry of a node's `remap` list, passed as `-r FROM:=TO`.
#[derive(Debug, Clone, PartialEq)]
pub struct Remap {
    /// The name as the node uses it.
    pub from: String,
    /// The name it is mapped to.
    pub to: String,
}

impl NodeSpec {
    /// The node's label in output prefixes and messages: its name, else its
    /// exec.
    pub fn label(&self) -> &str {
        self.name.as_deref().unwrap_or(&self.exec)
    }
}

/// Splits a caller's launch argument `NAME:=VALUE` (as `ros2 launch` takes
/// them) into name and value.
pub fn parse_launch_arg(text: &str) -> Result<(String, String), LaunchError> {
    match text.split_once(":=") {
        Some((name, value)) if !name.is_empty() => Ok((name.to_string(), value.to_string())),
        _ => Err(LaunchError::Argument {
            arg: text.to_string(),
            message: "expected NAME:=VALUE".to_string(),
        }),
    }
}

impl LaunchFile {
    /// Reads and checks the launch file at `path`. `args` are the caller's
    /// launch arguments (`NAME`, `VALUE`); they override the `arg` defaults
    /// and must each be declared by the file. A later pair overrides an
    /// earlier one of the same name.
    pub fn load(path: impl AsRef<Path>, args: &[(String, String)]) -> Result<Self, LaunchError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| LaunchError::Read {
            file: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, path, args)
    }

    /// Like [`LaunchFile::load`], for a file whose text is already read.
    /// `path` is used in messages and to resolve relative paths.
    pub fn parse(
        text: &str,
        path: impl AsRef<Path>,
        args: &[(String, String)],
    ) -> Result<Self, LaunchError> {
        let path = path.as_ref();
        let parent = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let dir = std::path::absolute(parent).unwrap_or_else(|_| parent.to_path_buf());
        let root: Value = serde_norway::from_str(text).map_err(|source| LaunchError::Yaml {
            file: path.to_path_buf(),
            source,
        })?;
        let mut reader = Reader {
            file: path,
            dir: &dir,
            overrides: args.iter().cloned().collect(),
            vars: BTreeMap::new(),
            args: Vec::new(),
            nodes: Vec::new(),
        };
        reader.root(&root)?;
        if let Some((name, value)) = reader
            .overrides
            .iter()
            .find(|(name, _)| !reader.args.iter().any(|a| &a.name == *name))
        {
            let declared: Vec<&str> = reader.args.iter().map(|a| a.name.as_str()).collect();
            return Err(LaunchError::Argument {
                arg: format!("{name}:={value}"),
                message: format!(
                    "{} declares no argument {name:?} (declared: {})",
                    path.display(),
                    if declared.is_empty() {
                        "none".to_string()
                    } else {
                        declared.join(", ")
                    }
                ),
            });
        }
        Ok(Self {
            path: path.to_path_buf(),
            args: reader.args,
            nodes: reader.nodes,
        })
    }
}

const ACTIONS: &[&str] = &["arg", "let", "node"];
const ARG_KEYS: &[&str] = &["name", "default", "description"];
const LET_KEYS: &[&str] = &["name", "value"];
const NODE_KEYS: &[&str] = &[
    "pkg",
    "exec",
    "name",
    "namespace",
    "ns",
    "output",
    "args",
    "param",
    "remap",
    "env",
];
const PARAM_KEYS: &[&str] = &["name", "value", "from"];
const REMAP_KEYS: &[&str] = &["from", "to"];
const ENV_KEYS: &[&str] = &["name", "value"];

/// The state while reading one file.
struct Reader<'a> {
    file: &'a Path,
    dir: &'a Path,
    overrides: BTreeMap<String, String>,
    /// Launch configurations defined so far.
    vars: BTreeMap<String, String>,
    args: Vec<ArgDecl>,
    nodes: Vec<NodeSpec>,
}

/// The fields of one mapping, checked against the keys allowed there.
struct Fields<'v> {
    at: String,
    map: BTreeMap<&'v str, &'v Value>,
}

impl<'v> Fields<'v> {
    fn get(&self, key: &str) -> Option<(String, &'v Value)> {
        self.map
            .get(key)
            .map(|v| (format!("{}.{key}", self.at), *v))
    }
}

fn type_name(value: &Value) -> &'static str {
    match value {
        Value::Null => "null",
        Value::Bool(_) => "a bool",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Sequence(_) => "a list",
        Value::Mapping(_) => "a mapping",
        Value::Tagged(_) => "a tagged value",
    }
}

impl Reader<'_> {
    fn invalid(&self, at: impl Into<String>, message: impl Into<String>) -> LaunchError {
        LaunchError::Invalid {
            file: self.file.to_path_buf(),
            at: at.into(),
            message: message.into(),
        }
    }

    fn root(&mut self, root: &Value) -> Result<(), LaunchError> {
        let Value::Mapping(map) = root else {
            return Err(self.invalid(
                "top level",
                format!(
                    "expected a mapping with the key `launch`, found {}",
                    type_name(root)
                ),
            ));
        };
        let fields = self.fields(map, "top level", &["launch"])?;
        let Some((at, launch)) = fields.get("launch") else {
            return Err(self.invalid("top level", "missing key \"launch\""));
        };
        let at = at.trim_start_matches("top level.").to_string();
        let actions = self.list(launch, &at)?;
        for (i, action) in actions.iter().enumerate() {
            self.action(action, &format!("{at}[{i}]"))?;
        }
        Ok(())
    }

    fn action(&mut self, action: &Value, at: &str) -> Result<(), LaunchError> {
        let Value::Mapping(map) = action else {
            return Err(self.invalid(
                at,
                format!(
                    "expected an action such as `node: {{...}}`, found {}",
                    type_name(action)
                ),
            ));
        };
        if map.len() != 1 {
            return Err(self.invalid(
                at,
                format!(
                    "an action is a mapping with exactly one key ({}), found {} keys",
                    ACTIONS.join(", "),
                    map.len()
                ),
            ));
        }
        let fields = self.fields(map, at, ACTIONS)?;
        if let Some((at, body)) = fields.get("arg") {
            self.arg(body, &at)
        } else if let Some((at, body)) = fields.get("let") {
            self.let_(body, &at)
        } else if let Some((at, body)) = fields.get("node") {
            self.node(body, &at)
        } else {
            Ok(())
        }
    }

    fn arg(&mut self, body: &Value, at: &str) -> Result<(), LaunchError> {
        let f = self.mapping(body, at, ARG_KEYS)?;
        let name = self.required_name(&f)?;
        if let Some(first) = self.args.iter().find(|a| a.name == name) {
            return Err(self.invalid(at, format!("argument {:?} is declared twice", first.name)));
        }
        let default = self.opt_text(&f, "default")?;
        let description = match f.get("description") {
            Some((at, v)) => Some(self.raw_text(v, &at)?),
            None => None,
        };
        let value = match (self.overrides.get(&name), &default) {
            (Some(given), _) => given.clone(),
            (None, Some(default)) => default.clone(),
            (None, None) => {
                return Err(self.invalid(
                    at,
                    format!(
                        "argument {name:?} has no default and was not given (pass {name}:=VALUE)"
                    ),
                ))
            }
        };
        self.vars.insert(name.clone(), value.clone());
        self.args.push(ArgDecl {
            name,
            default,
            description,
            value,
        });
        Ok(())
    }

    fn let_(&mut self, body: &Value, at: &str) -> Result<(), LaunchError> {
        let f = self.mapping(body, at, LET_KEYS)?;
        let name = self.required_name(&f)?;
        let value = self.req_text(&f, "value")?;
        self.vars.insert(name, value);
        Ok(())
    }

    fn node(&mut self, body: &Value, at: &str) -> Result<(), LaunchError> {
        let f = self.mapping(body, at, NODE_KEYS)?;
        let pkg = self.req_text(&f, "pkg")?;
        let exec = self.req_text(&f, "exec")?;
        if exec.is_empty() {
            return Err(self.invalid(format!("{at}.exec"), "must not be empty"));
        }
        let name = self.opt_text(&f, "name")?;
        let namespace = match (self.opt_text(&f, "namespace")?, self.opt_text(&f, "ns")?) {
            (Some(_), Some(_)) => {
                return Err(self.invalid(at, "give either `namespace` or `ns`, not both"))
            }
            (Some(ns), None) | (None, Some(ns)) if ns.starts_with('/') => Some(ns),
            (Some(ns), None) | (None, Some(ns)) => Some(format!("/{ns}")),
            (None, None) => None,
        };
        let output = self.opt_text(&f, "output")?;
        let args = match f.get("args") {
            Some((at, v)) => {
                let text = self.text(v, &at)?;
                shell_words::split(&text)
                    .map_err(|e| self.invalid(at, format!("cannot split {text:?}: {e}")))?
            }
            None => Vec::new(),
        };
        let mut params = Vec::new();
        if let Some((at, v)) = f.get("param") {
            for (i, entry) in self.list(v, &at)?.iter().enumerate() {
                params.push(self.param(entry, &format!("{at}[{i}]"))?);
            }
        }
        let mut remaps = Vec::new();
        if let Some((at, v)) = f.get("remap") {
            for (i, entry) in self.list(v, &at)?.iter().enumerate() {
                let f = self.mapping(entry, &format!("{at}[{i}]"), REMAP_KEYS)?;
                remaps.push(Remap {
                    from: self.req_text(&f, "from")?,
                    to: self.req_text(&f, "to")?,
                });
            }
        }
        let mut env = Vec::new();
        if let Some((at, v)) = f.get("env") {
            for (i, entry) in self.list(v, &at)?.iter().enumerate() {
                let f = self.mapping(entry, &format!("{at}[{i}]"), ENV_KEYS)?;
                let name = self.req_text(&f, "name")?;
                if name.is_empty() || name.contains('=') || name.contains('\0') {
                    return Err(self.invalid(
                        format!("{}.name", f.at),
                        format!("{name:?} is not a valid environment variable name"),
                    ));
                }
                env.push((name, self.req_text(&f, "value")?));
            }
        }
        self.nodes.push(NodeSpec {
            at: at.to_string(),
            pkg,
            exec,
            name,
            namespace,
            output,
            args,
            params,
            remaps,
            env,
        });
        Ok(())
    }

    fn param(&self, entry: &Value, at: &str) -> Result<Param, LaunchError> {
        let f = self.mapping(entry, at, PARAM_KEYS)?;
        if let Some((from_at, from)) = f.get("from") {
            if f.map.len() > 1 {
                return Err(self.invalid(
                    at,
                    "give either `from` (a params file) or `name` and `value`, not both",
                ));
            }
            let path = PathBuf::from(self.text(from, &from_at)?);
            let path = if path.is_relative() {
                self.dir.join(path)
            } else {
                path
            };
            if !path.is_file() {
                return Err(
                    self.invalid(from_at, format!("params file {} not found", path.display()))
                );
            }
            return Ok(Param::File(path));
        }
        let name = self.req_text(&f, "name")?;
        if name.is_empty() {
            return Err(self.invalid(format!("{at}.name"), "must not be empty"));
        }
        let Some((value_at, value)) = f.get("value") else {
            return Err(self.invalid(at, "missing key \"value\" (or give `from: FILE`)"));
        };
        let value = self.param_value(value, &value_at)?;
        Ok(Param::Value { name, value })
    }

    /// A parameter value. Literal strings stay strings; a string holding a
    /// substitution is read as YAML once substituted, as ROS 2 does, so
    /// `value: $(var rate)` with `rate` = `2.5` is the float 2.5.
    fn param_value(&self, value: &Value, at: &str) -> Result<ParamValue, LaunchError> {
        let substituted = match value {
            Value::String(s) => Some(self.retyped(s, at)?),
            Value::Sequence(items) => {
                let mut out = Vec::with_capacity(items.len());
                for (i, item) in items.iter().enumerate() {
                    out.push(match item {
                        Value::String(s) => self.retyped(s, &format!("{at}[{i}]"))?,
                        other => other.clone(),
                    });
                }
                Some(Value::Sequence(out))
            }
            _ => None,
        };
        ParamValue::from_yaml(substituted.as_ref().unwrap_or(value))
            .map_err(|message| self.invalid(at, message))
    }

    fn retyped(&self, s: &str, at: &str) -> Result<Value, LaunchError> {
        if !subst::has_substitution(s) {
            return Ok(Value::String(s.to_string()));
        }
        let text = self.substitute(s, at)?;
        Ok(match serde_norway::from_str::<Value>(&text) {
            Ok(v @ (Value::Bool(_) | Value::Number(_) | Value::Sequence(_))) => v,
            _ => Value::String(text),
        })
    }

    fn fields<'v>(
        &self,
        map: &'v Mapping,
        at: &str,
        allowed: &[&str],
    ) -> Result<Fields<'v>, LaunchError> {
        let mut out = BTreeMap::new();
        for (key, value) in map {
            let Value::String(key) = key else {
                return Err(self.invalid(
                    at,
                    format!("keys must be strings, found {}", type_name(key)),
                ));
            };
            if !allowed.contains(&key.as_str()) {
                let what = if allowed == ACTIONS {
                    "unknown action"
                } else {
                    "unknown key"
                };
                return Err(self.invalid(
                    at,
                    format!("{what} {key:?} (expected one of: {})", allowed.join(", ")),
                ));
            }
            out.insert(key.as_str(), value);
        }
        Ok(Fields {
            at: at.to_string(),
            map: out,
        })
    }

    fn mapping<'v>(
        &self,
        value: &'v Value,
        at: &str,
        allowed: &[&str],
    ) -> Result<Fields<'v>, LaunchError> {
        match value {
            Value::Mapping(map) => self.fields(map, at, allowed),
            other => Err(self.invalid(
                at,
                format!(
                    "expected a mapping with keys {}, found {}",
                    allowed.join(", "),
                    type_name(other)
                ),
            )),
        }
    }

    fn list<'v>(&self, value: &'v Value, at: &str) -> Result<&'v [Value], LaunchError> {
        match value {
            Value::Sequence(items) => Ok(items),
            other => Err(self.invalid(at, format!("expected a list, found {}", type_name(other)))),
        }
    }

    fn substitute(&self, text: &str, at: &str) -> Result<String, LaunchError> {
        subst::substitute(
            text,
            &Scope {
                vars: &self.vars,
                dir: self.dir,
            },
        )
        .map_err(|message| self.invalid(at, message))
    }

    /// A scalar as text, without substitution.
    fn raw_text(&self, value: &Value, at: &str) -> Result<String, LaunchError> {
        match value {
            Value::String(s) => Ok(s.clone()),
            Value::Number(n) => Ok(n.to_string()),
            Value::Bool(b) => Ok(b.to_string()),
            other => {
                Err(self.invalid(at, format!("expected a string, found {}", type_name(other))))
            }
        }
    }

    /// A scalar as text, with substitutions done.
    fn text(&self, value: &Value, at: &str) -> Result<String, LaunchError> {
        let raw = self.raw_text(value, at)?;
        self.substitute(&raw, at)
    }

    fn opt_text(&self, f: &Fields<'_>, key: &str) -> Result<Option<String>, LaunchError> {
        f.get(key).map(|(at, v)| self.text(v, &at)).transpose()
    }

    fn req_text(&self, f: &Fields<'_>, key: &str) -> Result<String, LaunchError> {
        self.opt_text(f, key)?
            .ok_or_else(|| self.invalid(&f.at, format!("missing key {key:?}")))
    }

    /// The `name` of an `arg` or `let`: required, no substitutions.
    fn required_name(&self, f: &Fields<'_>) -> Result<String, LaunchError> {
        let Some((at, v)) = f.get("name") else {
            return Err(self.invalid(&f.at, "missing key \"name\""));
        };
        let name = self.raw_text(v, &at)?;
        if name.is_empty() || name.contains(['$', '(', ')']) || name.contains(char::is_whitespace) {
            return Err(self.invalid(at, format!("{name:?} is not a valid argument name")));
        }
        Ok(name)
    }
}
