//! Benchmark: calibrate (placeholder until its stage lands).
fn main() {}
