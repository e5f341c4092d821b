//! Progress on stderr that fits a log: when stderr is not a terminal (a pipe here, as in
//! CI or a redirected run) progress comes as plain lines, never a carriage return, and
//! `--quiet` prints nothing at all on stderr.

use std::path::PathBuf;
use std::process::{Command, Output};

fn luxtally(args: &[&str]) -> Output {
    // `output()` pipes stderr: not a terminal.
    Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args(args)
        .output()
        .expect("binary runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("luxtally-progress-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn stderr_of(out: &Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{err}");
    err
}

#[test]
fn run_progress_in_a_log_is_plain_lines_ending_with_the_stop() {
    let dir = temp_dir("run");
    let args = ["run", "scenes/office.toml", "--photons", "200000", "--out"];
    let err = stderr_of(&luxtally(&[&args[..], &[dir.to_str().unwrap()]].concat()));
    assert!(!err.contains('\r'), "carriage return in {err:?}");
    assert!(!err.contains('\x1b'), "terminal escape in {err:?}");
    // The last line is the run's final state, with everything the live line shows.
    let last = err.lines().last().unwrap_or_default();
    for part in [
        " s  receiver:desk: ",
        " %, stopped on photons  200000 photons  ",
        " Mrays/s",
    ] {
        assert!(last.contains(part), "`{part}` missing from {last:?}");
    }
}

#[test]
fn render_progress_in_a_log_is_plain_lines() {
    let dir = temp_dir("render");
    let out = dir.to_str().unwrap();
    let err = stderr_of(&luxtally(&[
        "render",
        "scenes/office.toml",
        "--photons",
        "50000",
        "--out",
        out,
    ]));
    assert!(!err.contains('\r') && !err.contains('\x1b'), "{err:?}");
    assert!(
        err.lines()
            .any(|l| l.starts_with("render: 100 % of 307200 pixels in ")),
        "{err}"
    );
}

#[test]
fn quiet_runs_and_renders_print_nothing_on_stderr() {
    let dir = temp_dir("quiet");
    let out = dir.to_str().unwrap();
    let run = luxtally(&[
        "run",
        "scenes/office.toml",
        "--photons",
        "50000",
        "--quiet",
        "--out",
        out,
    ]);
    assert_eq!(stderr_of(&run), "");
    assert!(run.stdout.is_empty());
    let render = luxtally(&["render", "scenes/office.toml", "--from", out, "--quiet"]);
    assert_eq!(stderr_of(&render), "");
}

#[test]
fn bench_commands_add_nothing_to_a_log() {
    let bench = luxtally(&["bench-rays", "scenes/office.toml", "--rays", "2000"]);
    assert_eq!(stderr_of(&bench), "");
    assert!(String::from_utf8_lossy(&bench.stdout).contains("| embree |"));
}
