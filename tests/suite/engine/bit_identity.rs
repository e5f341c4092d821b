//! Same seed ⇒ the same bits: every bundled scene (`scenes/*.toml`) is run — and the
//! office rendered — with a fixed seed and photon count, and each output file's
//! hash is compared with `tests/data/golden_outputs.txt`. Refactors must leave every
//! number alone; a change that means to alter results re-records the file with
//! `LUXTALLY_BLESS=1 cargo test --release --features obvhs --test suite bit_identity`, and
//! says why in its commit.
//!
//! What the hashes hold for, and so what each test compares on any machine:
//! - **obvhs** is pure Rust built for baseline x86-64, and its maths is the pure-Rust libm
//!   (glibc picks its exp/log/sin kernels by CPU, and their last bits differ): one set of
//!   hashes for every x86-64 CPU. The test also runs it with glibc told to use its
//!   kernels for CPUs without AVX2/FMA/AVX/SSE4, which must change nothing.
//! - **Embree** picks its kernels by instruction set, and they round differently, so its
//!   hashes are recorded per ISA (sse2, sse4.2, avx, avx2, avx512: whichever the recording
//!   CPU could run, forced with `LUXTALLY_EMBREE_CONFIG=max_isa=…`). Every recorded ISA
//!   this CPU can run is compared; an unrecorded native ISA is cross-checked instead.
//!   Below AVX-512 Embree's kernels use the approximate reciprocals rcpps/rsqrtps, whose
//!   bits differ between CPU generations (AVX-512's rcp14 is exactly specified): those
//!   ISAs' hashes are keyed by the CPU's reciprocal family too (`embree-avx2+rcp…`, a
//!   hash of rcpps/rsqrtps on fixed inputs), and a family not recorded is skipped and
//!   said so.
//! - **Embree against obvhs**: each receiver's mean and the scene's mean illuminance from
//!   the native Embree run must agree with obvhs's recorded figures within 4σ, on every
//!   machine and build (the recorded figures are obvhs's own, which hold on any CPU).

use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

const PHOTONS: &str = "20000";
/// The bundled scene whose `render` outputs are recorded too.
const RENDERED: &str = "office";
const SEED: &str = "7";
const GOLDEN: &str = "tests/data/golden_outputs.txt";

/// Embree's instruction sets, lowest first, as its `max_isa` setting spells them.
const EMBREE_ISAS: [&str; 5] = ["sse2", "sse4.2", "avx", "avx2", "avx512"];

/// glibc's kernels for a CPU without the newer instruction sets (glibc.cpu.hwcaps).
#[cfg(feature = "obvhs")]
const OLD_CPU_GLIBC: &str = "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX,-FMA4,-SSE4_1,-SSE4_2";

/// 64-bit FNV-1a: enough to tell two outputs apart, and no dependency.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The instruction sets of `EMBREE_ISAS` this CPU runs, by the CPU flags Embree requires.
fn cpu_isas() -> Vec<&'static str> {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let flags: Vec<&str> = info
        .lines()
        .find(|l| l.starts_with("flags"))
        .and_then(|l| l.split_once(':'))
        .map(|(_, v)| v.split_whitespace().collect())
        .unwrap_or_default();
    let has = |names: &[&str]| names.iter().all(|n| flags.contains(n));
    let needs: [&[&str]; 5] = [
        &["sse2"],
        &["sse4_1", "sse4_2", "ssse3", "popcnt"],
        &["avx"],
        &["avx2", "fma", "bmi1", "bmi2", "abm"],
        &["avx512f", "avx512cd", "avx512dq", "avx512bw", "avx512vl"],
    ];
    EMBREE_ISAS
        .iter()
        .zip(needs)
        .take_while(|(_, need)| has(need))
        .map(|(isa, _)| *isa)
        .collect()
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

/// A mean and a standard deviation that bounds its error.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Figure {
    mean: f64,
    sigma: f64,
}

/// What one set of runs produced: a hash per output file, and the run's figures.
#[derive(Default, Debug)]
struct Outputs {
    hashes: BTreeMap<String, u64>,
    figures: BTreeMap<String, Figure>,
}

/// Each receiver's mean, with the mean of its cells' σ as its σ (the σ of an average of
/// correlated cells is at most the average σ), and the scene's mean illuminance.
fn figures_of(stem: &str, summary: &Value, figures: &mut BTreeMap<String, Figure>) {
    let number = |v: &Value| v.as_f64().unwrap_or(0.0);
    if let Some(receivers) = summary["receivers"].as_object() {
        for (name, r) in receivers {
            let sigma = r["sigma"].as_array().map_or(0.0, |s| {
                s.iter().map(number).sum::<f64>() / s.len().max(1) as f64
            });
            let mean = number(&r["mean"]);
            figures.insert(format!("{stem} receiver:{name}"), Figure { mean, sigma });
        }
    }
    let global = &summary["global"];
    figures.insert(
        format!("{stem} global"),
        Figure {
            mean: number(&global["mean_illuminance_lx"]),
            sigma: number(&global["mean_sigma_lx"]),
        },
    );
}

