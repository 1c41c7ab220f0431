//! Node parameters: ROS 2 parameter YAML files plus `-p key:=value` overrides, validated into a
//! typed struct.
//!
//! A params file is a mapping from node selectors to `ros__parameters:` blocks, as in ROS 2:
//! ```yaml
//! /**:                     # every node
//!   ros__parameters: {rerun: "off"}
//! monitor:                 # the node named `monitor`, any namespace
//!   ros__parameters:
//!     expect_toolpaths: 1
//! /cell/monitor:           # exactly /cell/monitor
//!   ros__parameters: {}
//! ```
//! Later sources override earlier ones: files in command-line order, then `-p`. The merged
//! mapping is deserialized into the node's struct, which should use
//! `#[serde(deny_unknown_fields, default)]`, so a typo is an error naming its file and key.

use std::{collections::HashMap, path::Path};

use serde::de::DeserializeOwned;
use serde_norway::{Mapping, Value};

use crate::args::RosArgs;

/// A parameter that could not be read or does not fit the node's parameter struct.
#[derive(Debug, thiserror::Error)]
#[error("{origin}: {what}")]
pub struct ParamsError {
    /// Where the bad value came from: a file path (with line where known) or `-p KEY`.
    pub origin: String,
    /// What is wrong, naming the key.
    pub what: String,
}

/// Parameters merged from all sources, remembering where each key came from.
#[derive(Debug, Default, Clone)]
pub struct ParamSources {
    merged: Mapping,
    /// Dotted key path → origin description, for error messages.
    origins: HashMap<String, String>,
}

impl ParamSources {
    /// Collects the parameters that apply to node `name` in namespace `namespace` from the
    /// params files and `-p` overrides in `ros`.
    pub fn collect(ros: &RosArgs, namespace: &str, name: &str) -> Result<Self, ParamsError> {
        let mut sources = ParamSources::default();
        for path in &ros.params_files {
            sources.merge_file(path, namespace, name)?;
        }
        for (key, yaml) in &ros.params {
            let origin = format!("-p {key}");
            let value: Value = serde_norway::from_str(yaml).map_err(|e| ParamsError {
                origin: origin.clone(),
                what: format!("value {yaml:?} is not valid YAML: {e}"),
            })?;
            sources.insert_dotted(key, value, &origin);
        }
        Ok(sources)
    }

