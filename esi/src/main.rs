//! `esi` CLI.
fn main() {}
