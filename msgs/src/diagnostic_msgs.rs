//! Vendored `diagnostic_msgs` types.

use serde::{Deserialize, Serialize};

use crate::std_msgs::Header;

/// The message on `/diagnostics` (`diagnostic_msgs/msg/DiagnosticArray`).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct DiagnosticArray {
    /// Time of the report.
    pub header: Header,
    /// One status per component reported on.
    pub status: Vec<DiagnosticStatus>,
}

/// The status of one component (`diagnostic_msgs/msg/DiagnosticStatus`).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct DiagnosticStatus {
    /// One of [`Self::OK`], [`Self::WARN`], [`Self::ERROR`], [`Self::STALE`].
    pub level: u8,
    /// What is reported on, conventionally `node: component`.
    pub name: String,
    /// A description of the status.
    pub message: String,
    /// A hardware-unique string.
    pub hardware_id: String,
    /// Values that go with the status.
    pub values: Vec<KeyValue>,
}

impl DiagnosticStatus {
    /// Level: operating normally.
    pub const OK: u8 = 0;
    /// Level: warning.
    pub const WARN: u8 = 1;
    /// Level: error.
    pub const ERROR: u8 = 2;
    /// Level: no recent updates.
    pub const STALE: u8 = 3;
}

/// One labelled value of a [`DiagnosticStatus`] (`diagnostic_msgs/msg/KeyValue`).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct KeyValue {
    /// Label.
    pub key: String,
    /// Value, as text.
    pub value: String,
}
