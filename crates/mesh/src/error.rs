//! Error types of mesh loading and slicing.

use std::path::PathBuf;

/// Why an STL file (or byte buffer) could not be turned into a [`crate::Mesh`].
///
/// Every variant names the source (`file`: the path, or the name given to
/// [`crate::Mesh::from_stl_bytes`]) and, where it applies, the 0-based triangle index.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be read at all.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// The file.
        file: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file holds no triangle (zero bytes, `solid …/endsolid` only, or a binary count of 0).
    #[error("{file}: the STL holds no triangle")]
    Empty {
        /// The file.
        file: PathBuf,
    },
    /// A binary STL shorter than its header (84 bytes) plus 50 bytes per announced triangle.
    #[error(
        "{file}: truncated binary STL: {len_bytes} bytes, but the header announces {announced} \
         triangles ({expected_bytes} bytes); triangle {triangle} is incomplete"
    )]
    Truncated {
        /// The file.
        file: PathBuf,
        /// Actual length in bytes.
        len_bytes: usize,
        /// Triangle count from the binary header.
        announced: u64,
        /// Length the header implies (84 + 50 × announced).
        expected_bytes: u64,
        /// Index of the first incomplete triangle.
        triangle: u64,
    },
    /// The STL parser rejected the content (malformed ASCII, bad tokens, early end of file).
    #[error("{file}: malformed STL at triangle {triangle}: {message}")]
    Parse {
        /// The file.
        file: PathBuf,
        /// Index of the triangle being read when the parser failed.
        triangle: usize,
        /// The parser's message.
        message: String,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("{file}: triangle {triangle}, vertex {vertex}: non-finite coordinate {value}")]
    NonFinite {
        /// The file.
        file: PathBuf,
        /// 0-based triangle index.
        triangle: usize,
        /// 0-based vertex index within the triangle.
        vertex: usize,
        /// The offending value.
        value: f32,
    },
    /// The weld tolerance is negative or not finite.
    #[error("weld tolerance must be finite and >= 0, got {0}")]
    BadTolerance(f64),
    /// More than `u32::MAX` vertices or triangles.
    #[error("{file}: mesh too large ({triangles} triangles)")]
    TooLarge {
        /// The file.
        file: PathBuf,
        /// Triangle count.
        triangles: usize,
    },
}

/// Why [`crate::slice()`] refused its parameters.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SliceError {
    /// Layer height not finite or not > 0.
    #[error("layer_height_mm must be finite and > 0, got {0}")]
    BadLayerHeight(f64),
    /// A start height or tolerance that is not finite (or a negative tolerance).
    #[error("{field} must be finite (and >= 0 for tolerances), got {value}")]
    BadParam {
        /// The field name in [`crate::SliceParams`].
        field: &'static str,
        /// The value.
        value: f64,
    },
    /// The layer count would exceed [`crate::MAX_LAYERS`].
    #[error(
        "{layers} layers of {layer_height_mm} mm over {height_mm} mm exceed the limit of {max}"
    )]
    TooManyLayers {
        /// Requested layer count.
        layers: f64,
        /// Layer height.
        layer_height_mm: f64,
        /// Sliced height.
        height_mm: f64,
        /// The limit.
        max: usize,
    },
}
