//! The `raypath` command-line program.
fn main() {}
