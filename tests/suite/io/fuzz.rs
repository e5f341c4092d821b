//! Mutation fuzzing of everything a user hands luxtally: the bundled scene files, and
//! the mesh (OBJ, glTF, GLB) and photometry (IES, EULUMDAT) files scenes read. Each case
//! edits a file at random — numbers swapped for values at and beyond f32's and f64's
//! range, lines deleted, duplicated, swapped or borrowed, keys renamed, bytes flipped,
//! the file cut short — and runs `luxtally` on it. The answer must be exit 0, or exit 1
//! with one line on stderr: never a signal (an abort inside a ray caster), a panic or a
//! hang.
//!
//! Cases are seeded: a failure names its case and keeps its files. Each backend this
//! build has takes every other case. `LUXTALLY_FUZZ_CASES=N` runs N scene cases and N/2
//! file cases (default 2000 and 1000).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Longer than any case should need (the runs are capped at a few seconds of tracing).
const CASE_TIMEOUT: Duration = Duration::from_secs(120);

/// Numbers at the edges: f32's and f64's limits, Embree's `FLT_LARGE` (1.844e18),
/// luxtally's ±1e16 m, subnormals, NaN and infinities, integers past 2^24 and 2^32.
const EDGE_VALUES: &[&str] = &[
    "0",
    "-0",
    "0.0",
    "1",
    "-1",
    "3.4e38",
    "3.4028236e38",
    "-3.4e38",
    "1e39",
    "-1e39",
    "1e300",
    "-1e300",
    "1.7976931348623157e308",
    "1e-45",
    "1e-39",
    "-1e-39",
    "1e-300",
    "5e-324",
    "1e16",
    "1.0000001e16",
    "-1e16",
    "1e17",
    "1.9e18",
    "1e30",
    "nan",
    "inf",
    "-inf",
    "16777217",
    "4294967296",
    "18446744073709551616",
    "1e9",
    "0.9999999",
    "1.0000001",
    "-0.5",
    "2",
];

/// SplitMix64: the cases' random numbers, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Byte ranges of the numbers in `text` (not inside identifiers).
fn numbers(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            || (matches!(b[i], b'-' | b'+' | b'.') && b.get(i + 1).is_some_and(u8::is_ascii_digit));
        let after_word = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if starts && !after_word {
            let start = i;
            i += 1;
            while i < b.len()
                && (b[i].is_ascii_digit()
                    || b[i] == b'.'
                    || ((b[i] == b'e' || b[i] == b'E')
                        && b.get(i + 1)
                            .is_some_and(|c| c.is_ascii_digit() || *c == b'-')))
            {
                i += if b[i] == b'e' || b[i] == b'E' { 2 } else { 1 };
            }
            out.push((start, i.min(b.len())));
        } else {
            i += 1;
        }
    }
    out
}

/// A value for a number: an edge value, or the number scaled by 10^k.
fn new_number(rng: &mut Rng, old: &str) -> String {
    if rng.below(3) == 0 {
        let k = rng.below(121) as i32 - 60;
        format!(
            "{}e{k}",
            old.trim_end_matches(|c: char| !c.is_ascii_digit())
        )
    } else {
        rng.pick(EDGE_VALUES).to_string()
    }
}

