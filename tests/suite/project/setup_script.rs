//! scripts/setup.sh decides what to install from dpkg's package state. Each case runs the
//! real script with PATH holding only stubs: `dpkg-query` answers from a list of installed
//! packages, `id -u` says root or not, and `apt-get`, `sudo` and `cargo` only record their
//! arguments to a log. Nothing is installed.

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Every package setup.sh ensures, in its order.
const ALL: [&str; 9] = [
    "build-essential",
    "pkg-config",
    "libclang-dev",
    "libembree-dev",
    "chromium",
    "openmpi-bin",
    "libopenmpi-dev",
    "python3-venv",
    "python3-dev",
];

/// The machine the script sees.
struct Machine<'a> {
    /// `(package, dpkg status)` pairs; any other package is unknown to dpkg.
    packages: &'a [(&'a str, &'a str)],
    root: bool,
    sudo: bool,
}

/// `bash` from the test's own PATH: the script runs under a PATH of stubs only.
fn bash() -> PathBuf {
    std::env::var_os("PATH")
        .iter()
        .flat_map(std::env::split_paths)
        .map(|dir| dir.join("bash"))
        .find(|p| p.is_file())
        .expect("bash on PATH")
}

fn stub(dir: &Path, name: &str, body: &str) {
    let path = dir.join(name);
    std::fs::write(&path, format!("#!{}\n{body}", bash().display())).expect("stub written");
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).expect("chmod");
}

