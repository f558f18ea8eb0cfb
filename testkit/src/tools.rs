//! Programs from outside the Rust toolchain that some tests run (tshark, can-utils' `log2asc`).
//!
//! `cargo test --workspace` must pass on a machine with only the Rust toolchain, so a test that
//! needs such a program asks [`require`] first: when the program is missing the test prints one
//! line saying it skipped and how to install the program, and returns. CI sets
//! `ARMHIL_REQUIRE_TOOLS=1`, and there a missing program fails the test instead, so a check can
//! never be skipped silently where it is supposed to run.

use std::io::Write;
use std::path::{Path, PathBuf};

/// The environment variable that turns a missing program into a test failure.
pub const REQUIRE_TOOLS_ENV: &str = "ARMHIL_REQUIRE_TOOLS";

/// An outside program a test needs, and how to get it.
#[derive(Debug, Clone, Copy)]
pub struct Tool {
    /// The executable's name, looked up on `PATH`.
    pub program: &'static str,
    /// The command that installs it, shown in the skip message.
    pub install: &'static str,
}

/// Wireshark's command-line reader (pcap checks).
pub const TSHARK: Tool = Tool {
    program: "tshark",
    install: "apt-get install tshark",
};

/// can-utils' candump-log to Vector ASC converter (candump log checks).
pub const LOG2ASC: Tool = Tool {
    program: "log2asc",
    install: "apt-get install can-utils",
};

/// can-utils' Vector ASC to candump-log converter.
pub const ASC2LOG: Tool = Tool {
    program: "asc2log",
    install: "apt-get install can-utils",
};

/// can-utils' long-format log printer.
pub const LOG2LONG: Tool = Tool {
    program: "log2long",
    install: "apt-get install can-utils",
};

/// Whether `ARMHIL_REQUIRE_TOOLS` asks for every tool to be present (any value but empty or `0`).
pub fn tools_required() -> bool {
    std::env::var(REQUIRE_TOOLS_ENV).is_ok_and(|v| !v.is_empty() && v != "0")
}

/// Where `program` is on `PATH`, if it is there as a file.
pub fn find_on_path(program: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|dir| dir.join(program))
        .find(|candidate| is_file(candidate))
}

fn is_file(path: &Path) -> bool {
    path.metadata().is_ok_and(|m| m.is_file())
}

/// Whether `test` can run: true when every tool is on `PATH`. When one is missing, prints
/// `skipped: <test>: <program> not on PATH — <install>` and returns false, or, under
/// `ARMHIL_REQUIRE_TOOLS=1`, panics with the same text.
pub fn require(test: &str, tools: &[Tool]) -> bool {
    match decide(test, tools, tools_required()) {
        Ok(None) => true,
        Ok(Some(skip)) => {
            // Straight to the process's stderr: libtest captures `eprintln!` of a passing test,
            // and a skip nobody sees is a silent one.
            let _ = writeln!(std::io::stderr(), "skipped: {skip}");
            false
        }
        Err(failure) => panic!("{failure}"),
    }
}

/// The decision behind [`require`], without printing or panicking: `Ok(None)` to run,
/// `Ok(Some(reason))` to skip, `Err(message)` when a missing tool must fail the test.
fn decide(test: &str, tools: &[Tool], required: bool) -> Result<Option<String>, String> {
    let Some(missing) = tools
        .iter()
        .find(|tool| find_on_path(tool.program).is_none())
    else {
        return Ok(None);
    };
    let reason = format!(
        "{test}: {} not on PATH — {}",
        missing.program, missing.install
    );
    if required {
        Err(format!(
            "{reason} ({REQUIRE_TOOLS_ENV} is set, so a missing tool is a failure)"
        ))
    } else {
        Ok(Some(reason))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MISSING: Tool = Tool {
        program: "armhil-no-such-program",
        install: "apt-get install nothing",
    };
    // `sh` is on every machine that can run `cargo test`.
    const SH: Tool = Tool {
        program: "sh",
        install: "",
    };

    #[test]
    fn a_present_tool_runs_the_test_whether_required_or_not() {
        assert!(find_on_path("sh").is_some());
        assert_eq!(decide("t", &[SH], false), Ok(None));
        assert_eq!(decide("t", &[SH], true), Ok(None));
    }

    #[test]
    fn a_missing_tool_skips_with_what_to_install() {
        let reason = decide("t", &[SH, MISSING], false).unwrap().unwrap();
        assert_eq!(
            reason,
            "t: armhil-no-such-program not on PATH — apt-get install nothing"
        );
    }

    #[test]
    fn a_missing_tool_fails_when_tools_are_required() {
        let failure = decide("t", &[MISSING], true).unwrap_err();
        assert!(failure.starts_with("t: armhil-no-such-program not on PATH"));
        assert!(failure.contains(REQUIRE_TOOLS_ENV));
    }
}
