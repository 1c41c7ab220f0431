//! Vendored `std_srvs` services, so a stock ROS 2 client (`ros2 service call … std_srvs/srv/SetBool`)
//! can call a cellsuite server without any cellsuite package installed.

use serde::{Deserialize, Serialize};

/// Request of `std_srvs/srv/SetBool`: switch something on or off.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct SetBoolRequest {
    /// The value to set (e.g. for hardware enabling / disabling).
    pub data: bool,
}

/// Response of `std_srvs/srv/SetBool`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct SetBoolResponse {
    /// Whether the value was set.
    pub success: bool,
    /// Informational, e.g. an error message.
    pub message: String,
}