/// One random edit of a text file; `corpus` lends lines and keys.
fn mutate_text(rng: &mut Rng, text: &str, corpus: &[String]) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    if lines.is_empty() {
        return text.to_string();
    }
    match rng.below(10) {
        0..=4 => {
            let spans = numbers(text);
            if spans.is_empty() {
                return text.to_string();
            }
            let (a, b) = *rng.pick(&spans);
            let replacement = new_number(rng, &text[a..b]);
            return format!("{}{replacement}{}", &text[..a], &text[b..]);
        }
        5 => {
            lines.remove(rng.below(lines.len()));
        }
        6 => {
            let k = rng.below(lines.len());
            lines.insert(k, lines[k].clone());
        }
        7 => {
            let (a, b) = (rng.below(lines.len()), rng.below(lines.len()));
            lines.swap(a, b);
        }
        8 => {
            // A line of another file of the corpus, or a key renamed after one of its keys.
            let borrowed = rng.pick(corpus).clone();
            let k = rng.below(lines.len());
            match (lines[k].split_once('='), borrowed.split_once('=')) {
                (Some((_, value)), Some((key, _))) if rng.below(2) == 0 => {
                    lines[k] = format!("{key}={value}");
                }
                _ => lines.insert(k, borrowed),
            }
        }
        _ => {
            let cut = rng.below(text.len());
            let cut = (0..=cut)
                .rev()
                .find(|&c| text.is_char_boundary(c))
                .unwrap_or(0);
            return text[..cut].to_string();
        }
    }
    let mut out = lines.join("\n");
    out.push('\n');
    out
}

/// One random edit of a binary file: bytes flipped, an f32 overwritten, or cut short.
fn mutate_bytes(rng: &mut Rng, bytes: &[u8]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    if out.is_empty() {
        return out;
    }
    match rng.below(4) {
        0 => {
            for _ in 0..1 + rng.below(8) {
                let k = rng.below(out.len());
                out[k] ^= 1 << rng.below(8);
            }
        }
        1 | 2 => {
            let value = *rng.pick(&[
                f32::MAX,
                -f32::MAX,
                f32::INFINITY,
                f32::NAN,
                1e30,
                1e-40,
                0.0,
                1.9e18,
                1e17,
            ]);
            let k = rng.below(out.len() / 4) * 4;
            if k + 4 <= out.len() {
                out[k..k + 4].copy_from_slice(&value.to_le_bytes());
            }
        }
        _ => out.truncate(rng.below(out.len())),
    }
    out
}

/// A file a scene reads, and a scene that reads it (`{FILE}` stands for its name).
struct Carrier {
    file: &'static str,
    scene: &'static str,
}

/// A grey floor and a receiver over it: what every carrier scene has.
const FLOOR: &str = r#"
[materials.grey]
reflectance = 0.5
[[objects]]
shape = "rect"
corner = [-5, -5, 0]
u = [10, 0, 0]
v = [0, 10, 0]
material = "grey"
[[receivers]]
name = "floor"
corner = [-2, -2, 0.001]
u = [4, 0, 0]
v = [0, 4, 0]
cells = [8, 8]
"#;

/// The floor with a mesh file (`{FILE}`) on it under a point light.
const MESH_SCENE: &str = r#"
[[objects]]
file = "{FILE}"
material = "grey"
translate = [0, 0, 0.5]
[[lights]]
type = "point"
position = [0.3, 0.2, 4]
intensity_cd = 100
"#;

/// The floor under a luminaire read from `{FILE}`.
const LUMINAIRE_SCENE: &str = r#"
[[lights]]
type = "luminaire"
file = "{FILE}"
position = [0, 0, 2.5]
"#;

const CARRIERS: &[Carrier] = &[
    Carrier {
        file: "scenes/meshes/cornell_box.obj",
        scene: MESH_SCENE,
    },
    Carrier {
        file: "scenes/meshes/suzanne.obj",
        scene: MESH_SCENE,
    },
    Carrier {
        file: "scenes/gltf/Box.gltf",
        scene: MESH_SCENE,
    },
    Carrier {
        file: "scenes/gltf/OrientationTest.glb",
        scene: MESH_SCENE,
    },
    Carrier {
        file: "scenes/photometry/examp1.ies",
        scene: LUMINAIRE_SCENE,
    },
    Carrier {
        file: "tests/data/photometry/opening_feet.ies",
        scene: LUMINAIRE_SCENE,
    },
    Carrier {
        file: "tests/data/photometry/lobe_c90.ies",
        scene: LUMINAIRE_SCENE,
    },
    Carrier {
        file: "tests/data/photometry/cosine.ldt",
        scene: LUMINAIRE_SCENE,
    },
];