/// Runs scripts/setup.sh on `machine`; returns its output and the recorded commands,
/// one line per call (`apt-get ARGS`, `sudo ARGS`).
fn run_setup(name: &str, machine: &Machine) -> (Output, Vec<String>) {
    let dir = std::env::temp_dir().join(format!("luxtally-setup-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).expect("temp dir");
    let log = dir.join("calls.log");
    let state = dir.join("dpkg-status");
    let listing: String = machine
        .packages
        .iter()
        .map(|(p, s)| format!("{p}\t{s}\n"))
        .collect();
    std::fs::write(&state, listing).expect("dpkg state written");

    // Like dpkg-query -W -f='${Status}' PKG: the status, or exit 1 for an unknown package.
    stub(
        &bin,
        "dpkg-query",
        &format!(
            r#"[ "$1 $2" = "-W -f=\${{Status}}" ] || {{ echo "dpkg-query stub: unexpected $*" >&2; exit 2; }}
while IFS=$'\t' read -r name status; do
  if [ "$name" = "$3" ]; then printf '%s' "$status"; exit 0; fi
done < '{state}'
echo "dpkg-query: no packages found matching $3" >&2
exit 1
"#,
            state = state.display()
        ),
    );
    let uid = if machine.root { 0 } else { 1000 };
    stub(
        &bin,
        "id",
        &format!("[ \"$1\" = -u ] || exit 2\necho {uid}\n"),
    );
    let record = format!("echo \"$(basename_ \"$0\") $*\" >> '{}'\n", log.display());
    let basename = "basename_() { echo \"${1##*/}\"; }\n";
    stub(&bin, "apt-get", &format!("{basename}{record}"));
    stub(&bin, "cargo", "exit 0\n");
    if machine.sudo {
        // Records, then runs the command with its VAR=value assignments.
        stub(
            &bin,
            "sudo",
            &format!(
                "{basename}{record}while [ \"${{1#*=}}\" != \"$1\" ]; do export \"$1\"; shift; done\nexec \"$@\"\n"
            ),
        );
    }

    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/setup.sh");
    let out = Command::new(bash())
        .arg(script)
        .env_clear()
        .env("PATH", &bin)
        .output()
        .expect("setup.sh runs");
    let calls = std::fs::read_to_string(&log)
        .unwrap_or_default()
        .lines()
        .map(str::to_string)
        .collect();
    let _ = std::fs::remove_dir_all(&dir);
    (out, calls)
}

fn install_line(packages: &[&str]) -> String {
    format!("apt-get install -y -qq {}", packages.join(" "))
}

fn assert_ok(out: &Output) {
    assert!(
        out.status.success(),
        "exit {:?}: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn nothing_installed_installs_every_package_after_one_update() {
    let (out, calls) = run_setup(
        "nothing",
        &Machine {
            packages: &[],
            root: true,
            sudo: false,
        },
    );
    assert_ok(&out);
    assert_eq!(
        calls,
        ["apt-get update -qq".to_string(), install_line(&ALL)]
    );
}

#[test]
fn libclang_cpp_is_not_libclang_dev() {
    // The machine of the original bug: a libclang-cpp14 pulled in by another package,
    // and a chromium removed with its configuration left (not installed either).
    let (out, calls) = run_setup(
        "clang-cpp",
        &Machine {
            packages: &[
                ("libclang-cpp14", "install ok installed"),
                ("libllvm14", "install ok installed"),
                ("chromium", "deinstall ok config-files"),
            ],
            root: true,
            sudo: false,
        },
    );
    assert_ok(&out);
    assert_eq!(
        calls,
        ["apt-get update -qq".to_string(), install_line(&ALL)]
    );
}

#[test]
fn some_installed_installs_exactly_the_rest() {
    let (out, calls) = run_setup(
        "some",
        &Machine {
            packages: &[
                ("build-essential", "install ok installed"),
                ("pkg-config", "hold ok installed"),
                ("libembree-dev", "install ok installed"),
                ("openmpi-bin", "install ok installed"),
            ],
            root: true,
            sudo: false,
        },
    );
    assert_ok(&out);
    assert_eq!(
        calls,
        [
            "apt-get update -qq".to_string(),
            install_line(&[
                "libclang-dev",
                "chromium",
                "libopenmpi-dev",
                "python3-venv",
                "python3-dev"
            ])
        ]
    );
}

#[test]
fn all_installed_runs_no_apt_get() {
    let all: Vec<(&str, &str)> = ALL.iter().map(|p| (*p, "install ok installed")).collect();
    let (out, calls) = run_setup(
        "all",
        &Machine {
            packages: &all,
            root: false,
            sudo: true,
        },
    );
    assert_ok(&out);
    assert!(calls.is_empty(), "no apt-get, no sudo: {calls:?}");
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn not_root_with_sudo_installs_through_sudo() {
    let (out, calls) = run_setup(
        "sudo",
        &Machine {
            packages: &[],
            root: false,
            sudo: true,
        },
    );
    assert_ok(&out);
    let install = install_line(&ALL);
    assert_eq!(
        calls,
        [
            "sudo DEBIAN_FRONTEND=noninteractive apt-get update -qq".to_string(),
            "apt-get update -qq".to_string(),
            format!("sudo DEBIAN_FRONTEND=noninteractive {install}"),
            install,
        ]
    );
}

#[test]
fn not_root_and_no_sudo_names_the_command_to_run_and_installs_nothing() {
    let (out, calls) = run_setup(
        "nosudo",
        &Machine {
            packages: &[
                ("build-essential", "install ok installed"),
                ("pkg-config", "install ok installed"),
                ("libembree-dev", "install ok installed"),
                ("openmpi-bin", "install ok installed"),
                ("libopenmpi-dev", "install ok installed"),
                ("python3-venv", "install ok installed"),
                ("python3-dev", "install ok installed"),
            ],
            root: false,
            sudo: false,
        },
    );
    assert!(!out.status.success(), "exit non-zero");
    assert!(calls.is_empty(), "nothing run: {calls:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    assert!(
        err.contains("`apt-get update && apt-get install -y libclang-dev chromium`"),
        "names the command: {err}"
    );
}

#[test]
fn a_machine_without_the_python_toolchain_installs_venv_and_dev_only() {
    // Debian 12 with everything the Rust build needs but Python's venv and headers (a
    // python3 alone comes with the base system).
    let packages: Vec<(&str, &str)> = ALL[..7]
        .iter()
        .map(|p| (*p, "install ok installed"))
        .chain([("python3", "install ok installed")])
        .collect();
    let (out, calls) = run_setup(
        "python",
        &Machine {
            packages: &packages,
            root: true,
            sudo: false,
        },
    );
    assert_ok(&out);
    assert_eq!(
        calls,
        [
            "apt-get update -qq".to_string(),
            install_line(&["python3-venv", "python3-dev"])
        ]
    );
}
