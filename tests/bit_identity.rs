//! Same seed ⇒ the same bits: every bundled scene (`scenes/*.toml`) is run — and rendered
//! where it has a `[camera]` — with a fixed seed and photon count on every backend this
//! build has, and each output file's hash is compared with `tests/data/golden_outputs.txt`.
//! Refactors must leave every number alone; a change that means to alter results
//! re-records the file with `LUXTALLY_BLESS=1 cargo test --release --test bit_identity`
//! (and `--features obvhs`), and says why in its commit.
//!
//! Embree picks its traversal kernels by CPU, so the hashes hold for the CPU they were
//! recorded on (its model and flags are part of the file); on another CPU the test says
//! so and checks nothing.

use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

const PHOTONS: &str = "20000";
const SEED: &str = "7";
const GOLDEN: &str = "tests/data/golden_outputs.txt";

/// 64-bit FNV-1a: enough to tell two outputs apart, and no dependency.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// What identifies the machine's ray-casting kernels: the CPU model and its flags.
fn cpu_identity() -> String {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let field = |name: &str| {
        info.lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.split_once(':'))
            .map(|(_, v)| v.trim().to_string())
            .unwrap_or_default()
    };
    format!(
        "{:016x}",
        fnv1a(format!("{}|{}", field("model name"), field("flags")).as_bytes())
    )
}

/// Timings, thread counts and what derives from them (the figure of merit's stability
/// and the `reliable` verdict it feeds) differ between identical runs.
fn is_timing(key: &str) -> bool {
    key == "threads"
        || key == "reliable"
        || key.ends_with("_s")
        || key.ends_with("_share")
        || key.ends_with("per_s")
        || key.contains("fom")
}

fn without_timings(v: &mut Value) {
    match v {
        Value::Object(map) => {
            map.retain(|k, _| !is_timing(k));
            map.values_mut().for_each(without_timings);
        }
        Value::Array(items) => items.iter_mut().for_each(without_timings),
        _ => {}
    }
}

/// Hash of every output but the report page and the checkpoint (both hold timings).
fn output_hashes(out: &Path, prefix: &str, hashes: &mut BTreeMap<String, u64>) {
    let mut files = Vec::new();
    let mut dirs = vec![out.to_path_buf()];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else {
                files.push(path);
            }
        }
    }
    for path in files {
        let name = path
            .strip_prefix(out)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        if name == "report.html" || name.starts_with("checkpoint.bin") {
            continue;
        }
        let bytes = std::fs::read(&path).unwrap();
        let hash = if name == "summary.json" {
            let mut v: Value = serde_json::from_slice(&bytes).unwrap();
            without_timings(&mut v);
            fnv1a(v.to_string().as_bytes())
        } else {
            fnv1a(&bytes)
        };
        hashes.insert(format!("{prefix} {name}"), hash);
    }
}

fn bundled_scenes() -> Vec<PathBuf> {
    let mut scenes: Vec<PathBuf> = std::fs::read_dir("scenes")
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 4, "bundled scenes: {scenes:?}");
    scenes
}

fn backends() -> Vec<&'static str> {
    if cfg!(feature = "obvhs") {
        vec!["embree", "obvhs"]
    } else {
        vec!["embree"]
    }
}

fn run_all(backend: &str) -> BTreeMap<String, u64> {
    let mut hashes = BTreeMap::new();
    let root = std::env::temp_dir().join(format!("luxtally-bits-{}", std::process::id()));
    for scene in bundled_scenes() {
        let text = std::fs::read_to_string(&scene).unwrap();
        let stem = scene.file_stem().unwrap().to_string_lossy().into_owned();
        let mut commands = vec!["run"];
        if text.lines().any(|l| l.trim() == "[camera]") {
            commands.push("render");
        }
        for command in commands {
            let out = root.join(format!("{stem}-{command}-{backend}"));
            let _ = std::fs::remove_dir_all(&out);
            let status = Command::new(env!("CARGO_BIN_EXE_luxtally"))
                .args([
                    command,
                    scene.to_str().unwrap(),
                    "--out",
                    out.to_str().unwrap(),
                ])
                .args(["--photons", PHOTONS, "--seed", SEED, "--threads", "2"])
                .args(["--backend", backend, "--quiet"])
                .status()
                .unwrap();
            assert!(status.success(), "{command} {}", scene.display());
            output_hashes(&out, &format!("{stem} {command} {backend}"), &mut hashes);
        }
    }
    let _ = std::fs::remove_dir_all(&root);
    hashes
}

fn read_golden() -> (String, BTreeMap<String, u64>) {
    let text = std::fs::read_to_string(GOLDEN).unwrap_or_default();
    let mut cpu = String::new();
    let mut hashes = BTreeMap::new();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        if let Some(c) = line.strip_prefix("cpu ") {
            cpu = c.to_string();
        } else if let Some((key, hash)) = line.rsplit_once(' ') {
            hashes.insert(key.to_string(), u64::from_str_radix(hash, 16).unwrap());
        }
    }
    (cpu, hashes)
}

fn write_golden(cpu: &str, hashes: &BTreeMap<String, u64>) {
    let mut text = String::from(
        "# Hashes of the bundled scenes' outputs (tests/bit_identity.rs): scene, command,\n\
         # backend, file, FNV-1a 64 (summary.json without its timings).\n",
    );
    text += &format!("cpu {cpu}\n");
    for (key, hash) in hashes {
        text += &format!("{key} {hash:016x}\n");
    }
    std::fs::write(GOLDEN, text).unwrap();
}

#[test]
fn bundled_scenes_give_the_recorded_bits() {
    let cpu = cpu_identity();
    let (golden_cpu, mut golden) = read_golden();
    let bless = std::env::var_os("LUXTALLY_BLESS").is_some();
    if !bless && golden_cpu != cpu {
        eprintln!(
            "golden outputs were recorded on another CPU ({golden_cpu} ≠ {cpu}): not compared"
        );
        return;
    }
    for backend in backends() {
        let hashes = run_all(backend);
        if bless {
            golden.retain(|k, _| !k.contains(&format!(" {backend} ")));
            golden.extend(hashes);
            continue;
        }
        let recorded: BTreeMap<_, _> = golden
            .iter()
            .filter(|(k, _)| k.split(' ').nth(2) == Some(backend))
            .map(|(k, v)| (k.clone(), *v))
            .collect();
        let changed: Vec<&String> = recorded
            .keys()
            .chain(hashes.keys())
            .filter(|k| recorded.get(*k) != hashes.get(*k))
            .collect();
        assert!(
            changed.is_empty(),
            "outputs differ from {GOLDEN} ({} of {}): {changed:?}",
            changed.len(),
            hashes.len()
        );
    }
    if bless {
        write_golden(&cpu, &golden);
    }
}
