//! Continuous decay-rate maps in the cosine domain (Schaefer 2020, ch. 9).
//!
//! Work in progress: the API lands with its issue.
