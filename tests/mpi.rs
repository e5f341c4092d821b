//! `mpirun -np 2 luxtally run ...` (feature `mpi`): the ranks share every epoch's
//! chunks and rank 0 folds them in chunk order, so the outputs are bit-identical to one
//! process; adaptive stopping works across ranks. MPI can be initialised once per
//! process, so each run is an mpirun subprocess.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const SCENE: &str = "scenes/office.toml";

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("luxtally-mpi-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn ok(out: Output) -> Output {
    assert!(
        out.status.success(),
        "exit {:?}: {}{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// mpirun with 2 ranks of one thread each: as root it needs --allow-run-as-root,
/// --oversubscribe lets 2 ranks run on fewer cores, --bind-to none keeps rayon's threads.
fn mpirun(args: &[&str]) -> Output {
    Command::new("mpirun")
        .args([
            "--allow-run-as-root",
            "--oversubscribe",
            "--bind-to",
            "none",
            "-np",
            "2",
        ])
        .arg(env!("CARGO_BIN_EXE_luxtally"))
        .args(args)
        .output()
        .expect("mpirun runs (openmpi-bin: scripts/setup.sh)")
}

fn summary(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn two_ranks_give_the_bits_of_one_process() {
    two_ranks_as_one_process("plain", &[]);
}

/// The same under `--qmc`: blocks of photons, QMC points and the direct light's Sobol'
/// patterns are functions of the seed and indices alone.
#[test]
fn two_ranks_give_the_bits_of_one_process_under_qmc() {
    two_ranks_as_one_process("qmc", &["--qmc"]);
}

fn two_ranks_as_one_process(name: &str, extra: &[&str]) {
    let one = temp_dir(&format!("{name}-one"));
    ok(Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args([
            "run",
            SCENE,
            "--photons",
            "400000",
            "--seed",
            "9",
            "--quiet",
        ])
        .args(extra)
        .arg("--out")
        .arg(&one)
        .output()
        .unwrap());
    let two = temp_dir(&format!("{name}-two"));
    ok(mpirun(
        &[
            &[
                "run",
                SCENE,
                "--photons",
                "400000",
                "--seed",
                "9",
                "--threads",
                "1",
                "--quiet",
                "--out",
                two.to_str().unwrap(),
            ],
            extra,
        ]
        .concat(),
    ));
    let (a, b) = (summary(&one), summary(&two));
    for k in [
        "photons_emitted",
        "rays_traced",
        "direct_replicates",
        "receivers",
        "global",
    ] {
        let (x, mut y) = (a[k].clone(), b[k].clone());
        let mut x = x;
        if k == "receivers" {
            for v in [&mut x, &mut y] {
                v["desk"].as_object_mut().unwrap().remove("fom");
            }
        }
        assert_eq!(x.to_string(), y.to_string(), "summary.json `{k}` differs");
    }
    assert!(
        std::fs::read(one.join("indirect_map.bin")).unwrap()
            == std::fs::read(two.join("indirect_map.bin")).unwrap()
    );
    assert!(
        two.join("checkpoint.bin").exists(),
        "rank 0 writes the checkpoint"
    );
}

#[test]
fn an_error_target_stops_every_rank() {
    let dir = temp_dir("target");
    ok(mpirun(&[
        "run",
        SCENE,
        "--target-error",
        "0.05",
        "--seed",
        "3",
        "--threads",
        "1",
        "--quiet",
        "--out",
        dir.to_str().unwrap(),
    ]));
    let s = summary(&dir);
    assert_eq!(s["stop_reason"], "target_error");
    assert!(
        s["receivers"]["desk"]["rel_error"]["arithmetic"]
            .as_f64()
            .unwrap()
            <= 0.05
    );
}
