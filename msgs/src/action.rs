//! Parts of the `cell_msgs/action/*` actions (goal, result, feedback), mirroring
//! `msgs/action/*.action` section by section.

use serde::{Deserialize, Serialize};

use crate::{CutPlan, LayerStack, MachineProgram, Toolpath};

/// Goal of `PlanHotwire`: plan a hot-wire cut of a (possibly tapered) wing panel (Swarm-Cut
/// exposure-optimised trajectory with the kerf model).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct PlanHotwireGoal {
    /// Job identifier, carried into the Toolpath.
    pub job_id: String,
    /// Root airfoil: a name under config/airfoils (e.g. "s1223") or a path to a UIUC .dat file.
    pub root_airfoil: String,
    /// Tip airfoil; empty means the same as the root.
    pub tip_airfoil: String,
    /// Root chord \[mm\].
    pub root_chord_mm: f64,
    /// Tip chord \[mm\]; 0 means the same as the root.
    pub tip_chord_mm: f64,
    /// Tip twist about the pivot \[deg\], positive nose up.
    pub tip_twist_deg: f64,
    /// Leading-edge sweep of the tip relative to the root \[mm\].
    pub tip_sweep_mm: f64,
    /// Panel span between root and tip \[mm\].
    pub span_mm: f64,
    /// Material name from the material library (e.g. "EPS", "XPS", "EPP").
    pub material: String,
    /// Critical specific energy target (normalised exposure units); 0 = material default.
    pub cse: f64,
    /// Machine profile under config/machines.
    pub machine_profile: String,
    /// PSO iterations; 0 = the paper's default (8000).
    pub iterations: u32,
    /// RNG seed; the same seed gives the same toolpath.
    pub seed: u64,
}

/// Result of `PlanHotwire`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct PlanHotwireResult {
    /// Whether planning succeeded.
    pub success: bool,
    /// Why it failed, or a one-line summary on success.
    pub message: String,
    /// The planned toolpath.
    pub toolpath: Toolpath,
    /// Mean squared exposure error of the optimised path.
    pub final_loss: f64,
    /// Mean squared exposure error of the fixed-offset baseline.
    pub baseline_loss: f64,
}

/// Feedback of `PlanHotwire`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct PlanHotwireFeedback {
    /// Current optimiser iteration.
    pub iteration: u32,
    /// Iterations planned in total.
    pub total_iterations: u32,
    /// Best loss so far.
    pub best_loss: f64,
    /// Estimated time to completion \[s\].
    pub eta_s: f64,
}

/// Goal of `ExecuteProgram`: stream a machine program to a controller and follow it to
/// completion.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct ExecuteProgramGoal {
    /// The program to run.
    pub program: MachineProgram,
    /// Target controller (an id under `config/controllers`); empty = the controller configured
    /// for the program's `machine_profile`, else the bridge's default controller.
    pub machine_id: String,
    /// Original line number (of the program's first file, 1-based) to start from; 0 = the
    /// first line. Resuming after a stop: the operator-confirmed line, usually the result's
    /// `last_acked_line + 1`.
    pub start_line: u32,
}

/// Result of `ExecuteProgram`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct ExecuteProgramResult {
    /// Whether the program ran to completion.
    pub success: bool,
    /// Why it failed, or a summary on success.
    pub message: String,
    /// Final controller state (one of `MachineStatus::STATE_*`).
    pub final_state: u8,
    /// One of `OUTCOME_*`.
    pub outcome: u8,
    /// The line the outcome concerns: the rejected line, or the last acknowledged line; 0 =
    /// none.
    pub line: u32,
    /// Last line the controller acknowledged (original numbering); 0 = none.
    pub last_acked_line: u32,
    /// Link drops survived by reconnecting and resuming during this goal.
    pub reconnects: u32,
}

impl ExecuteProgramResult {
    /// Every line ran.
    pub const OUTCOME_FINISHED: u8 = 0;
    /// Stopped by a cancel, an abort command or shutdown.
    pub const OUTCOME_ABORTED: u8 = 1;
    /// The controller raised an alarm.
    pub const OUTCOME_ALARM: u8 = 2;
    /// The controller rejected a line (`error:N`); `line` names it.
    pub const OUTCOME_REJECTED_LINE: u8 = 3;
    /// The link was lost and not resumed.
    pub const OUTCOME_LINK_LOST: u8 = 4;
    /// Refused before anything was sent (wrong dialect or machine, unknown controller, busy).
    pub const OUTCOME_REFUSED: u8 = 5;
}

