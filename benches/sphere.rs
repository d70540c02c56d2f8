//! sphere benchmarks (in progress).
fn main() {}
