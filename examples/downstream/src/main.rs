//! Placeholder until the ray-casting trait lands (see README).
fn main() {}
