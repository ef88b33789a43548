//! Pole extraction, pole maps and pole-based localization (Schaefer 2020, ch. 12).
//!
//! Work in progress: the API lands with its issue.