    /// Reads one ROS 2 params file and merges the sections that select this node.
    pub fn merge_file(
        &mut self,
        path: &Path,
        namespace: &str,
        name: &str,
    ) -> Result<(), ParamsError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ParamsError {
            origin: file.clone(),
            what: format!("cannot read params file: {e}"),
        })?;
        let doc: Value = cell_config::from_yaml_str(&text, &file).map_err(|e| ParamsError {
            origin: match e.line {
                Some(line) => format!("{file}:{line}"),
                None => file.clone(),
            },
            what: format!("not valid YAML: {}", e.message),
        })?;
        let Value::Mapping(sections) = doc else {
            return Err(ParamsError {
                origin: file,
                what: "expected a mapping of node names to `ros__parameters:`".into(),
            });
        };
        let fqn = fully_qualified(namespace, name);
        for (selector, section) in sections {
            let selector = selector.as_str().unwrap_or_default().to_string();
            if !selects(&selector, &fqn, name) {
                continue;
            }
            let Some(params) = section.get("ros__parameters") else {
                return Err(ParamsError {
                    origin: file,
                    what: format!("section `{selector}` has no `ros__parameters:` key"),
                });
            };
            if let Value::Mapping(extra) = &section {
                if let Some(other) = extra.keys().find(|k| k.as_str() != Some("ros__parameters")) {
                    return Err(ParamsError {
                        origin: file,
                        what: format!(
                            "section `{selector}`: unexpected key `{}` beside `ros__parameters`",
                            other.as_str().unwrap_or("?")
                        ),
                    });
                }
            }
            let Value::Mapping(params) = params.clone() else {
                return Err(ParamsError {
                    origin: file,
                    what: format!("section `{selector}`: `ros__parameters` must be a mapping"),
                });
            };
            let origin = format!("{file} (section `{selector}`)");
            for (key, value) in params {
                let key = key.as_str().unwrap_or_default().to_string();
                self.insert_dotted(&key, value, &origin);
            }
        }
        Ok(())
    }

    /// Sets `a.b.c` to `value`, creating nested mappings as ROS 2 does for dotted names.
    /// A mapping value is merged leaf by leaf, so a later source can override one nested key.
    fn insert_dotted(&mut self, key: &str, value: Value, origin: &str) {
        if let Value::Mapping(children) = value {
            if !children.is_empty() {
                for (child, v) in children {
                    let child = child.as_str().unwrap_or_default();
                    self.insert_dotted(&format!("{key}.{child}"), v, origin);
                }
                return;
            }
            return self.set_leaf(key, Value::Mapping(Mapping::new()), origin);
        }
        self.set_leaf(key, value, origin);
    }

    fn set_leaf(&mut self, key: &str, value: Value, origin: &str) {
        let mut map = &mut self.merged;
        let mut parts = key.split('.').peekable();
        while let Some(part) = parts.next() {
            let part = Value::String(part.to_string());
            if parts.peek().is_none() {
                map.insert(part, value);
                break;
            }
            let entry = map
                .entry(part)
                .or_insert_with(|| Value::Mapping(Mapping::new()));
            if !entry.is_mapping() {
                *entry = Value::Mapping(Mapping::new());
            }
            let Value::Mapping(next) = entry else {
                unreachable!("made a mapping above")
            };
            map = next;
        }
        self.origins.insert(key.to_string(), origin.to_string());
    }

    /// Removes the top-level key `key` (with everything below it) and returns its value and
    /// where it came from (the origin of one of its leaves: the first in key order).
    pub fn take(&mut self, key: &str) -> Option<(Value, String)> {
        let value = self.merged.remove(Value::String(key.to_string()))?;
        let below = format!("{key}.");
        let origin = self
            .origins
            .iter()
            .filter(|(k, _)| k.as_str() == key || k.starts_with(&below))
            .min_by(|a, b| a.0.cmp(b.0))
            .map(|(_, o)| o.clone())
            .unwrap_or_else(|| "parameters".to_string());
        self.origins
            .retain(|k, _| !(k.as_str() == key || k.starts_with(&below)));
        Some((value, origin))
    }

    /// The merged parameters as one YAML mapping.
    pub fn merged(&self) -> &Mapping {
        &self.merged
    }

    /// Deserializes the merged parameters into `T`; missing keys take `T`'s defaults when `T`
    /// uses `#[serde(default)]`. Errors name the source and the key.
    pub fn parse<T: DeserializeOwned>(&self) -> Result<T, ParamsError> {
        let value = Value::Mapping(self.merged.clone());
        serde_path_to_error::deserialize(value).map_err(|err| {
            let path = err.path().to_string();
            let message = err.inner().to_string();
            // serde_path_to_error's path already ends in an unknown field's name, except at
            // the top level, where it is ".".
            let key = match unknown_field_name(&message) {
                Some(field) if path == "." => field,
                _ => path,
            };
            let origin = self
                .origins
                .get(&key)
                .cloned()
                .unwrap_or_else(|| "parameters".to_string());
            ParamsError {
                origin,
                what: format!("parameter `{key}`: {message}"),
            }
        })
    }
}

/// Flattens a parameter tree into ROS 2 parameters (`a.b.c` names, ROS types). Lists of one
/// scalar type become typed arrays; what ROS 2 cannot type (nulls, mixed lists) is skipped.
pub fn flatten_for_ros(
    prefix: &str,
    value: &Value,
    out: &mut Vec<(String, ros2_client::ParameterValue)>,
) {
    use ros2_client::ParameterValue as P;
    let key = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    let scalar = |v: &Value| -> Option<P> {
        match v {
            Value::Bool(b) => Some(P::Boolean(*b)),
            Value::Number(n) if n.is_i64() => n.as_i64().map(P::Integer),
            Value::Number(n) => n.as_f64().map(P::Double),
            Value::String(s) => Some(P::String(s.clone())),
            _ => None,
        }
    };
    match value {
        Value::Mapping(map) => {
            for (k, v) in map {
                if let Some(k) = k.as_str() {
                    flatten_for_ros(&key(k), v, out);
                }
            }
        }
        Value::Sequence(items) => {
            if let Some(array) = items
                .iter()
                .map(scalar)
                .collect::<Option<Vec<P>>>()
                .and_then(typed_array)
            {
                out.push((prefix.to_string(), array));
            }
        }
        other => {
            if let Some(v) = scalar(other) {
                out.push((prefix.to_string(), v));
            }
        }
    }
}

