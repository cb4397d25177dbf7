//! Helpers shared by the command-line test files (each test file is its own crate and uses
//! a subset of them).
#![allow(dead_code)]

use std::process::{Command, Output};

/// Run the `lightlab` binary with `args` and collect its output.
pub fn lightlab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lightlab"))
        .args(args)
        .output()
        .expect("binary runs")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The stderr of a command that must have succeeded.
pub fn ok(o: &Output) -> String {
    let e = stderr(o);
    assert!(o.status.success(), "{e}");
    e
}