/// The bundled scenes, their cameras made cheap (the camera's keys are still fuzzed).
fn bundled_scenes() -> Vec<(String, String)> {
    let mut scenes: Vec<PathBuf> = std::fs::read_dir("scenes")
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    scenes
        .iter()
        .map(|p| {
            let text = std::fs::read_to_string(p).unwrap();
            let text: Vec<String> = text
                .lines()
                .map(|l| match l.split_once('=') {
                    Some((k, _)) if k.trim() == "resolution" => "resolution = [24, 16]".into(),
                    Some((k, _)) if k.trim() == "samples" => "samples = 1".into(),
                    _ => l.to_string(),
                })
                .collect();
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                text.join("\n"),
            )
        })
        .collect()
}

fn backends() -> Vec<&'static str> {
    if cfg!(feature = "obvhs") {
        vec!["embree", "obvhs"]
    } else {
        vec!["embree"]
    }
}

/// One case: the files to write into its folder, the scene to run and how.
struct Case {
    files: Vec<(String, Vec<u8>)>,
    scene: String,
    command: &'static str,
    backend: &'static str,
    own_estimator: bool,
    all_outputs: bool,
}

/// Copies the bundled scenes' folders (meshes, photometry) into `dir` once.
fn copy_assets(dir: &Path) {
    for sub in ["meshes", "photometry", "gltf"] {
        let to = dir.join(sub);
        std::fs::create_dir_all(&to).unwrap();
        for entry in std::fs::read_dir(Path::new("scenes").join(sub)).unwrap() {
            let path = entry.unwrap().path();
            std::fs::copy(&path, to.join(path.file_name().unwrap())).unwrap();
        }
    }
}

fn scene_case(n: usize, scenes: &[(String, String)], corpus: &[String]) -> Case {
    let mut rng = Rng(0x5eed_0000 + n as u64);
    let (name, text) = rng.pick(scenes);
    let mut text = text.clone();
    for _ in 0..1 + rng.below(3) {
        text = mutate_text(&mut rng, &text, corpus);
    }
    let has_camera = text.contains("[camera]");
    Case {
        files: vec![(name.clone(), text.into_bytes())],
        scene: name.clone(),
        command: if has_camera && n % 8 == 3 {
            "render"
        } else {
            "run"
        },
        backend: backends()[n % backends().len()],
        own_estimator: n.is_multiple_of(6),
        all_outputs: n % 4 == 1,
    }
}

fn file_case(n: usize, corpus: &[String]) -> Case {
    let mut rng = Rng(0xf11e_0000 + n as u64);
    let carrier = rng.pick(CARRIERS);
    let bytes = std::fs::read(carrier.file).unwrap();
    let name = Path::new(carrier.file)
        .file_name()
        .unwrap()
        .to_string_lossy()
        .into_owned();
    let mut mutated = bytes;
    for _ in 0..1 + rng.below(3) {
        mutated = match String::from_utf8(mutated) {
            Ok(text) => mutate_text(&mut rng, &text, corpus).into_bytes(),
            Err(e) => mutate_bytes(&mut rng, e.as_bytes()),
        };
    }
    let file = format!("fuzzed_{name}");
    let scene = format!("{FLOOR}{}", carrier.scene.replace("{FILE}", &file));
    Case {
        files: vec![(file, mutated), ("carrier.toml".into(), scene.into_bytes())],
        scene: "carrier.toml".into(),
        command: "run",
        backend: backends()[n % backends().len()],
        own_estimator: n.is_multiple_of(3),
        all_outputs: n % 4 == 1,
    }
}

/// How a case ended: a result, a refusal, or what went wrong.
enum Ending {
    Result,
    Refused,
    Failed(String),
}