/// Hash of every output but the report page and the checkpoint (both hold timings).
fn read_outputs(out: &Path, prefix: &str, outputs: &mut Outputs) {
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
        outputs.hashes.insert(format!("{prefix} {name}"), hash);
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

/// Runs (and renders) every bundled scene on `backend`, its outputs keyed by
/// `"{scene} {command} {kernels} {file}"`; `env` sets the runs' environment.
fn run_all(backend: &str, kernels: &str, env: &[(&str, &str)]) -> Outputs {
    let mut outputs = Outputs::default();
    let root = std::env::temp_dir().join(format!("luxtally-bits-{}-{kernels}", std::process::id()));
    for scene in bundled_scenes() {
        let text = std::fs::read_to_string(&scene).unwrap();
        let stem = scene.file_stem().unwrap().to_string_lossy().into_owned();
        // Every bundled scene has a camera; one render is enough here (the eye pass is the
        // same code for every scene), and six for each instruction set would cost CI
        // minutes.
        let mut commands = vec!["run"];
        if stem == RENDERED && text.lines().any(|l| l.trim() == "[camera]") {
            commands.push("render");
        }
        for command in commands {
            let out = root.join(format!("{stem}-{command}"));
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
                .envs(env.iter().copied())
                .status()
                .unwrap();
            assert!(status.success(), "{command} {}", scene.display());
            read_outputs(&out, &format!("{stem} {command} {kernels}"), &mut outputs);
            if command == "run" {
                let summary = std::fs::read(out.join("summary.json")).unwrap();
                let summary: Value = serde_json::from_slice(&summary).unwrap();
                figures_of(&stem, &summary, &mut outputs.figures);
            }
        }
    }
    let _ = std::fs::remove_dir_all(&root);
    outputs
}

fn embree_isa_run(isa: &str) -> Outputs {
    let kernels = embree_kernels(isa);
    let config = format!("max_isa={isa}");
    run_all("embree", &kernels, &[("LUXTALLY_EMBREE_CONFIG", &config)])
}

/// The goldens' name of Embree's kernels at `isa` on this CPU: below AVX-512 with the
/// CPU's reciprocal family.
fn embree_kernels(isa: &str) -> String {
    if isa == "avx512" {
        format!("embree-{isa}")
    } else {
        format!("embree-{isa}+rcp{:08x}", reciprocal_family())
    }
}

/// A hash of rcpps's and rsqrtps's results on fixed inputs: CPUs that agree on it
/// round Embree's pre-AVX-512 kernels alike.
fn reciprocal_family() -> u32 {
    use std::arch::x86_64::{_mm_rcp_ps, _mm_rsqrt_ps, _mm_set_ps, _mm_storeu_ps};
    let mut bits = Vec::new();
    for k in 0..64 {
        let x = 1.0 + k as f32 * 0.015_625 + 1e-3;
        let mut out = [0.0f32; 8];
        // SAFETY: SSE is part of x86-64; the stores write 4 floats into 4-float slices.
        unsafe {
            let v = _mm_set_ps(x, x * 3.7, x * 0.31, x * 117.0);
            _mm_storeu_ps(out[..4].as_mut_ptr(), _mm_rcp_ps(v));
            _mm_storeu_ps(out[4..].as_mut_ptr(), _mm_rsqrt_ps(v));
        }
        bits.extend(out.iter().flat_map(|f| f.to_bits().to_le_bytes()));
    }
    let h = fnv1a(&bits);
    (h ^ (h >> 32)) as u32
}

/// The recorded hashes and obvhs's recorded figures.
fn read_golden() -> Outputs {
    let text = std::fs::read_to_string(GOLDEN).unwrap_or_default();
    let mut golden = Outputs::default();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let words: Vec<&str> = line.split(' ').collect();
        if words.first() == Some(&"figure") && words.len() == 5 {
            let figure = Figure {
                mean: words[3].parse().unwrap(),
                sigma: words[4].parse().unwrap(),
            };
            golden
                .figures
                .insert(format!("{} {}", words[1], words[2]), figure);
        } else if let Some((key, hash)) = line.rsplit_once(' ') {
            let hash = u64::from_str_radix(hash, 16).unwrap();
            golden.hashes.insert(key.to_string(), hash);
        }
    }
    golden
}

fn write_golden(golden: &Outputs) {
    let mut text = String::from(
        "# Hashes of the bundled scenes' outputs (tests/bit_identity.rs): scene, command,\n\
         # kernels (obvhs on any x86-64 CPU; embree-ISA per Embree instruction set), file,\n\
         # FNV-1a 64 (summary.json without its timings). Then obvhs's figures: scene,\n\
         # receiver or global, mean, σ.\n",
    );
    for (key, hash) in &golden.hashes {
        text += &format!("{key} {hash:016x}\n");
    }
    for (key, f) in &golden.figures {
        text += &format!("figure {key} {:e} {:e}\n", f.mean, f.sigma);
    }
    std::fs::write(GOLDEN, text).unwrap();
}

fn blessing() -> bool {
    std::env::var_os("LUXTALLY_BLESS").is_some()
}

