//! Intensity calibration, reflectivity maps and scan matching (Khan 2017, ch. 3).
//!
//! Work in progress: the API lands with its issue.