/// One ROS 2 array parameter from scalars of one type (integers widen to doubles beside
/// doubles); `None` for a mix ROS 2 cannot type.
fn typed_array(items: Vec<ros2_client::ParameterValue>) -> Option<ros2_client::ParameterValue> {
    use ros2_client::ParameterValue as P;
    let all = |f: &dyn Fn(&P) -> bool| items.iter().all(f);
    Some(match items.first() {
        None => P::StringArray(Vec::new()),
        Some(P::Boolean(_)) if all(&|p| matches!(p, P::Boolean(_))) => P::BooleanArray(
            items
                .iter()
                .filter_map(|p| {
                    if let P::Boolean(b) = p {
                        Some(*b)
                    } else {
                        None
                    }
                })
                .collect(),
        ),
        Some(P::Integer(_)) if all(&|p| matches!(p, P::Integer(_))) => P::IntegerArray(
            items
                .iter()
                .filter_map(|p| {
                    if let P::Integer(i) = p {
                        Some(*i)
                    } else {
                        None
                    }
                })
                .collect(),
        ),
        Some(P::Integer(_) | P::Double(_))
            if all(&|p| matches!(p, P::Integer(_) | P::Double(_))) =>
        {
            P::DoubleArray(
                items
                    .iter()
                    .filter_map(|p| match p {
                        P::Double(d) => Some(*d),
                        P::Integer(i) => Some(*i as f64),
                        _ => None,
                    })
                    .collect(),
            )
        }
        Some(P::String(_)) if all(&|p| matches!(p, P::String(_))) => P::StringArray(
            items
                .iter()
                .filter_map(|p| {
                    if let P::String(s) = p {
                        Some(s.clone())
                    } else {
                        None
                    }
                })
                .collect(),
        ),
        _ => return None,
    })
}

fn unknown_field_name(message: &str) -> Option<String> {
    let rest = message.strip_prefix("unknown field `")?;
    Some(rest.split('`').next()?.to_string())
}

/// `/ns/name`, with a single slash for the root namespace.
pub fn fully_qualified(namespace: &str, name: &str) -> String {
    format!("{}/{name}", namespace.trim_end_matches('/'))
}

