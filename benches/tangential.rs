//! Benchmark: tangential (placeholder until its stage lands).
fn main() {}
