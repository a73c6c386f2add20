//! Benchmark: surface (placeholder until its stage lands).
fn main() {}