/// Whether a params-file section selector applies to a node (ROS 2 rules: `/**`, the bare
/// name, `/**/name`, or the fully qualified name).
fn selects(selector: &str, fqn: &str, name: &str) -> bool {
    let selector = selector.trim_end_matches('/');
    selector == "/**"
        || selector == name
        || selector == fqn
        || selector.strip_prefix("/**/") == Some(name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;
    use std::io::Write;

    #[derive(Debug, Deserialize, Default, PartialEq)]
    #[serde(deny_unknown_fields, default)]
    struct Params {
        rate_hz: f64,
        label: String,
        limits: Limits,
    }

    #[derive(Debug, Deserialize, Default, PartialEq)]
    #[serde(deny_unknown_fields, default)]
    struct Limits {
        max_current_a: f64,
    }

    fn file(text: &str) -> tempfile::NamedTempFile {
        let mut f = tempfile::Builder::new().suffix(".yaml").tempfile().unwrap();
        f.write_all(text.as_bytes()).unwrap();
        f
    }

    fn ros_with(files: &[&Path], params: &[(&str, &str)]) -> RosArgs {
        RosArgs {
            params_files: files.iter().map(|p| p.to_path_buf()).collect(),
            params: params
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
            ..Default::default()
        }
    }

    #[test]
    fn merges_sections_files_and_overrides_in_order() {
        let a = file(
            "/**:\n  ros__parameters:\n    rate_hz: 1.0\n    label: all\nother:\n  ros__parameters:\n    rate_hz: 9.0\n",
        );
        let b = file("/cell/mon:\n  ros__parameters:\n    label: mine\n    limits:\n      max_current_a: 4.5\n");
        let ros = ros_with(&[a.path(), b.path()], &[("rate_hz", "2.5")]);
        let p: Params = ParamSources::collect(&ros, "/cell", "mon")
            .unwrap()
            .parse()
            .unwrap();
        assert_eq!(
            p,
            Params {
                rate_hz: 2.5,
                label: "mine".into(),
                limits: Limits { max_current_a: 4.5 }
            }
        );
        let dotted = ros_with(&[], &[("limits.max_current_a", "3")]);
        let p: Params = ParamSources::collect(&dotted, "/", "mon")
            .unwrap()
            .parse()
            .unwrap();
        assert_eq!(p.limits.max_current_a, 3.0);
    }

    #[test]
    fn parameters_flatten_to_ros_types() {
        use ros2_client::ParameterValue as P;
        let text = "rate_hz: 2.5\nlabel: x\ncount: 3\non: true\nlimits: {max_current_a: 4.0}\n\
                    xs: [1.0, 2]\nnames: [a, b]\nnothing: null\nmixed: [1, a]\n";
        let v: Value = serde_norway::from_str(text).unwrap();
        let mut out = Vec::new();
        flatten_for_ros("", &v, &mut out);
        let get = |k: &str| out.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
        assert_eq!(get("rate_hz"), Some(P::Double(2.5)));
        assert_eq!(get("label"), Some(P::String("x".into())));
        assert_eq!(get("count"), Some(P::Integer(3)));
        assert_eq!(get("on"), Some(P::Boolean(true)));
        assert_eq!(get("limits.max_current_a"), Some(P::Double(4.0)));
        assert_eq!(get("xs"), Some(P::DoubleArray(vec![1.0, 2.0])));
        assert_eq!(
            get("names"),
            Some(P::StringArray(vec!["a".into(), "b".into()]))
        );
        assert_eq!(get("nothing"), None);
        assert_eq!(get("mixed"), None);
    }

    #[test]
    fn unknown_key_names_file_and_key() {
        let f = file("mon:\n  ros__parameters:\n    rate_hz: 1.0\n    rate_hzz: 2.0\n");
        let ros = ros_with(&[f.path()], &[]);
        let err = ParamSources::collect(&ros, "/", "mon")
            .unwrap()
            .parse::<Params>()
            .unwrap_err();
        let text = err.to_string();
        assert!(text.contains(&f.path().display().to_string()), "{text}");
        assert!(text.contains("parameter `rate_hzz`"), "{text}");
        assert!(text.contains("unknown field"), "{text}");
    }

    #[test]
    fn mistyped_value_names_key_and_source() {
        let f = file("/**:\n  ros__parameters:\n    limits: {max_current_a: lots}\n");
        let ros = ros_with(&[f.path()], &[]);
        let err = ParamSources::collect(&ros, "/", "mon")
            .unwrap()
            .parse::<Params>()
            .unwrap_err();
        assert!(
            err.to_string().contains("parameter `limits.max_current_a`"),
            "{err}"
        );
        assert!(
            err.to_string().contains(&f.path().display().to_string()),
            "{err}"
        );
        let ros = ros_with(&[], &[("rate_hz", "fast")]);
        let err = ParamSources::collect(&ros, "/", "mon")
            .unwrap()
            .parse::<Params>()
            .unwrap_err();
        assert!(
            err.to_string()
                .starts_with("-p rate_hz: parameter `rate_hz`"),
            "{err}"
        );
    }

    #[test]
    fn malformed_files_are_errors_with_location() {
        let f = file("mon:\n  ros__parameters:\n    rate_hz: [1,\n");
        let err = ParamSources::collect(&ros_with(&[f.path()], &[]), "/", "mon").unwrap_err();
        assert!(
            err.origin.starts_with(&f.path().display().to_string()),
            "{err}"
        );
        let f = file("mon:\n  rate_hz: 1\n");
        let err = ParamSources::collect(&ros_with(&[f.path()], &[]), "/", "mon").unwrap_err();
        assert!(err.to_string().contains("no `ros__parameters:`"), "{err}");
        let missing = Path::new("/nonexistent/params.yaml");
        let err = ParamSources::collect(&ros_with(&[missing], &[]), "/", "mon").unwrap_err();
        assert!(
            err.to_string()
                .contains("/nonexistent/params.yaml: cannot read"),
            "{err}"
        );
    }
}
