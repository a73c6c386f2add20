//! Benchmark: normal (placeholder until its stage lands).
fn main() {}
