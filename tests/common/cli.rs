//! Shared by the tests that run the `busspec` binary against other processes: whether tshark
//! is here (and must be), a simulator on a pseudo-terminal, and scratch directories.

#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Command, Stdio};

/// Whether tshark runs here. Where it does not, the check is skipped with a word on stderr,
/// except where CI says tshark is installed (`BUSSPEC_REQUIRE_TSHARK`): there it fails.
pub fn tshark_present(what: &str) -> bool {
    let present = Command::new("sh")
        .args(["-c", "command -v tshark"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !present {
        assert!(
            std::env::var_os("BUSSPEC_REQUIRE_TSHARK").is_none(),
            "BUSSPEC_REQUIRE_TSHARK is set but tshark is not installed"
        );
        eprintln!("tshark is not installed: skipping {what}");
    }
    present
}

/// `busspec sim ARGS --pty` running, killed when dropped; `path` is the pseudo-terminal it
/// printed.
pub struct Sim {
    child: Child,
    pub path: String,
}

impl Sim {
    pub fn start(args: &[&str]) -> Sim {
        Sim::spawn(args, Stdio::null())
    }

    /// As [`Sim::start`], keeping what it says on stderr for [`Sim::stop`].
    pub fn start_heard(args: &[&str]) -> Sim {
        Sim::spawn(args, Stdio::piped())
    }

    fn spawn(args: &[&str], stderr: Stdio) -> Sim {
        let mut child = Command::new(env!("CARGO_BIN_EXE_busspec"))
            .arg("sim")
            .args(args)
            .arg("--pty")
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .stdout(Stdio::piped())
            .stderr(stderr)
            .spawn()
            .expect("busspec runs");
        let mut line = String::new();
        let stdout = child.stdout.take().expect("piped");
        BufReader::new(stdout).read_line(&mut line).expect("reads");
        let path = line.trim().to_owned();
        assert!(path.starts_with("/dev/"), "sim printed {line:?}");
        Sim { child, path }
    }
}

impl Sim {
    /// Ends the simulator with `signal` (`INT`, as Ctrl-C does, or `TERM`) and returns its exit
    /// status and what it said on stderr (started with [`Sim::start_heard`]).
    pub fn stop(mut self, signal: &str) -> (Option<i32>, String) {
        let pid = self.child.id().to_string();
        let sent = Command::new("kill")
            .args([&format!("-{signal}"), &pid])
            .status();
        assert!(sent.is_ok_and(|s| s.success()), "kill -{signal} {pid}");
        let mut said = String::new();
        if let Some(mut e) = self.child.stderr.take() {
            e.read_to_string(&mut said).expect("stderr reads");
        }
        let status = self.child.wait().expect("the simulator ends");
        (status.code(), said)
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A directory of the test's own under the system's temporary directory, named
/// `busspec-{what}-…`, removed with everything in it when dropped, a failing test's too.
pub fn scratch(what: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("busspec-{what}-"))
        .tempdir()
        .expect("a temporary directory")
}
