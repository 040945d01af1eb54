//! The `chopperscape` command line.

fn main() {}