/// Feedback of `ExecuteProgram`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct ExecuteProgramFeedback {
    /// Last program line the controller acknowledged.
    pub acked_line: u32,
    /// Lines in the program.
    pub total_lines: u32,
    /// Controller state (one of `MachineStatus::STATE_*`).
    pub state: u8,
    /// Acknowledged share of the program, 0..100.
    pub percent_done: f32,
}

/// Goal of `SequenceSheet`: order the contours of a nested sheet, choose pierce points,
/// simulate the heating and improve the order within the connectivity rules (seed 003).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct SequenceSheetGoal {
    /// Job identifier, carried into the CutPlan and the Toolpath.
    pub job_id: String,
    /// A layout file the sequencer can read (.dxf or .json), or, if empty, `layout_json`.
    pub layout_file: String,
    /// The layout in the sequencer's own JSON format.
    pub layout_json: String,
    /// Precedence rules: "strict" or "relaxed"; empty = strict.
    pub precedence: String,
    /// Pierce points: "fixed" or "free"; empty = free.
    pub pierce: String,
    /// Construction policy: nearest, min_overheat, random, path_overheat, cost_greedy; empty =
    /// the sequencer's `policy` parameter (default nearest).
    pub policy: String,
    /// Run the improvement phase after the construction.
    pub improve: bool,
    /// Time budget for the improvement phase \[s\]; 0 = the sequencer's default.
    pub time_budget_s: f64,
    /// Machine profile under config/machines (cut and rapid speeds, dialect).
    pub machine_profile: String,
    /// RNG seed; the same seed gives the same plan.
    pub seed: u64,
}

/// Result of `SequenceSheet`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct SequenceSheetResult {
    /// Whether sequencing succeeded.
    pub success: bool,
    /// Why it failed (naming the file, entity or field), or a one-line summary on success.
    pub message: String,
    /// The cut order and its metrics.
    pub plan: CutPlan,
    /// Cut and travel segments with pierce markers, for the emitter.
    pub toolpath: Toolpath,
}

/// Feedback of `SequenceSheet`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct SequenceSheetFeedback {
    /// Construction or improvement.
    pub phase: String,
    /// Iteration of the phase.
    pub iteration: u32,
    /// Cost of the best plan so far.
    pub best_cost: f64,
    /// Its idle length \[mm\].
    pub best_idle_length_mm: f64,
    /// Its overheats.
    pub best_overheats: u32,
}

/// Goal of `Slice`: slice a part for wire-arc additive manufacturing (seed 004): mesh → layer
/// contours → bead toolpath, with the deposited volume, times and cost; or print one section
/// of a G-Wing wing (seed 002): perimeters and spars with extrusion flow.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct SliceGoal {
    /// Job identifier, carried into the LayerStack and the Toolpath.
    pub job_id: String,
    /// The part as an STL file (ASCII or binary, mm). Exactly one of `stl_file` and
    /// `wing_spec_file`.
    pub stl_file: String,
    /// A wing spec (cell_wing YAML, seed 002): the slicer designs the wing and prints one
    /// section.
    pub wing_spec_file: String,
    /// With `wing_spec_file`: which section, an index into the design's sections (0 = the
    /// centre section).
    pub wing_section: u32,
    /// WAAM process profile (YAML, cell_waam format); empty = the built-in
    /// `config/processes/waam.yaml`.
    pub process_file: String,
    /// Layer height \[mm\]; 0 = the process profile's.
    pub layer_height_mm: f64,
    /// Machine profile under config/machines (or a YAML path); empty = the slicer's default.
    pub machine_profile: String,
}

/// Result of `Slice`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct SliceResult {
    /// Whether slicing succeeded.
    pub success: bool,
    /// Why it failed (naming the file and field), or a one-line summary on success.
    pub message: String,
    /// The layer contours.
    pub layer_stack: LayerStack,
    /// Deposit and travel segments, for the emitter.
    pub toolpath: Toolpath,
    /// The report as JSON: layers, contours, deposited volume, times, cost breakdown, mesh
    /// report.
    pub report_json: String,
}

/// Feedback of `Slice`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct SliceFeedback {
    /// `load`, `slice`, `plan` (per layer) or `done`.
    pub phase: String,
    /// Layers planned so far.
    pub layers_done: u32,
    /// Layers in the stack.
    pub layers_total: u32,
}
