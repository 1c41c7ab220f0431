//! The improvement's knobs ([`ImproveParams`]) and their checks.

use serde::{Deserialize, Serialize};

use crate::thermal::{require, SequencerParamError};

// Limits of the knobs (issue 23: a goal's or a parameter file's number must not buy an hour
// of CPU or an overflow); each is far above what helps (benches README).

/// Most LNS iterations: 100× the default; each costs up to a few ms on a 500-part sheet.
pub const MAX_IMPROVE_ITERATIONS: usize = 100_000;
/// Farthest reach of local moves, positions: 40× the default (a sweep is O(n · window)).
pub const MAX_WINDOW: usize = 1_000;
/// Longest Or-opt run: a sweep is O(n · or_opt_max_len · window); the default is 3.
pub const MAX_OR_OPT_LEN: usize = 50;
/// Most local-search sweeps per round: 25× the default 4.
pub const MAX_LOCAL_SWEEPS: usize = 100;
/// Most cuts removed per LNS iteration (reinsertion is O(lns_remove · n)): 125× the default 8.
pub const MAX_LNS_REMOVE: usize = 1_000;

/// Knobs of the improvement phase (module docs). Defaults are ours.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImproveParams {
    /// LNS iterations. Default 1000.
    pub max_iterations: usize,
    /// Wall-clock budget, ms; 0 = none (then the result is deterministic). Default 0.
    pub time_budget_ms: u64,
    /// RNG seed. Default 0.
    pub seed: u64,
    /// Longest run Or-opt moves. Default 3.
    pub or_opt_max_len: usize,
    /// How far (positions) local moves reach. Default 25.
    pub window: usize,
    /// Local-search sweeps at the start and after each accepted LNS step. Default 4.
    pub local_sweeps: usize,
    /// Cuts removed per LNS iteration. Default 8.
    pub lns_remove: usize,
    /// Heat proxy radius: check points of a contour this close to an earlier contour's
    /// polyline are exposed to its heat, mm. Default 14 (benches README: at 30 the proxy
    /// counts a dense perforation's whole neighbourhood as exposed and the search spends the
    /// idle budget on the wrong moves).
    pub proxy_radius_mm: f64,
    /// Heat proxy half-life, mm of cutting in between. Default 150.
    pub proxy_half_life_mm: f64,
    /// Heat proxy look-back, cuts. Default 8.
    pub proxy_lookback: usize,
    /// Heat proxy weight, fraction of `w_overheat_mm`. Default 0.5: the proxy over-counts, and
    /// at 1 the search trades too much idle travel for it (benches README).
    pub proxy_weight: f64,
    /// Idle budget with thermal cost on, a multiple of the nearest-neighbour idle length of
    /// the same problem (issue 7 target: ≤ 1.5×): a move that leaves the idle length above it
    /// is only taken if it shortens idle travel. 0 = no budget. Default 1.5.
    #[serde(default = "default_idle_budget")]
    pub idle_budget: f64,
}

fn default_idle_budget() -> f64 {
    1.5
}

impl Default for ImproveParams {
    fn default() -> Self {
        ImproveParams {
            max_iterations: 1000,
            time_budget_ms: 0,
            seed: 0,
            or_opt_max_len: 3,
            window: 25,
            local_sweeps: 4,
            lns_remove: 8,
            proxy_radius_mm: 14.0,
            proxy_half_life_mm: 150.0,
            proxy_lookback: 8,
            proxy_weight: 0.5,
            idle_budget: default_idle_budget(),
        }
    }
}

impl ImproveParams {
    /// Checks every field.
    ///
    /// # Errors
    /// The first field out of range, by name.
    pub fn validate(&self) -> Result<(), SequencerParamError> {
        require(
            self.max_iterations <= MAX_IMPROVE_ITERATIONS,
            "max_iterations",
            self.max_iterations,
            "must be in [0, 100000] (MAX_IMPROVE_ITERATIONS)",
        )?;
        require(
            (1..=MAX_OR_OPT_LEN).contains(&self.or_opt_max_len),
            "or_opt_max_len",
            self.or_opt_max_len,
            "must be in [1, 50] (MAX_OR_OPT_LEN)",
        )?;
        require(
            (1..=MAX_WINDOW).contains(&self.window),
            "window",
            self.window,
            "must be in [1, 1000] (MAX_WINDOW)",
        )?;
        require(
            self.local_sweeps <= MAX_LOCAL_SWEEPS,
            "local_sweeps",
            self.local_sweeps,
            "must be in [0, 100] (MAX_LOCAL_SWEEPS)",
        )?;
        require(
            self.lns_remove <= MAX_LNS_REMOVE,
            "lns_remove",
            self.lns_remove,
            "must be in [0, 1000] (MAX_LNS_REMOVE)",
        )?;
        require(
            self.proxy_radius_mm.is_finite() && self.proxy_radius_mm > 0.0,
            "proxy_radius_mm",
            self.proxy_radius_mm,
            "must be finite and > 0",
        )?;
        require(
            self.proxy_lookback <= 16,
            "proxy_lookback",
            self.proxy_lookback,
            "must be ≤ 16",
        )?;
        require(
            self.proxy_weight.is_finite() && self.proxy_weight >= 0.0,
            "proxy_weight",
            self.proxy_weight,
            "must be finite and ≥ 0",
        )?;
        require(
            self.idle_budget.is_finite() && (self.idle_budget == 0.0 || self.idle_budget >= 1.0),
            "idle_budget",
            self.idle_budget,
            "must be 0 (none) or ≥ 1",
        )?;
        Ok(())
    }
}
