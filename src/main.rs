//! The `raykit` command line.
fn main() {}
