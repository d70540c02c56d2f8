//! space_robot benchmarks (in progress).
fn main() {}
