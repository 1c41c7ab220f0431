//! Configuration files, read one way.
//!
//! Every YAML or JSON file the suite reads into a struct (machine profiles, material
//! libraries, WAAM process profiles, wing specs, controller files, sheet layouts) goes through
//! [`from_yaml_str`] or [`from_json_str`]: serde with `serde_path_to_error`, so a rejected file
//! is a [`ParseError`] that names the file, the line (and column) and the dotted path of the
//! field. The validators that check the values afterwards report a [`FieldError`]: the field
//! and its [`Problem`], a value [`OutOfRange`] of what it [`Allowed`], or another rule.
//!
//! Every message has one shape, [`Place`] then what is wrong:
//!
//! ```text
//! config/machines/x.yaml:12: field `hotwire.tower_separation_mm`: invalid type: string "a", expected f64
//! config/machines/x.yaml: field `max_feed_mm_s`: 0 mm/s is out of range: must be finite and > 0
//! ```
//!
//! ```
//! #[derive(Debug, serde::Deserialize)]
//! #[serde(deny_unknown_fields)]
//! struct Axis {
//!     travel_mm: f64,
//! }
//! #[derive(Debug, serde::Deserialize)]
//! struct Machine {
//!     axis: Axis,
//! }
//! let e = cell_config::from_yaml_str::<Machine>("axis:\n  travel_mm: a\n", "m.yaml").unwrap_err();
//! assert_eq!((e.line, e.field.as_deref()), (Some(2), Some("axis.travel_mm")));
//! assert!(e.to_string().starts_with("m.yaml:2: field `axis.travel_mm`: invalid type"), "{e}");
//! ```
//!
//! A node answering a remote caller uses [`without_content`] and
//! [`ParseError::without_content`]: the same place and kind of problem, no value from the file.
//!
//! The crate is pure (serde only), so every algorithm crate may use it.

mod field;
mod parse;
mod place;
mod range;
mod redact;

pub use field::{FieldError, Problem};
pub use parse::{from_json_str, from_yaml_str, ParseError};
pub use place::Place;
pub use range::{Allowed, Bound, OutOfRange};
pub use redact::{without_content, BLANKED};