/// Runs `case` in `dir`.
fn run_case(case: &Case, dir: &Path) -> Ending {
    for (name, bytes) in &case.files {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    let out = dir.join(format!("out-{}", std::process::id()));
    let mut command = Command::new(env!("CARGO_BIN_EXE_luxtally"));
    command
        .current_dir(dir)
        .args([case.command, &case.scene, "--out"])
        .arg(&out)
        .args(["--photons", "2000", "--threads", "1", "--quiet"])
        .args(["--time-limit", "5", "--max-memory", "2G"])
        .args(["--backend", case.backend])
        .args(["--outputs", if case.all_outputs { "all" } else { "none" }])
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    if !case.own_estimator {
        command.args(["--estimator", "track"]);
    }
    let mut child = command.spawn().unwrap();
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > CASE_TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            return Ending::Failed(format!("no answer within {CASE_TIMEOUT:?}"));
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    let lines = stderr.trim().lines().count();
    match status.code() {
        Some(0) => Ending::Result,
        Some(1) if lines == 1 => Ending::Refused,
        Some(1) => Ending::Failed(format!("exit 1 with {lines} lines: {stderr}")),
        Some(code) => Ending::Failed(format!("exit {code}: {stderr}")),
        None => Ending::Failed(format!("killed by a signal ({status:?}): {stderr}")),
    }
}

/// Runs `count` cases made by `make` on two workers and asserts none failed.
fn run_cases(label: &str, count: usize, make: &(dyn Fn(usize) -> Case + Sync)) {
    let root = std::env::temp_dir().join(format!("luxtally-fuzz-{label}-{}", std::process::id()));
    let next = AtomicUsize::new(0);
    let failures = Mutex::new(Vec::new());
    let (results, refusals) = (AtomicUsize::new(0), AtomicUsize::new(0));
    std::thread::scope(|s| {
        for worker in 0..2 {
            let (root, next, failures) = (&root, &next, &failures);
            let (results, refusals) = (&results, &refusals);
            s.spawn(move || {
                let dir = root.join(format!("worker{worker}"));
                std::fs::create_dir_all(&dir).unwrap();
                copy_assets(&dir);
                loop {
                    let n = next.fetch_add(1, Ordering::Relaxed);
                    if n >= count {
                        break;
                    }
                    let case = make(n);
                    match run_case(&case, &dir) {
                        Ending::Result => {
                            results.fetch_add(1, Ordering::Relaxed);
                        }
                        Ending::Refused => {
                            refusals.fetch_add(1, Ordering::Relaxed);
                        }
                        Ending::Failed(what) => {
                            let keep = root.join(format!("case{n}"));
                            std::fs::create_dir_all(&keep).unwrap();
                            for (name, bytes) in &case.files {
                                std::fs::write(keep.join(name), bytes).unwrap();
                            }
                            failures.lock().unwrap().push(format!(
                                "{label} case {n} ({} {} on {}, kept in {}): {what}",
                                case.command,
                                case.scene,
                                case.backend,
                                keep.display()
                            ));
                        }
                    }
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    for worker in 0..2 {
        let _ = std::fs::remove_dir_all(root.join(format!("worker{worker}")));
    }
    eprintln!(
        "{label}: {count} cases on {:?}: {} results, {} one-line refusals, {} failures",
        backends(),
        results.into_inner(),
        refusals.into_inner(),
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn case_count() -> usize {
    std::env::var("LUXTALLY_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2000)
}

/// Every line of the bundled scenes and carriers: what mutations borrow.
fn corpus(scenes: &[(String, String)]) -> Vec<String> {
    scenes
        .iter()
        .map(|(_, t)| t.as_str())
        .chain([FLOOR, MESH_SCENE, LUMINAIRE_SCENE])
        .flat_map(|t| t.lines().map(str::to_string))
        .filter(|l| !l.trim().is_empty())
        .collect()
}

#[test]
fn mutated_scene_files_end_in_a_result_or_one_line() {
    let scenes = bundled_scenes();
    let corpus = corpus(&scenes);
    run_cases("scenes", case_count(), &|n| scene_case(n, &scenes, &corpus));
}

#[test]
fn mutated_mesh_and_photometry_files_end_in_a_result_or_one_line() {
    let corpus = corpus(&bundled_scenes());
    run_cases("files", case_count() / 2, &|n| file_case(n, &corpus));
}
