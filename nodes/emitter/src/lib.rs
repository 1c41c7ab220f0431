//! The `emitter` node: `Toolpath`s in, `MachineProgram`s out. The ROS adapter over
//! [`cell_emitter::emit_program`].
//!
//! - Subscribes to `input_topic` (default `toolpath`, where the planner publishes) and, for
//!   each `Toolpath`, emits a program for the `machine_profile` parameter's profile, publishes
//!   it on `output_topic` (default `machine_program`; both QoS `Plan`: reliable,
//!   transient-local) and, when `output_dir` is set, writes its files there atomically.
//! - Serves `emit_program` (`cell_msgs/srv/EmitProgram`): the request carries the toolpath and,
//!   optionally, a profile (a name or a YAML path; empty: the node's) and a job id; the response
//!   carries the program or why there is none. With `publish` set, the program is also
//!   published and written as for a toolpath received on the topic.
//! - A toolpath the emitter refuses (a NaN or infinite value, a feed ≤ 0, a position outside
//!   the machine's travel, an axis the machine lacks) or an unknown profile gives one line that
//!   names the job and, where it applies, the segment and point: logged for the topic, answered
//!   for the service. Nothing is published or written, and the node keeps running.
//!
//! The job id of a program is the request's, else the toolpath's, else `program-N` (N counts
//! the toolpaths the node has handled). Each program and each refusal is also logged to Rerun
//! as a text entry on `/emitter/log`.
//!
//! The `machine_profile` parameter is read (and, for a path, the file loaded) at start-up; a
//! profile named in a request is resolved for that request, a path only to a regular file
//! under `data_dirs` within `max_file_mib` ([`cell_runtime::data_files`]), and the answer
//! never quotes the file.

use std::{path::PathBuf, sync::Arc};

use anyhow::{bail, Context as _};
use cell_msgs::{EmitProgramRequest, EmitProgramResponse, MachineProgram, Toolpath};
use cell_profiles::MachineProfile;
use cell_runtime::data_files::{self, DataDirs};
use cell_runtime::{CellNode, NodeParamError, Publisher, QosPreset};
use serde::{Deserialize, Serialize};

/// The Rerun entity the node logs each program and each refusal to.
pub const RERUN_LOG: &str = "/emitter/log";

/// The service the node serves (resolved against its namespace and remappings).
pub const SERVICE: &str = "emit_program";

/// Parameters (ROS 2 YAML under `ros__parameters:` or `-p key:=value`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct EmitterParams {
    /// Machine profile for toolpaths from the topic and for requests that name none: a name
    /// under `config/machines` or a path to a profile YAML. It must have a `gcode` or a
    /// `rapid` section.
    pub machine_profile: String,
    /// Topic the toolpaths come in on.
    pub input_topic: String,
    /// Topic the programs go out on.
    pub output_topic: String,
    /// Directory to write each published program's files to (created if missing); empty: do
    /// not write files.
    pub output_dir: String,
    /// Directories a profile path in a request must lie in (relative: to the working
    /// directory); see `cell_runtime::data_files`.
    pub data_dirs: Vec<String>,
    /// Largest profile file a request may name, MiB.
    pub max_file_mib: u64,
}

impl Default for EmitterParams {
    fn default() -> Self {
        Self {
            machine_profile: "linuxcnc-xyuv".into(),
            input_topic: "toolpath".into(),
            output_topic: "machine_program".into(),
            output_dir: String::new(),
            data_dirs: data_files::default_data_dirs(),
            max_file_mib: data_files::DEFAULT_MAX_FILE_MIB,
        }
    }
}

/// The job id of a program: `requested`, else the toolpath's, else `program-{count}`.
pub fn job_id(requested: &str, toolpath: &Toolpath, count: u64) -> String {
    [requested, toolpath.job_id.as_str()]
        .into_iter()
        .find(|s| !s.is_empty())
        .map_or_else(|| format!("program-{count}"), str::to_owned)
}

/// The node's state between messages.
struct Emitter {
    node: CellNode,
    profile_name: String,
    profile: Arc<MachineProfile>,
    data_dirs: Arc<DataDirs>,
    output_dir: Option<PathBuf>,
    programs: Publisher<MachineProgram>,
    handled: u64,
}

impl Emitter {
    /// Emits on a blocking thread (a named profile may be a file to read; a long toolpath takes
    /// a while). An empty `profile` is the node's. Errors are one line naming the job.
    async fn emit(
        &self,
        toolpath: Toolpath,
        profile: String,
        job_id: String,
    ) -> Result<MachineProgram, String> {
        let default =
            (profile.is_empty() || profile == self.profile_name).then(|| self.profile.clone());
        let now = self.node.now();
        let data_dirs = self.data_dirs.clone();
        tokio::task::spawn_blocking(move || {
            let profile = match default {
                Some(p) => p,
                None => Arc::new(
                    data_dirs
                        .machine_profile("machine_profile", &profile)
                        .map_err(|e| format!("job {job_id}: {e}"))?,
                ),
            };
            let mut program = cell_emitter::emit_program(&toolpath, &profile, &job_id)
                .map_err(|e| format!("job {job_id}: {e}"))?;
            program.header.stamp = now;
            Ok(program)
        })
        .await
        .map_err(|e| format!("emitter thread: {e}"))?
    }

