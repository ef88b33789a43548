//! Filter update rate (placeholder, replaced below).
fn main() {}
