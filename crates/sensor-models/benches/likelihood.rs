//! Ray-likelihood throughput (placeholder until the likelihood benchmark lands).

fn main() {}
