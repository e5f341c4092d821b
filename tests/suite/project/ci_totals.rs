//! .ci/run's closing line (.ci/totals.awk) on sample logs: cargo's and pytest's results
//! added up, and tests that started but never reported shown, not dropped.

use std::io::Write;
use std::process::{Command, Stdio};

/// The totals line .ci/totals.awk prints for `log`.
fn totals(log: &str) -> String {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/.ci/totals.awk");
    let mut awk = Command::new("awk")
        .args(["-f", script])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("awk runs");
    awk.stdin
        .take()
        .expect("stdin")
        .write_all(log.as_bytes())
        .expect("log written");
    let out = awk.wait_with_output().expect("awk ends");
    assert!(out.status.success());
    String::from_utf8(out.stdout)
        .expect("utf-8")
        .trim()
        .to_string()
}

const CARGO: &str = "running 3 tests
test a ... ok
test result: ok. 2 passed; 0 failed; 1 ignored; 0 measured; 0 filtered out; finished in 0.01s
";

#[test]
fn cargo_and_pytest_results_add_up() {
    let log = format!(
        "{CARGO}============================= test session starts ==============================
collected 13 items

tests/test_a.py ..F.s.....xE.
=== 1 failed, 9 passed, 1 skipped, 1 xfailed, 1 error, 2 warnings in 3.40s ===
"
    );
    assert_eq!(totals(&log), "totals: 11 passed, 2 failed, 3 skipped");
}

#[test]
fn a_pytest_session_with_minutes_in_its_time_counts() {
    let log = "collected 51 items\n==== 51 passed in 83.10s (0:01:23) ====\n";
    assert_eq!(totals(log), "totals: 51 passed, 0 failed, 0 skipped");
}

#[test]
fn a_session_killed_before_its_result_is_unreported() {
    let log = format!("{CARGO}collected 40 items\ntests/test_a.py ....");
    assert_eq!(
        totals(&log),
        "totals: 2 passed, 0 failed, 1 skipped, 40 unreported \
         (a test binary or pytest session ended without its result)"
    );
}

#[test]
fn progress_lines_of_equal_signs_are_not_results() {
    let log = "=== FAILURES ===\n=== short test summary info ===\ncollected 1 item\n\
               === 1 passed in 0.01s ===\n";
    assert_eq!(totals(log), "totals: 1 passed, 0 failed, 0 skipped");
}