    /// Writes the program's files to `output_dir` (if set), publishes it and logs it. Returns
    /// a note if the files could not be written (the program is published regardless).
    async fn deliver(&self, program: MachineProgram) -> Option<String> {
        let mut note = None;
        if let Some(dir) = self.output_dir.clone() {
            let p = program.clone();
            let written = tokio::task::spawn_blocking(move || {
                cell_emitter::program::write_files(&p, &dir, None)
            })
            .await;
            match written {
                Ok(Ok(paths)) => tracing::debug!("job {}: wrote {paths:?}", program.job_id),
                Ok(Err(e)) => note = Some(format!("not written: {e}")),
                Err(e) => note = Some(format!("not written: writer thread: {e}")),
            }
        }
        if let Some(n) = &note {
            tracing::warn!("job {}: {n}", program.job_id);
        }
        let summary = cell_emitter::program::summary(&program);
        let sink = self.node.rerun();
        sink.set_time(&program.header.stamp, self.handled as i64);
        sink.log_text(RERUN_LOG, &summary);
        match self.programs.publish(program).await {
            Ok(()) => tracing::info!("{}: {summary}", self.programs.topic()),
            Err(e) => tracing::warn!("{summary}: {e:#}"),
        }
        note
    }

    /// Logs a refused toolpath or request.
    fn refuse(&self, source: &str, why: &str) {
        tracing::warn!("{source}: refused: {why}");
        self.node
            .rerun()
            .log_text(RERUN_LOG, &format!("refused ({source}): {why}"));
    }

    /// A toolpath from the input topic.
    async fn on_toolpath(&mut self, source: &str, toolpath: Toolpath) {
        self.handled += 1;
        let job_id = job_id("", &toolpath, self.handled);
        match self.emit(toolpath, String::new(), job_id).await {
            Ok(program) => {
                self.deliver(program).await;
            }
            Err(why) => self.refuse(source, &why),
        }
    }

    /// An `emit_program` request.
    async fn on_request(
        &mut self,
        source: &str,
        request: EmitProgramRequest,
    ) -> EmitProgramResponse {
        self.handled += 1;
        let job_id = job_id(&request.job_id, &request.toolpath, self.handled);
        let program = match self
            .emit(request.toolpath, request.machine_profile, job_id)
            .await
        {
            Ok(program) => program,
            Err(why) => {
                self.refuse(source, &why);
                return EmitProgramResponse {
                    success: false,
                    message: why,
                    program: MachineProgram::default(),
                };
            }
        };
        let mut message = cell_emitter::program::summary(&program);
        if request.publish {
            if let Some(note) = self.deliver(program.clone()).await {
                message = format!("{message}; {note}");
            }
        } else {
            tracing::info!("{source}: {message}");
        }
        EmitProgramResponse {
            success: true,
            message,
            program,
        }
    }
}

/// Emits programs and serves `emit_program` until shutdown.
///
/// # Errors
/// At start-up: a `machine_profile` that does not resolve or takes no programs (a
/// [`NodeParamError`]: exit status 64), an `output_dir` that cannot be created, topics or the
/// service that cannot be set up.
pub async fn run(node: CellNode, p: EmitterParams) -> anyhow::Result<()> {
    let profile = MachineProfile::resolve(&p.machine_profile)
        .map_err(|e| NodeParamError(format!("machine_profile: {e}")))?;
    if profile.gcode.is_none() && profile.rapid.is_none() {
        return Err(NodeParamError(format!(
            "machine_profile: {:?} has no gcode or rapid section, so no program can be written for it",
            p.machine_profile
        ))
        .into());
    }
    let output_dir = (!p.output_dir.is_empty()).then(|| PathBuf::from(&p.output_dir));
    if let Some(dir) = &output_dir {
        std::fs::create_dir_all(dir).with_context(|| format!("output_dir {}", dir.display()))?;
    }
    let mut toolpaths = node.subscriber::<Toolpath>(&p.input_topic, QosPreset::Plan)?;
    let programs = node.publisher::<MachineProgram>(&p.output_topic, QosPreset::Plan)?;
    let server = node.service_server::<EmitProgramRequest, EmitProgramResponse>(SERVICE)?;
    tracing::info!(
        "emitting {} -> {} for {}; serving {}",
        toolpaths.topic(),
        programs.topic(),
        profile.name,
        server.name()
    );
    let input = toolpaths.topic().to_owned();
    let service = server.name().to_owned();
    let mut emitter = Emitter {
        node: node.clone(),
        profile_name: p.machine_profile.clone(),
        profile: Arc::new(profile),
        data_dirs: Arc::new(DataDirs::from_params(&p.data_dirs, p.max_file_mib)),
        output_dir,
        programs,
        handled: 0,
    };
    loop {
        tokio::select! {
            received = toolpaths.recv() => {
                let Some(received) = received else {
                    bail!("{input}: the subscription ended");
                };
                emitter.on_toolpath(&input, received.message).await;
            }
            (id, request) = server.receive() => {
                let response = emitter.on_request(&service, request).await;
                if let Err(e) = server.respond(id, response).await {
                    tracing::warn!("{e:#}");
                }
            }
            _ = node.shutdown().requested() => return Ok(()),
        }
    }
}

/// The `emitter` binary (also `cell node emitter`).
pub fn main(argv: Vec<String>) -> std::process::ExitCode {
    cell_runtime::run_node("emitter", argv, run)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_params_file_parses_and_matches_the_defaults() {
        let mut sources = cell_runtime::params::ParamSources::default();
        let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../../config/emitter.yaml");
        sources
            .merge_file(std::path::Path::new(file), "/", "emitter")
            .unwrap();
        let p: EmitterParams = sources.parse().unwrap();
        assert_eq!(p, EmitterParams::default());
    }

    #[test]
    fn job_ids_come_from_the_request_then_the_toolpath() {
        let mut toolpath = Toolpath::default();
        assert_eq!(job_id("", &toolpath, 3), "program-3");
        toolpath.job_id = "wing-1".into();
        assert_eq!(job_id("", &toolpath, 3), "wing-1");
        assert_eq!(job_id("rerun-2", &toolpath, 3), "rerun-2");
    }
}
