//! Rtree variable-resolution occupancy grid (Khan 2017, ch. 2).
//!
//! Work in progress: the API lands with its issue.
