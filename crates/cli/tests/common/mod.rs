//! What the command line's test files share: the binary under test, started one way. Each test file says
//! `mod common;` (a folder's `mod.rs` is not a test binary of its own) and uses what it needs of this.
#![allow(dead_code)]

use std::path::PathBuf;
use std::time::Duration;

/// The `chopperscape` binary under test, as an `assert_cmd` command. It is killed after five minutes, so that a
/// command that hangs (an endless episode, a stuck child) fails its test instead of stalling the run.
pub fn cs() -> assert_cmd::Command {
    let mut c = assert_cmd::Command::cargo_bin("chopperscape").unwrap();
    c.timeout(Duration::from_secs(300));
    c
}

/// The path of the `chopperscape` binary, for a `std::process::Command` (signals, pipes, children).
pub fn bin() -> PathBuf {
    assert_cmd::cargo::cargo_bin("chopperscape")
}
