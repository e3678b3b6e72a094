//! cargo xtask entry point (see README).
fn main() {}
