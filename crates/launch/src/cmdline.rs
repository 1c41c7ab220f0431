//! Turning a node into a ROS 2 command line.

use crate::file::{NodeSpec, Param};

impl NodeSpec {
    /// The arguments after the executable, ROS 2 style:
    ///
    /// `ARGS... --ros-args -r __node:=NAME -r __ns:=NS -p KEY:=VALUE...
    /// --params-file FILE... -r FROM:=TO...`
    ///
    /// `ARGS` are the words of `args`. Values are YAML (see
    /// [`ParamValue::to_yaml`](crate::ParamValue::to_yaml)); no shell is
    /// involved, so nothing is shell-quoted. `--ros-args` is left out when
    /// the node has no name, namespace, parameter or remapping.
    pub fn command_args(&self) -> Vec<String> {
        let mut ros = Vec::new();
        if let Some(name) = &self.name {
            ros.extend(["-r".to_string(), format!("__node:={name}")]);
        }
        if let Some(ns) = &self.namespace {
            ros.extend(["-r".to_string(), format!("__ns:={ns}")]);
        }
        for param in &self.params {
            if let Param::Value { name, value } = param {
                ros.extend(["-p".to_string(), format!("{name}:={}", value.to_yaml())]);
            }
        }
        for param in &self.params {
            if let Param::File(path) = param {
                ros.extend(["--params-file".to_string(), path.display().to_string()]);
            }
        }
        for remap in &self.remaps {
            ros.extend(["-r".to_string(), format!("{}:={}", remap.from, remap.to)]);
        }
        let mut argv = self.args.clone();
        if !ros.is_empty() {
            argv.push("--ros-args".to_string());
            argv.extend(ros);
        }
        argv
    }
}
