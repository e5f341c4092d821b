//! Checkpoints (#15): a run killed with SIGKILL and resumed, again and again, ends
//! bit-identical to one never stopped; shards merged end bit-identical to one run; a
//! checkpoint that does not fit is refused in one line.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

const SCENE: &str = "scenes/office.toml";
/// An area source: the direct light's replicates grow past the pilot during the run, so
/// its schedule is part of what must come out the same.
const CORNELL: &str = "scenes/cornell.toml";
/// Requirements on many receivers and observers: the history counts their checks.
const OFFICE_CHECKS: &str = "scenes/en12464_office.toml";

fn luxtally(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args(args)
        .output()
        .expect("binary runs")
}

fn spawn(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary starts")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("luxtally-resume-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn ok(out: Output) {
    assert!(
        out.status.success(),
        "exit {:?}: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// summary.json without what depends on the clock or the epochs (times, shares, FOM,
/// history, forecast, threads, stop reason).
fn numbers_of(dir: &Path) -> Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let mut s: Value = serde_json::from_str(&text).unwrap();
    let o = s.as_object_mut().unwrap();
    for k in [
        "elapsed_s",
        "setup_s",
        "direct_s",
        "stats_s",
        "stats_share",
        "merge_s",
        "merge_share",
        "history",
        "forecast",
        "reliability",
        "threads",
        "stop_reason",
    ] {
        assert!(o.remove(k).is_some(), "summary.json has no {k}");
    }
    for r in o["receivers"].as_object_mut().unwrap().values_mut() {
        r.as_object_mut().unwrap().remove("fom");
    }
    s
}

/// The two runs' numbers, bit for bit: summary.json's values (printed shortest
/// round-trip, so equal text is equal bits), the indirect map and the receiver files.
fn assert_identical(a: &Path, b: &Path) {
    let (x, y) = (numbers_of(a), numbers_of(b));
    for (k, v) in x.as_object().unwrap() {
        assert_eq!(
            v.to_string(),
            y[k].to_string(),
            "summary.json `{k}` differs between {} and {}",
            a.display(),
            b.display()
        );
    }
    let mut files = vec![PathBuf::from("indirect_map.bin")];
    for e in std::fs::read_dir(a.join("receivers")).unwrap() {
        let f = Path::new("receivers").join(e.unwrap().file_name());
        if f.extension().is_some_and(|x| x == "csv" || x == "exr") {
            files.push(f);
        }
    }
    assert!(files.len() >= 3, "{files:?}");
    for f in files {
        assert!(
            std::fs::read(a.join(&f)).unwrap() == std::fs::read(b.join(&f)).unwrap(),
            "{} differs",
            f.display()
        );
    }
}

/// A pseudo-random delay in 0..max_ms, different in every run of the test.
fn random_ms(max_ms: u64, salt: u64) -> u64 {
    let t = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .subsec_nanos() as u64;
    let mut z = t ^ salt.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ std::process::id() as u64;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    (z ^ (z >> 27)) % max_ms
}

/// Polls until the run wrote a checkpoint other than `before` (it has made progress)
/// or ended; returns whether it is still running.
fn wait_for_new_checkpoint(child: &mut Child, dir: &Path, before: &Option<Vec<u8>>) -> bool {
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return false;
        }
        let now = std::fs::read(dir.join("checkpoint.bin")).ok();
        if now.is_some() && &now != before {
            return true;
        }
        assert!(
            start.elapsed() < Duration::from_secs(600),
            "no checkpoint after 600 s: the run hangs"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Runs `run BASE` into `dir`, killed (SIGKILL) at random times after new checkpoints
/// and resumed, a few rounds, then resumed to its end; asserts that it was killed and
/// resumed at least once.
fn kill_and_resume(base: &[&str], dir: &Path) {
    let d = dir.to_str().unwrap();
    let mut kills = 0;
    let mut resumes = 0;
    for round in 0..4 {
        let mut args = vec!["run"];
        args.extend(base);
        args.extend(["--checkpoint-every", "0.1"]);
        if round == 0 {
            args.extend(["--out", d]);
        } else {
            args.extend(["--resume", d]);
            resumes += 1;
        }
        let before = std::fs::read(dir.join("checkpoint.bin")).ok();
        let mut child = spawn(&args);
        if !wait_for_new_checkpoint(&mut child, dir, &before) {
            break;
        }
        // Anywhere in the next few checkpoints, mid-epoch or mid-save.
        std::thread::sleep(Duration::from_millis(random_ms(400, round)));
        if child.try_wait().unwrap().is_none() {
            child.kill().unwrap();
            kills += 1;
        }
        child.wait().unwrap();
    }
    let mut args = vec!["run"];
    args.extend(base);
    args.extend(["--resume", d]);
    ok(luxtally(&args));
    assert!(
        kills >= 1 && resumes >= 1,
        "{kills} kills, {resumes} resumes"
    );
}

/// summary.json's history: per point, its photons, then its error and checks' counts as
/// text (equal text is equal bits).
fn history_of(dir: &Path) -> Vec<(u64, String)> {
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let s: Value = serde_json::from_str(&text).unwrap();
    s["history"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let numbers = format!("{} {}", p["rel_error"], p["checks"]);
            (p["photons"].as_u64().unwrap(), numbers)
        })
        .collect()
}

/// A scene with requirements, killed and resumed: every point of its history, those
/// saved in the checkpoints too, counts the checks, and at every photon count both runs
/// reached (the epochs follow the clock, but end at every schedule point) the error and
/// the counts are the uninterrupted run's.
#[test]
fn a_resumed_run_keeps_the_verdict_history_of_an_uninterrupted_one() {
    let full = temp_dir("verdicts-full");
    let base = [
        OFFICE_CHECKS,
        "--photons",
        "2000000",
        "--seed",
        "3",
        "--quiet",
    ];
    let mut args = vec!["run"];
    args.extend(base);
    args.extend(["--out", full.to_str().unwrap()]);
    ok(luxtally(&args));
    let dir = temp_dir("verdicts-killed");
    kill_and_resume(&base, &dir);
    let (a, b) = (history_of(&full), history_of(&dir));
    for (photons, numbers) in a.iter().chain(&b) {
        assert!(!numbers.ends_with("null"), "{photons} photons: no counts");
    }
    let uninterrupted: std::collections::HashMap<_, _> = a.iter().cloned().collect();
    let mut common = 0;
    for (photons, numbers) in &b {
        if let Some(expected) = uninterrupted.get(photons) {
            assert_eq!(numbers, expected, "at {photons} photons");
            common += 1;
        }
    }
    // The schedule points 4096 · 2^k up to 2·10⁶, and the end.
    assert!(common >= 10, "{common} photon counts in common");
    assert_eq!(a.last(), b.last());
}

#[test]
fn killed_and_resumed_runs_end_bit_identical_to_an_uninterrupted_one() {
    let full = temp_dir("full");
    let base = [CORNELL, "--photons", "3000000", "--seed", "11", "--quiet"];
    let mut args = vec!["run"];
    args.extend(base);
    args.extend(["--out", full.to_str().unwrap()]);
    ok(luxtally(&args));

    let dir = temp_dir("killed");
    kill_and_resume(&base, &dir);
    assert_identical(&full, &dir);
    let s = numbers_of(&dir);
    assert_eq!(s["photons_emitted"], 3_000_000);
    assert!(
        s["direct_replicates"].as_u64().unwrap() > 16,
        "the direct light's schedule added replicates past the pilot"
    );
}

#[test]
fn merged_shards_are_bit_identical_to_one_run() {
    let photons = "700000";
    let full = temp_dir("single");
    ok(luxtally(&[
        "run",
        CORNELL,
        "--photons",
        photons,
        "--seed",
        "5",
        "--quiet",
        "--threads",
        "1",
        "--out",
        full.to_str().unwrap(),
    ]));
    let mut shards = Vec::new();
    for i in 0..3 {
        let dir = temp_dir(&format!("shard{i}"));
        let shard = format!("{i}/3");
        ok(luxtally(&[
            "run",
            CORNELL,
            "--photons",
            photons,
            "--seed",
            "5",
            "--quiet",
            "--shard",
            &shard,
            "--out",
            dir.to_str().unwrap(),
        ]));
        assert!(dir.join("checkpoint.bin").exists());
        assert!(
            !dir.join("summary.json").exists(),
            "a shard alone has no outputs"
        );
        shards.push(dir.to_str().unwrap().to_string());
    }
    let merged = temp_dir("merged");
    // Any order of the directories.
    ok(luxtally(&[
        "merge",
        &shards[2],
        &shards[0],
        &shards[1],
        "--out",
        merged.to_str().unwrap(),
    ]));
    assert_identical(&full, &merged);
    assert!(numbers_of(&merged)["direct_replicates"].as_u64().unwrap() > 16);

    let missing = luxtally(&[
        "merge",
        &shards[0],
        &shards[2],
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert_one_line(&missing, &["shard 1/3 is missing"]);
    let twice = luxtally(&[
        "merge",
        &shards[0],
        &shards[1],
        &shards[1],
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert_one_line(&twice, &["given twice"]);
}

/// Ctrl-C (SIGINT) mid-epoch: the run stops at the chunks traced in order so far, on a
/// multiple of the chunk size, with its outputs and checkpoint, and resuming it ends
/// bit-identical to a run never interrupted.
#[test]
fn an_interrupted_run_resumes_to_the_same_bits() {
    let (dir, full) = (temp_dir("sigint"), temp_dir("sigint_full"));
    let base = [
        "run",
        SCENE,
        "--photons",
        "6000000",
        "--seed",
        "4",
        "--quiet",
    ];
    fn with<'a>(base: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
        [base, extra].concat()
    }
    let out = ["--out", dir.to_str().unwrap(), "--checkpoint-every", "0.1"];
    let mut child = spawn(&with(&base, &out));
    // After its first epoch: the Ctrl-C handler is in place.
    assert!(wait_for_new_checkpoint(&mut child, &dir, &None));
    let pid = child.id().to_string();
    let sent = Command::new("kill").args(["-INT", &pid]).status().unwrap();
    assert!(sent.success());
    child.wait().unwrap();
    let interrupted = numbers_of(&dir);
    let photons = interrupted["photons_emitted"].as_u64().unwrap();
    let summary: Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["stop_reason"], "interrupted", "{summary:?}");
    assert!(
        photons < 12_000_000 && photons.is_multiple_of(4096),
        "{photons} photons"
    );
    ok(luxtally(&with(&base, &["--resume", dir.to_str().unwrap()])));
    ok(luxtally(&with(&base, &["--out", full.to_str().unwrap()])));
    assert_identical(&dir, &full);
}

/// Portal photons (the daylit office under the sky and the sun: two distant lights,
/// a portal, glazing) are a pure function of the photon index too: one thread, two,
/// and two shards merged give the same bits.
#[test]
fn portal_photons_give_the_same_bits_on_any_threads_and_shards() {
    let scene = "scenes/daylit_office_sun.toml";
    let base = [
        "run",
        scene,
        "--photons",
        "300000",
        "--seed",
        "3",
        "--quiet",
    ];
    let run = |name: &str, extra: &[&str]| run_in(name, &base, extra);
    let one = run("portal_t1", &["--threads", "1"]);
    let two = run("portal_t2", &["--threads", "2"]);
    assert_identical(&one, &two);
    let shards: Vec<String> = (0..2)
        .map(|i| {
            let dir = run(&format!("portal_shard{i}"), &["--shard", &format!("{i}/2")]);
            dir.to_str().unwrap().to_string()
        })
        .collect();
    let merged = temp_dir("portal_merged");
    ok(luxtally(&[
        "merge",
        &shards[1],
        &shards[0],
        "--out",
        merged.to_str().unwrap(),
    ]));
    assert_identical(&one, &merged);
}

/// A QMC run (`--qmc`) is a pure function of the photon index too: one thread, two, two
/// shards merged, and a run resumed from a smaller one's checkpoint give the same bits;
/// --photons rounds up to whole blocks; resuming without --qmc is refused in one line.
#[test]
fn qmc_runs_give_the_same_bits_on_any_threads_shards_and_resumes() {
    let base = ["run", SCENE, "--seed", "5", "--quiet", "--qmc"];
    let run = |name: &str, extra: &[&str]| run_in(name, &base, extra);
    let photons = ["--photons", "300000"];
    let one = run("qmc_t1", &[&photons[..], &["--threads", "1"]].concat());
    assert_eq!(
        numbers_of(&one)["photons_emitted"],
        303_104,
        "74 whole chunks"
    );
    let two = run("qmc_t2", &[&photons[..], &["--threads", "2"]].concat());
    assert_identical(&one, &two);
    let shards: Vec<String> = (0..2)
        .map(|i| {
            let shard = format!("{i}/2");
            let dir = run(
                &format!("qmc_shard{i}"),
                &[&photons[..], &["--shard", &shard]].concat(),
            );
            dir.to_str().unwrap().to_string()
        })
        .collect();
    let merged = temp_dir("qmc_merged");
    ok(luxtally(&[
        "merge",
        &shards[0],
        &shards[1],
        "--out",
        merged.to_str().unwrap(),
    ]));
    assert_identical(&one, &merged);
    let first = run("qmc_first", &["--photons", "150000"]);
    let resumed = ["--resume", first.to_str().unwrap()];
    ok(luxtally(&[&base[..], &photons[..], &resumed[..]].concat()));
    assert_identical(&one, &first);
    let plain = [&base[..5], &photons[..], &resumed[..]].concat();
    assert_one_line(&luxtally(&plain), &["QMC differs"]);
}

/// Runs `base` and `extra` into a fresh folder `name`, which it returns.
fn run_in(name: &str, base: &[&str], extra: &[&str]) -> PathBuf {
    let dir = temp_dir(name);
    let out = ["--out", dir.to_str().unwrap()];
    ok(luxtally(&[base, extra, &out[..]].concat()));
    dir
}

fn assert_one_line(out: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "stderr: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` missing from: {err}");
    }
}

#[test]
fn a_checkpoint_that_does_not_fit_is_refused_in_one_line() {
    let dir = temp_dir("refuse");
    let d = dir.to_str().unwrap();
    ok(luxtally(&[
        "run",
        SCENE,
        "--photons",
        "20000",
        "--seed",
        "2",
        "--quiet",
        "--out",
        d,
    ]));
    let resume = |extra: &[&str]| {
        let mut args = vec!["run", SCENE, "--quiet", "--resume", d];
        args.extend(extra);
        luxtally(&args)
    };
    assert_one_line(
        &resume(&["--seed", "3"]),
        &["checkpoint.bin", "seed differs"],
    );
    assert_one_line(
        &resume(&["--seed", "2", "--estimator", "track"]),
        &["--estimator differs"],
    );
    assert_one_line(
        &resume(&["--seed", "2", "--photons", "10000"]),
        &["--photons", "fewer"],
    );
    // Another scene: the office with a brighter lamp.
    let text = std::fs::read_to_string(SCENE).unwrap();
    let changed = text.replacen("intensity_cd = 1000", "intensity_cd = 1001", 1);
    assert_ne!(changed, text, "the office has a lamp to change");
    let other = dir.join("brighter.toml");
    std::fs::write(&other, changed).unwrap();
    let out = luxtally(&[
        "run",
        other.to_str().unwrap(),
        "--quiet",
        "--seed",
        "2",
        "--resume",
        d,
    ]);
    assert_one_line(&out, &["scene differs"]);
    // Growing --photons goes on.
    ok(resume(&["--seed", "2", "--photons", "30000"]));
    let s = numbers_of(&dir);
    assert_eq!(s["photons_emitted"], 30000);
    // Damaged files.
    let bytes = std::fs::read(dir.join("checkpoint.bin")).unwrap();
    std::fs::write(dir.join("checkpoint.bin"), &bytes[..bytes.len() / 2]).unwrap();
    assert_one_line(&resume(&["--seed", "2"]), &["checkpoint.bin", "truncated"]);
    let mut flipped = bytes.clone();
    let k = bytes.len() - 5;
    flipped[k] ^= 0x10;
    std::fs::write(dir.join("checkpoint.bin"), &flipped).unwrap();
    assert_one_line(&resume(&["--seed", "2"]), &["checkpoint.bin", "checksum"]);
    std::fs::write(dir.join("checkpoint.bin"), b"not a checkpoint").unwrap();
    assert_one_line(&resume(&["--seed", "2"]), &["not a luxtally checkpoint"]);
}
