//! The command line as a user meets it: outputs of `run`, and one clear line with a
//! non-zero exit for every kind of bad input.

use std::path::PathBuf;
use std::process::{Command, Output};

fn luxtally(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args(args)
        .output()
        .expect("binary runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("luxtally-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Asserts a failed run: exit code 1 (bad input) or 2 (bad usage), one stderr line
/// containing every `needle`, no panic.
fn assert_fails_with(out: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        matches!(out.status.code(), Some(1 | 2)),
        "exit {:?}, stderr: {err}",
        out.status.code()
    );
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(
        !err.contains("panicked") && !err.contains("RUST_BACKTRACE"),
        "{err}"
    );
    for n in needles {
        assert!(err.contains(n), "`{n}` missing from: {err}");
    }
}

#[test]
fn run_writes_a_summary_with_every_contract_key() {
    let out_dir = temp_dir("office");
    let out = luxtally(&[
        "run",
        "scenes/office.toml",
        "--photons",
        "100000",
        "--quiet",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(out_dir.join("summary.json")).unwrap();
    let s: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in [
        "scene",
        "backend",
        "seed",
        "threads",
        "photons_emitted",
        "rays_traced",
        "elapsed_s",
        "stop_reason",
        "total_flux_lm",
        "receivers",
        "global",
        "history",
        "forecast",
    ] {
        assert!(s.get(key).is_some(), "summary.json lacks `{key}`");
    }
    assert_eq!(s["photons_emitted"], 100_000);
    assert_eq!(s["stop_reason"], "photons");
    let desk = &s["receivers"]["desk"];
    for key in [
        "quantity",
        "unit",
        "cells",
        "values",
        "sigma",
        "hits",
        "mean",
        "rel_error",
    ] {
        assert!(desk.get(key).is_some(), "desk lacks `{key}`");
    }
    assert_eq!(desk["values"].as_array().unwrap().len(), 64 * 32);
    for key in ["arithmetic", "quadratic"] {
        assert!(desk["rel_error"][key].as_f64().unwrap() > 0.0);
        assert!(s["global"]["rel_error"][key].as_f64().unwrap() > 0.0);
        assert!(s["global"]["indirect_rel_error"][key].as_f64().unwrap() > 0.0);
    }
    for key in ["triangles", "area_m2", "mean_illuminance_lx"] {
        assert!(s["global"].get(key).is_some(), "global lacks `{key}`");
    }
    assert!(s["forecast"].is_null(), "no target error, no forecast");
    let h = &s["history"][0];
    for key in ["elapsed_s", "photons", "rel_error"] {
        assert!(h.get(key).is_some(), "history lacks `{key}`");
    }
}

#[test]
fn missing_scene_file_is_one_line_naming_it() {
    assert_fails_with(
        &luxtally(&["run", "no/such/scene.toml", "--quiet"]),
        &["no/such/scene.toml"],
    );
}

#[test]
fn malformed_scene_is_one_line_naming_file_and_key() {
    let dir = temp_dir("bad");
    let path = dir.join("bad.toml");
    std::fs::write(
        &path,
        "[materials.m]\nreflectance = 0.7\nspecular_reflectance = 0.5\n",
    )
    .unwrap();
    assert_fails_with(
        &luxtally(&["run", path.to_str().unwrap(), "--quiet"]),
        &["bad.toml", "materials.m"],
    );
    std::fs::write(
        &path,
        "[[lights]]\ntype = \"point\"\nposition = [0, nan, 0]\nintensity_cd = 1\n",
    )
    .unwrap();
    assert_fails_with(
        &luxtally(&["run", path.to_str().unwrap(), "--quiet"]),
        &["bad.toml", "lights[0].position"],
    );
    std::fs::write(&path, "[[receivers]\nname = 3").unwrap();
    assert_fails_with(
        &luxtally(&["run", path.to_str().unwrap(), "--quiet"]),
        &["bad.toml"],
    );
}

#[test]
fn bad_command_line_values_are_one_line_each() {
    let out_dir = temp_dir("flags");
    let out = out_dir.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--target", "receiver:chair"], "--target"),
        (&["--target", "receiver:desk[0..99,0..1]"], "--target"),
        (&["--backend", "optix"], "--backend"),
        (&["--threads", "0"], "--threads"),
        (&["--target-error", "-1"], "--target-error"),
        (&["--time-limit", "0"], "--time-limit"),
        (&["--min-hits", "5", "--target", "global"], "--min-hits"),
        (&["--photons", "0"], "--photons"),
        (&["--photons", "many"], "--photons"),
        (&["--no-such-flag"], "--no-such-flag"),
    ];
    for (flags, needle) in cases {
        let mut args = vec!["run", "scenes/office.toml", "--quiet", "--out", out];
        args.extend_from_slice(flags);
        assert_fails_with(&luxtally(&args), &[needle]);
    }
}

/// `merge --threads 0` is refused as `run --threads 0` is, before any checkpoint is
/// read; so is a value that is none of a flag's names.
#[test]
fn merge_refuses_zero_threads_and_unknown_names_are_bad_input() {
    let out_dir = temp_dir("merge-threads");
    let out = out_dir.to_str().unwrap();
    let merge = luxtally(&["merge", "no/such/shard", "--out", out, "--threads", "0"]);
    assert_fails_with(&merge, &["--threads", "must be at least 1"]);
    assert_eq!(merge.status.code(), Some(1));
    let run = luxtally(&["run", "scenes/office.toml", "--threads", "0", "--out", out]);
    assert_eq!(run.stderr, merge.stderr, "the same refusal");
    let backend = luxtally(&["run", "scenes/office.toml", "--backend", "optix"]);
    assert_fails_with(&backend, &["--backend", "optix", "embree or obvhs"]);
    assert_eq!(backend.status.code(), Some(1));
}

#[cfg(not(feature = "obvhs"))]
#[test]
fn obvhs_backend_without_the_feature_says_how_to_get_it() {
    let out_dir = temp_dir("noobvhs");
    assert_fails_with(
        &luxtally(&[
            "run",
            "scenes/office.toml",
            "--quiet",
            "--backend",
            "obvhs",
            "--out",
            out_dir.to_str().unwrap(),
        ]),
        &["--features obvhs"],
    );
}

/// Polls until `path` exists (a run's readiness signal). Fails the test at once when the
/// child exits first, and after a generous bound meant only to end a hung run.
fn wait_for_file(child: &mut std::process::Child, path: &std::path::Path) {
    let start = std::time::Instant::now();
    while !path.exists() {
        if let Some(status) = child.try_wait().expect("wait") {
            let mut err = String::new();
            if let Some(mut e) = child.stderr.take() {
                let _ = std::io::Read::read_to_string(&mut e, &mut err);
            }
            panic!(
                "the run ended ({status}) before writing {}: {err}",
                path.display()
            );
        }
        if start.elapsed() > std::time::Duration::from_secs(600) {
            let _ = child.kill();
            panic!("no {} after 600 s: the run hangs", path.display());
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

#[test]
fn ctrl_c_stops_at_an_epoch_boundary_with_complete_outputs() {
    let out_dir = temp_dir("interrupt");
    // --report-every writes report.html at the end of the first epoch: the readiness
    // signal (the Ctrl-C handler is in place and photons are traced).
    let mut child = Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args([
            "run",
            "scenes/office.toml",
            "--photons",
            "100000000000",
            "--report-every",
            "3600",
            "--quiet",
            "--out",
            out_dir.to_str().unwrap(),
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("binary starts");
    wait_for_file(&mut child, &out_dir.join("report.html"));
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success());
    let out = child.wait_with_output().expect("run ends");
    assert!(
        out.status.success(),
        "exit {:?}: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(s["stop_reason"], "interrupted");
    let photons = s["photons_emitted"].as_u64().unwrap();
    assert!(photons > 0 && photons < 100_000_000_000);
    // Everything traced is in the output: the last history point is the final state.
    assert_eq!(
        s["history"].as_array().unwrap().last().unwrap()["photons"],
        photons
    );
    assert!(s["receivers"]["desk"]["mean"].as_f64().unwrap() > 0.0);
}

#[test]
fn until_decided_needs_requirements() {
    let dir = temp_dir("until");
    let scene = dir.join("s.toml");
    std::fs::write(
        &scene,
        "[[receivers]]\nname = \"r\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\ncells = [2, 2]\n",
    )
    .unwrap();
    let out = dir.join("out");
    let args = [
        "run",
        scene.to_str().unwrap(),
        "--until",
        "decided",
        "--out",
        out.to_str().unwrap(),
    ];
    assert_fails_with(
        &luxtally(&args),
        &["--until decided", "no [[requirements]]"],
    );
    let mut wrong = args;
    wrong[3] = "sure";
    assert_fails_with(&luxtally(&wrong), &["--until"]);
}

/// `luxtally tasks` lists every task type a requirement can name, with its values.
#[test]
fn tasks_lists_the_task_types() {
    let out = luxtally(&["tasks"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for t in luxtally::scene::tasks::TASK_TYPES {
        let line = text
            .lines()
            .find(|l| l.starts_with(&format!("{} ", t.id)))
            .unwrap_or_else(|| panic!("no line for {}", t.id));
        assert!(
            line.contains(t.title) && line.contains(&format!("{}", t.ugr_max)),
            "{line}"
        );
    }
}

/// DIR/day.toml holding `lights` and a 1-cell receiver, for the `sky` command; DIR is
/// a fresh temporary folder named `name`.
fn sky_scene(name: &str, lights: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let dir = temp_dir(name);
    let scene = dir.join("day.toml");
    let receiver =
        "[[receivers]]\nname = \"r\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\n\
                    cells = [1, 1]\n";
    std::fs::write(&scene, format!("{lights}{receiver}")).unwrap();
    (dir, scene)
}

/// `luxtally sky --patches MF --vector FILE`: the sky vector of Reinhart MF:2 (577
/// patches) as CSV, whose patch means reproduce the sky's exact horizontal
/// illuminance to the patch-uniform discretisation (Σ L̄·∫cos dω within 0.2 % for the
/// overcast sky; the solid angles sum to 2π); a bad MF is one line.
#[test]
fn sky_writes_a_reinhart_sky_vector() {
    let (dir, scene) = sky_scene(
        "sky-vector",
        "[[lights]]\ntype = \"sky\"\ncie_type = 16\nhorizontal_illuminance_lx = 7000\n",
    );
    let csv = dir.join("vector.csv");
    let s = scene.to_str().unwrap();
    let out = luxtally(&[
        "sky",
        s,
        "--patches",
        "2",
        "--vector",
        csv.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("Reinhart MF:2 (577 patches)"), "{text}");
    let rows: Vec<Vec<f64>> = std::fs::read_to_string(&csv)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').skip(1).map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 577);
    let (mut omega, mut e) = (0.0, 0.0);
    for r in &rows {
        let (s0, s1) = (libm::sin(r[1].to_radians()), libm::sin(r[2].to_radians()));
        let width = (r[4] - r[3]).to_radians();
        omega += r[5];
        e += r[7] * 0.5 * width * (s1 * s1 - s0 * s0);
    }
    assert!(
        (omega - 2.0 * std::f64::consts::PI).abs() < 1e-6,
        "Σ Ω = {omega}"
    );
    assert!((e / 7000.0 - 1.0).abs() < 2e-3, "E from the vector: {e}");
    let out = luxtally(&["sky", s, "--patches", "13"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        err.contains("--patches") && err.trim().lines().count() == 1,
        "{err}"
    );
}

/// `luxtally sky SCENE` describes each sky and sun: model, Lz, horizontal illuminance,
/// the sun's position.
#[test]
fn sky_describes_the_daylight_sources() {
    let (_, scene) = sky_scene(
        "sky-command",
        "[[lights]]\ntype = \"sky\"\ncie_type = 16\nhorizontal_illuminance_lx = 7000\n\
         [[lights]]\ntype = \"sun\"\ndirect_normal_lx = 50000\nsun_altitude_deg = 40\nsun_azimuth_deg = 135\n",
    );
    let out = luxtally(&["sky", scene.to_str().unwrap()]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    // Type 16: E_h = 7π/9·Lz, so Lz = 7000·9/(7π) = 2864.79 cd/m².
    for needle in [
        "traditional overcast",
        "Lz 2864.79",
        "7000.0 lx",
        "altitude 40.000°",
        "azimuth 135.000°",
    ] {
        assert!(text.contains(needle), "`{needle}` not in: {text}");
    }
}

/// `luxtally sky` on a Perez sky prints ε, Δ and the direct normal illuminance its sun
/// should get; `luxtally weather` prints an EPW file's summary, and refuses a truncated
/// one in one line.
#[test]
fn perez_sky_and_weather_commands_print_their_summaries() {
    let (dir, scene) = sky_scene(
        "perez-weather",
        "[[lights]]\ntype = \"sky\"\nmodel = \"perez\"\ndirect_normal_irradiance_wm2 = 700\n\
         diffuse_horizontal_irradiance_wm2 = 100\nsun_altitude_deg = 60\nsun_azimuth_deg = 180\nday_of_year = 172\n",
    );
    let out = luxtally(&["sky", scene.to_str().unwrap()]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    // By hand (tests/suite/physics/perez.rs): E_dh 13318.7 lx, E_dn 72426.9 lx.
    for needle in [
        "Perez all-weather sky",
        "category 8",
        "13318.7 lx",
        "direct_normal_lx = 72426.9",
    ] {
        assert!(text.contains(needle), "`{needle}` not in: {text}");
    }
    let mut epw = String::from(
        "LOCATION,Berlin,BE,DEU,test,103840,52.47,13.40,1.0,49.0\nDESIGN CONDITIONS,0\n\
         TYPICAL/EXTREME PERIODS,0\nGROUND TEMPERATURES,0\nHOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\n\
         COMMENTS 1,x\nCOMMENTS 2,x\nDATA PERIODS,1,1,Data,Sunday, 1/ 1, 1/ 1\n",
    );
    for h in 1..=24 {
        epw += &format!(
            "2026,1,1,{h},60,flags,2,-1,80,101325,0,0,300,100,200,50,10000,20000,5000,9999,180,3,5,5,20,77777,9,999999999,10,0.1,0,88,0.2,0,0\n"
        );
    }
    let file = dir.join("b.epw");
    std::fs::write(&file, &epw).unwrap();
    let out = luxtally(&["weather", file.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "Berlin: latitude 52.47°",
        "24 hourly records",
        "0 missing",
        "direct normal 4.8",
    ] {
        assert!(text.contains(needle), "`{needle}` not in: {text}");
    }
    let cut: String = epw.lines().take(20).map(|l| format!("{l}\n")).collect();
    std::fs::write(&file, cut).unwrap();
    let out = luxtally(&["weather", file.to_str().unwrap()]);
    assert_fails_with(
        &out,
        &["b.epw", "12 hourly records", "makes 24", "truncated"],
    );
}

/// `luxtally annual` on a one-day weather file writes its files and prints its verdicts;
/// bad input is one line each: no `[annual]`, bad keys, a missing or truncated weather
/// file.
#[test]
fn annual_runs_and_refuses_bad_input_in_one_line() {
    let dir = temp_dir("annual");
    let office = std::fs::read_to_string("scenes/daylit_office.toml")
        .unwrap()
        .replace("cells = [12, 20]", "cells = [3, 4]");
    let mut epw = String::from(
        "LOCATION,Golden,CO,USA,test,724666,39.74,-105.18,-7.0,1829.0\nDESIGN CONDITIONS,0\n\
         TYPICAL/EXTREME PERIODS,0\nGROUND TEMPERATURES,0\nHOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\n\
         COMMENTS 1,test\nCOMMENTS 2,test\nDATA PERIODS,1,1,Data,Sunday, 6/21, 6/21\n",
    );
    for h in 1..=24 {
        let (dni, dhi) = if (7..=18).contains(&h) {
            (500, 100)
        } else {
            (0, 0)
        };
        epw += &format!(
            "1990,6,21,{h},60,?9,20.0,5.0,40,81000,0,0,300,{},{dni},{dhi},999999,999999,999999,9999,180,3.0,5,5,20.0,77777,9,999999999,10,0.1,0,88,0.2,0,0\n",
            dni / 2 + dhi
        );
    }
    std::fs::write(dir.join("day.epw"), &epw).unwrap();
    let truncated: String = epw.lines().take(20).map(|l| format!("{l}\n")).collect();
    std::fs::write(dir.join("short.epw"), truncated).unwrap();
    let write = |name: &str, table: &str| {
        let path = dir.join(name);
        std::fs::write(&path, format!("{office}\n{table}\n")).unwrap();
        path.display().to_string()
    };
    let good = write(
        "good.toml",
        "[annual]\nweather = \"day.epw\"\nmf = 1\nsun_mf = 2\nphotons = 100_000",
    );
    let out_dir = dir.join("out");
    let out = luxtally(&[
        "annual",
        &good,
        "--out",
        out_dir.to_str().unwrap(),
        "--quiet",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("sDA300/50 %") && stdout.contains("EN 17037 minimum level"),
        "{stdout}"
    );
    for f in [
        "annual.json",
        "annual.html",
        "annual_df_grid.csv",
        "annual_df_grid_hours.csv",
        "annual_df_grid_hourly.bin",
    ] {
        assert!(out_dir.join(f).is_file(), "{f} missing");
    }
    let cases: [(&str, &str, &[&str]); 6] = [
        ("none.toml", "", &["no [annual] table"]),
        (
            "mf.toml",
            "[annual]\nweather = \"day.epw\"\nmf = 0",
            &["annual.mf", "MF"],
        ),
        (
            "key.toml",
            "[annual]\nweather = \"day.epw\"\nsky = 1",
            &["annual", "sky"],
        ),
        (
            "recv.toml",
            "[annual]\nweather = \"day.epw\"\nreceivers = [\"desk\"]",
            &["annual.receivers", "desk"],
        ),
        (
            "missing.toml",
            "[annual]\nweather = \"nowhere.epw\"",
            &["nowhere.epw"],
        ),
        (
            "short.toml",
            "[annual]\nweather = \"short.epw\"",
            &["short.epw"],
        ),
    ];
    for (name, table, needles) in cases {
        let path = write(name, table);
        assert_fails_with(
            &luxtally(&["annual", &path, "--out", out_dir.to_str().unwrap()]),
            needles,
        );
    }
}

/// `bench-accuracy` on the office to 2 % with `extra` flags: its output and the rows of
/// its rays table.
fn bench_accuracy_table(extra: &[&str]) -> (String, Vec<Vec<f64>>) {
    let args = [
        "bench-accuracy",
        "scenes/office.toml",
        "--target-error",
        "0.02",
    ];
    let out = luxtally(&[&args[..], &["--threads", "2"], extra].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let header = "| goal % | photons | photon rays | direct rays | rays | elapsed s | error % |";
    let table = text.split(header).nth(1).expect("the rays table");
    let rows: Vec<Vec<f64>> = (table.lines().skip(2))
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            (l.trim_matches('|').split('|'))
                .map(|x| x.trim().parse().unwrap())
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 2, "goals 5 and 2 %: {table}");
    (text, rows)
}

/// `bench-accuracy` ends with the rays to each goal down to its target: one row per
/// goal, each run stopped at its error, photons and rays growing as the goal tightens.
#[test]
fn bench_accuracy_reports_the_rays_to_each_goal() {
    let (_, rows) = bench_accuracy_table(&[]);
    for (row, goal) in rows.iter().zip([5.0, 2.0]) {
        assert_eq!(row[0], goal);
        assert!(row[6] <= goal, "error {} beyond its goal {goal}", row[6]);
        assert_eq!(row[4], row[2] + row[3], "rays add up");
    }
    assert!(rows[1][1] > rows[0][1] && rows[1][4] > rows[0][4]);
}

/// `bench-accuracy --qmc` measures the QMC run: its heading says so, and every run of its
/// table stops on whole blocks, none before the 32 whose σ is reported.
#[test]
fn bench_accuracy_measures_qmc_runs() {
    let (text, rows) = bench_accuracy_table(&["--qmc"]);
    assert!(text.contains("next_event estimator, QMC"), "{text}");
    let photons: Vec<u64> = rows.iter().map(|r| r[1] as u64).collect();
    assert!(
        photons.iter().all(|&p| p % 4096 == 0 && p >= 32 * 2048),
        "{photons:?}"
    );
}

/// `--qmc` on a scene of luminance meters alone says it cannot help there, and runs;
/// on a scene with an illuminance grid it says nothing of the kind.
#[test]
fn qmc_on_luminance_meters_alone_says_it_gains_nothing() {
    let dir = temp_dir("qmc-meters");
    let scene = |name: &str| format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR"));
    let stderr_of_run = |name: &str| {
        let out = dir.join(name);
        let out = out.to_str().unwrap().to_string();
        let o = luxtally(&[
            "run",
            &scene(name),
            "--qmc",
            "--photons",
            "4096",
            "--quiet",
            "--out",
            &out,
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    assert!(stderr_of_run("office_luminance.toml").contains("expect no gain"));
    assert!(!stderr_of_run("office.toml").contains("expect no gain"));
}
