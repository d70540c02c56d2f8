//! rover benchmarks (in progress).
fn main() {}
