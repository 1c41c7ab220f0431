//! Live preview: while a job runs, the exposure of the best path so far, handed out at most
//! once per period.

use std::time::Instant;

use cell_msgs::HeatMap;

use crate::pso::Problem;

use super::views::{heat_map, profile_map};

/// How often [`plan_observed`](super::plan_observed) hands out the current best's heat maps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveOptions {
    /// Least time between two updates (default 1 s); `None`: only the baselines.
    pub period: Option<std::time::Duration>,
}

impl Default for LiveOptions {
    fn default() -> Self {
        Self {
            period: Some(std::time::Duration::from_secs(1)),
        }
    }
}

/// The current best path's exposure while planning ([`plan_observed`](super::plan_observed)).
#[derive(Debug, Clone, PartialEq)]
pub struct LiveMaps {
    /// Iterations done when it was computed (0: the baseline).
    pub iteration: usize,
    /// 1 × N exposure profile (`exposure_profile`).
    pub profile: HeatMap,
    /// M × N wire × panel contributions (`wire_exposure`).
    pub matrix: HeatMap,
}

/// Rate-limited producer of [`LiveMaps`].
pub(super) struct Live<'a, F> {
    pub(super) options: &'a LiveOptions,
    pub(super) last: Option<Instant>,
    pub(super) sink: F,
}

impl<F: FnMut(LiveMaps)> Live<'_, F> {
    pub(super) fn due(&self) -> bool {
        match (self.options.period, self.last) {
            (None, _) => false,
            (Some(_), None) => true,
            (Some(p), Some(t)) => t.elapsed() >= p,
        }
    }

    /// Computes and hands out the maps of `controls` (skipped if the path is degenerate).
    pub(super) fn show(
        &mut self,
        problem: &Problem,
        controls: &[f64],
        iteration: usize,
        frame: &str,
    ) {
        let model = problem.objective().model;
        let (Ok(exposure), Ok((rows, cols, values))) = (
            problem.exposure(controls),
            problem.exposure_matrix(controls),
        ) else {
            return;
        };
        let mut profile = profile_map(model, problem.cse(), &exposure);
        let mut matrix = heat_map(model, problem.cse(), "wire_exposure", cols, rows, values);
        profile.header.frame_id = frame.into();
        matrix.header.frame_id = frame.into();
        self.last = Some(Instant::now());
        (self.sink)(LiveMaps {
            iteration,
            profile,
            matrix,
        });
    }
}
