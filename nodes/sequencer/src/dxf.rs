//! DXF input (issue 7).
