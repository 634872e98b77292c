//! Helpers shared by the command-line tests.
// Each test binary uses a subset of these helpers.
#![allow(dead_code)]

use std::ffi::OsStr;
use std::path::PathBuf;
use std::process::Command;

/// Runs the `himal` binary with `args` and the environment variables `env`
/// set; returns (exit status success, stdout, stderr).
pub fn run(args: &[&str], env: &[(&str, &OsStr)]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_himal"))
        .envs(env.iter().copied())
        .args(args)
        .output()
        .expect("runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// Asserts that the run of `args` failed with `needle` in its stderr.
pub fn assert_fails_with(args: &[&str], (ok, _, err): &(bool, String, String), needle: &str) {
    assert!(!ok, "{args:?} should fail");
    assert!(
        err.contains(needle),
        "{args:?}: stderr lacks \"{needle}\":\n{err}"
    );
}

/// `himal-<name>-<pid>` under the system temp dir (not created).
pub fn temp_path(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("himal-{name}-{}", std::process::id()))
}
