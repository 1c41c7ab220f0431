//! Why a message has no view.

/// A message whose contents cannot be drawn as it claims to be.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ViewError {
    /// A toolpath segment has secondary points, but not one per primary point.
    #[error(
        "toolpath {job_id:?}: segment {segment} has {secondary} secondary points for {primary} points \
         (expected none or one per point)"
    )]
    SecondaryPoints {
        /// The toolpath's job.
        job_id: String,
        /// Index of the segment.
        segment: usize,
        /// Number of primary points.
        primary: usize,
        /// Number of secondary points.
        secondary: usize,
    },
    /// A heat map whose `data` is not `width * height` values, or too wide for an image row.
    #[error("heat map {quantity:?}: {reason}")]
    HeatMap {
        /// What the heat map shows.
        quantity: String,
        /// What is wrong.
        reason: String,
    },
}
