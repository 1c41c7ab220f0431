//! An operator's resume from a line after the first: the controller, reset by the stop that
//! ended the earlier run, is put back into the state the program had at that line (units,
//! distance, plane, work offset, feed mode and F, heat with its S, pierce height; see
//! [`cell_grbl::resume`]) before the line is streamed. The bridge's own resume after a link drop
//! inside a run does not come here: that controller kept its state.

use std::sync::atomic::Ordering;

use cell_grbl::program::Program;
use cell_grbl::resume::preamble;
use cell_grbl::stream::GrblClient;
use cell_msgs::{ExecuteProgramResult as R, MachineStatus};

use super::GrblController;
use crate::controller::RunOutcome;

impl GrblController {
    /// Why `program` cannot be resumed from `from`, as an operator-facing message.
    pub(super) fn resume_refusal(&self, program: &Program, from: usize) -> Option<String> {
        preamble(program, from)
            .err()
            .map(|e| format!("cannot resume from line {from}: {e}"))
    }

    /// Sends the preamble for a resume from `from` (nothing when `from` is the first line), each
    /// line acknowledged before the next. A refused line ends in the safe stop (the preamble
    /// may have switched the heat on); an abort (which runs the safe stop itself) ends it too.
    /// Preamble lines are not program lines: the line accounting starts at `from`.
    pub(super) async fn restore_state(
        &self,
        client: &GrblClient,
        program: &Program,
        from: usize,
    ) -> Result<(), RunOutcome> {
        let id = &self.cfg.id;
        let lines = preamble(program, from).map_err(|e| {
            RunOutcome::refused(
                format!("{id}: cannot resume from line {from}: {e}"),
                self.state_now(),
            )
        })?;
        if lines.is_empty() {
            return Ok(());
        }
        tracing::info!(
            "{id}: resuming at line {from}; restoring the program's state there: {}",
            lines.join(" | ")
        );
        let stopped = |outcome: u8, message: String| RunOutcome {
            success: false,
            outcome,
            message,
            line: from as u32,
            last_acked_line: 0,
            reconnects: 0,
            final_state: MachineStatus::STATE_UNKNOWN,
        };
        let aborted = || self.abort_requested.load(Ordering::SeqCst);
        let abort_outcome = || {
            stopped(
                R::OUTCOME_ABORTED,
                format!("{id}: aborted while restoring the state for line {from}"),
            )
        };
        for line in &lines {
            if aborted() {
                return Err(abort_outcome());
            }
            if let Err(e) = client.command(line).await {
                if aborted() {
                    return Err(abort_outcome());
                }
                let stop = client.safe_stop().await;
                return Err(stopped(
                    R::OUTCOME_REJECTED_LINE,
                    format!(
                        "{id}: restoring the state for line {from}: `{line}`: {e}; {}",
                        stop.summary()
                    ),
                ));
            }
        }
        if aborted() {
            return Err(abort_outcome());
        }
        Ok(())
    }
}