/// Replaces the recorded hashes of `kernels` by `outputs`' (blessing only).
fn record(kernels: &str, outputs: &Outputs) {
    static GOLDEN_FILE: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one_writer = GOLDEN_FILE.lock().unwrap();
    let mut golden = read_golden();
    golden
        .hashes
        .retain(|k, _| k.split(' ').nth(2) != Some(kernels));
    golden.hashes.extend(outputs.hashes.clone());
    if kernels == "obvhs" {
        golden.figures = outputs.figures.clone();
    }
    write_golden(&golden);
}

/// The recorded hashes of `kernels`, or `None` when none are.
fn recorded(golden: &Outputs, kernels: &str) -> Option<BTreeMap<String, u64>> {
    let hashes: BTreeMap<String, u64> = golden
        .hashes
        .iter()
        .filter(|(k, _)| k.split(' ').nth(2) == Some(kernels))
        .map(|(k, v)| (k.clone(), *v))
        .collect();
    (!hashes.is_empty()).then_some(hashes)
}

/// Asserts `outputs` has exactly the recorded hashes of `kernels`; returns how many.
fn assert_same_bits(outputs: &Outputs, recorded: &BTreeMap<String, u64>, what: &str) -> usize {
    let changed: std::collections::BTreeSet<&String> = recorded
        .keys()
        .chain(outputs.hashes.keys())
        .filter(|k| recorded.get(*k) != outputs.hashes.get(*k))
        .collect();
    assert!(
        changed.is_empty(),
        "{what}: outputs differ from {GOLDEN} ({} of {}): {changed:?}",
        changed.len(),
        outputs.hashes.len()
    );
    outputs.hashes.len()
}

/// Asserts every figure of `outputs` is within 4σ of obvhs's recorded one (σ the two
/// runs' σ combined); returns how many were compared.
fn assert_agrees_with_obvhs(outputs: &Outputs, golden: &Outputs) -> usize {
    assert!(
        !golden.figures.is_empty(),
        "{GOLDEN} holds no obvhs figures"
    );
    let mut compared = 0;
    for (key, reference) in &golden.figures {
        let figure = outputs
            .figures
            .get(key)
            .unwrap_or_else(|| panic!("the run has no figure {key}"));
        let sigma = libm::hypot(reference.sigma, figure.sigma);
        let gap = (figure.mean - reference.mean).abs();
        assert!(
            gap <= 4.0 * sigma,
            "{key}: Embree {} ± {}, obvhs {} ± {}: {:.1}σ apart",
            figure.mean,
            figure.sigma,
            reference.mean,
            reference.sigma,
            gap / sigma
        );
        compared += 1;
    }
    compared
}

#[cfg(feature = "obvhs")]
#[test]
fn obvhs_gives_the_recorded_bits_on_any_cpu() {
    let outputs = run_all("obvhs", "obvhs", &[]);
    if blessing() {
        record("obvhs", &outputs);
        return;
    }
    let golden = read_golden();
    let hashes = recorded(&golden, "obvhs").expect("no obvhs hashes are recorded");
    let n = assert_same_bits(&outputs, &hashes, "obvhs");
    let old_glibc = run_all("obvhs", "obvhs", &[("GLIBC_TUNABLES", OLD_CPU_GLIBC)]);
    let m = assert_same_bits(&old_glibc, &hashes, "obvhs under glibc's older kernels");
    eprintln!(
        "compared {n} obvhs outputs with the goldens (any x86-64 CPU), and {m} more with \
         glibc's kernels for CPUs without AVX2/FMA/AVX/SSE4"
    );
}

#[test]
fn embree_gives_the_recorded_bits_for_each_instruction_set() {
    let isas = cpu_isas();
    let native = *isas.last().expect("an x86-64 CPU runs SSE2");
    if blessing() {
        for isa in &isas {
            record(&embree_kernels(isa), &embree_isa_run(isa));
        }
        return;
    }
    let golden = read_golden();
    let mut compared = Vec::new();
    for isa in &isas {
        let kernels = embree_kernels(isa);
        match recorded(&golden, &kernels) {
            Some(hashes) => {
                let n = assert_same_bits(&embree_isa_run(isa), &hashes, &kernels);
                compared.push(format!("{n} outputs with max_isa={isa}"));
            }
            None => compared.push(format!("none for {kernels} (not recorded)")),
        }
    }
    let native_kernels = embree_kernels(native);
    let native_run = run_all("embree", &native_kernels, &[]);
    match recorded(&golden, &native_kernels) {
        Some(hashes) => {
            let n = assert_same_bits(&native_run, &hashes, "Embree's own choice of ISA");
            compared.push(format!("{n} outputs with Embree's own choice ({native})"));
        }
        None => compared.push(format!(
            "no goldens for this CPU's {native}: its outputs were cross-checked against obvhs"
        )),
    }
    let n = assert_agrees_with_obvhs(&native_run, &golden);
    compared.push(format!("{n} figures within 4σ of obvhs's"));
    eprintln!("Embree: compared {}", compared.join("; "));
}
