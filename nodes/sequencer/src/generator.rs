//! Layout generator (issue 7).
