//! Local search to a local optimum (module docs, step 1): the neighbour-list sweeps without the
//! heat proxy, then the window sweeps.

use super::params::ImproveParams;
use super::search::Search;

impl Search<'_, '_> {
    /// Local search to a local optimum (module docs, step 1): from every position if `full`,
    /// else from those whose don't-look bits are set.
    pub(super) fn local_search(
        &mut self,
        params: &ImproveParams,
        full: bool,
        deadline: &dyn Fn() -> bool,
    ) {
        if deadline() {
            return;
        }
        if full {
            self.wake_all();
        }
        if self.proxy_w == 0.0 {
            // Idle cost only: neighbour-list moves with O(1) deltas, to a local optimum.
            for _ in 0..params.local_sweeps * 8 {
                if !self.neighbour_sweep() || deadline() {
                    break;
                }
            }
        }
        self.idle = self.span_idle(0, self.seq.len().saturating_sub(1));
        for _ in 0..params.local_sweeps {
            if !self.sweep(params) || deadline() {
                break;
            }
        }
    }
}
