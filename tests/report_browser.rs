//! report.html in a real browser: Debian's chromium, headless, with networking off,
//! opens the report of a finished run, of a live run (--report-every) and of a run
//! stopped by Ctrl-C (SIGINT); every chart must have drawn (`data-rendered="1"` on each
//! `data-chart` container), the page's error box must be empty and the console must
//! show no uncaught error. Screenshots are saved as test artifacts in
//! `<cargo target dir>/test-artifacts/` (`report.png`, `report_live.png`,
//! `report_interrupted.png`, `report_edge.png`, `report_decided.png`, `report_sky.png`).
//! The template's marching squares (the isolux contours) also run there on small grids.
//!
//! Without chromium (/usr/bin/chromium, or the path in `LUXTALLY_CHROMIUM`; scripts/setup.sh
//! installs it) every test reports as ignored, with the reason: this file has its own
//! harness (libtest-mimic), which can ignore a test at run time, as libtest cannot.

use libtest_mimic::{Arguments, Completion, Failed, Trial};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const DEFAULT_CHROMIUM: &str = "/usr/bin/chromium";

/// The browser: `LUXTALLY_CHROMIUM` when set, else Debian's chromium.
fn chromium_path() -> PathBuf {
    std::env::var_os("LUXTALLY_CHROMIUM").map_or_else(|| DEFAULT_CHROMIUM.into(), PathBuf::from)
}

fn main() {
    let args = Arguments::from_args();
    let tests: [(&str, fn()); 6] = [
        (
            "report_of_a_finished_run_renders_every_chart_offline",
            report_of_a_finished_run_renders_every_chart_offline,
        ),
        (
            "reports_of_a_live_run_and_of_a_run_stopped_by_ctrl_c_render",
            reports_of_a_live_run_and_of_a_run_stopped_by_ctrl_c_render,
        ),
        (
            "report_of_dark_tall_and_luminance_receivers_renders",
            report_of_dark_tall_and_luminance_receivers_renders,
        ),
        (
            "report_of_a_decided_run_draws_the_verdict_history",
            report_of_a_decided_run_draws_the_verdict_history,
        ),
        (
            "contours_close_around_a_peak_skip_gaps_and_split_saddles",
            contours_close_around_a_peak_skip_gaps_and_split_saddles,
        ),
        (
            "report_of_a_sky_scene_draws_each_skys_fisheye",
            report_of_a_sky_scene_draws_each_skys_fisheye,
        ),
    ];
    let trials = tests
        .into_iter()
        .map(|(name, test)| {
            Trial::ignorable_test(name, move || {
                let browser = chromium_path();
                if !browser.exists() {
                    return Ok(Completion::ignored_with(format!(
                        "no chromium at {}; scripts/setup.sh installs it",
                        browser.display()
                    )));
                }
                // A panic (a failed assert) is a failure: libtest-mimic catches it, and
                // the panic message is on stderr.
                test();
                Ok::<_, Failed>(Completion::Completed)
            })
        })
        .collect();
    libtest_mimic::run(&args, trials).exit();
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("luxtally-browser-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// `<target dir>/test-artifacts`, found from the binary under test
/// (`<target dir>/<profile>/luxtally`).
fn artifacts_dir() -> PathBuf {
    let bin = Path::new(env!("CARGO_BIN_EXE_luxtally"));
    let dir = bin
        .parent()
        .and_then(Path::parent)
        .unwrap_or(Path::new("target"))
        .join("test-artifacts");
    std::fs::create_dir_all(&dir).expect("artifacts dir");
    dir
}

/// Headless chromium with every network feature off and a throw-away profile.
fn chromium(extra: &[&str], page: &Path) -> std::process::Output {
    let profile = temp_dir(&format!(
        "profile-{}",
        page.file_stem().unwrap().to_string_lossy()
    ));
    let url = format!(
        "file://{}",
        page.canonicalize().expect("page exists").display()
    );
    let mut args = vec![
        "90".to_string(),
        chromium_path().display().to_string(),
        "--headless".into(),
        "--no-sandbox".into(),
        "--disable-gpu".into(),
        "--disable-background-networking".into(),
        "--disable-component-update".into(),
        "--disable-sync".into(),
        "--no-first-run".into(),
        "--disable-extensions".into(),
        // Any request to a host fails: the page must need none.
        "--host-resolver-rules=MAP * ~NOTFOUND".into(),
        "--enable-logging=stderr".into(),
        "--v=0".into(),
        format!("--user-data-dir={}", profile.display()),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    args.push(url);
    let out = Command::new("timeout")
        .args(&args)
        .stdin(Stdio::null())
        .output()
        .expect("chromium runs");
    let _ = std::fs::remove_dir_all(&profile);
    out
}

/// Opens `report` (through a copy, `view-NAME.html`: the run may rewrite the original) and checks that it rendered; saves
/// `<artifacts>/name.png`. `other_charts`: the verdict history and the luminaires' polar
/// diagrams and UGR tables. Returns the rendered page (the DOM).
fn assert_report_renders(
    report: &Path,
    name: &str,
    receivers: usize,
    other_charts: usize,
) -> String {
    let page = report.with_file_name(format!("view-{name}.html"));
    std::fs::copy(report, &page).expect("copy report");
    let dom = chromium(&["--dump-dom"], &page);
    let html = String::from_utf8_lossy(&dom.stdout);
    let log = String::from_utf8_lossy(&dom.stderr);
    assert!(
        html.contains("data-report-done=\"1\""),
        "{name}: the script ran to its end\n{log}"
    );
    let charts = html.matches("data-chart=").count();
    let rendered = html.matches("data-rendered=\"1\"").count();
    assert_eq!(
        charts,
        1 + 5 * receivers + other_charts,
        "{name}: accuracy chart + 5 per receiver + {other_charts} others"
    );
    assert_eq!(rendered, charts, "{name}: every chart rendered");
    assert_eq!(
        html.matches("data-receiver=").count(),
        receivers,
        "{name}: one results row per receiver"
    );
    assert!(
        html.contains("<pre id=\"errors\"></pre>"),
        "{name}: the page reported errors: {}",
        html.split("<pre id=\"errors\">")
            .nth(1)
            .unwrap_or("")
            .split("</pre>")
            .next()
            .unwrap_or("")
    );
    for line in log.lines().filter(|l| l.contains("CONSOLE")) {
        assert!(
            !line.contains("Uncaught") && !line.contains("Error"),
            "{name}: console: {line}"
        );
    }
    let shot = artifacts_dir().join(format!("{name}.png"));
    let _ = std::fs::remove_file(&shot);
    let out = chromium(
        &[
            &format!("--screenshot={}", shot.display()),
            "--window-size=1200,2300",
            "--hide-scrollbars",
        ],
        &page,
    );
    assert!(
        shot.exists(),
        "{name}: screenshot saved\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    eprintln!("{name}: screenshot in {}", shot.display());
    html.into_owned()
}

/// Points in the history of the summary embedded in a report page (`const S = {...};`).
fn report_history_len(page: &Path) -> usize {
    let Ok(html) = std::fs::read_to_string(page) else {
        return 0;
    };
    let json = html
        .split_once("const S = ")
        .and_then(|(_, rest)| rest.split_once(";\n"))
        .map_or("", |(json, _)| json);
    serde_json::from_str::<serde_json::Value>(json)
        .ok()
        .and_then(|s| s["history"].as_array().map(Vec::len))
        .unwrap_or(0)
}

fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("JSON")
}

fn report_of_a_finished_run_renders_every_chart_offline() {
    let dir = temp_dir("finished");
    let out = Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args([
            "run",
            "scenes/office.toml",
            "--photons",
            "20000000",
            "--target-error",
            "0.1",
        ])
        .args(["--quiet", "--out", dir.to_str().unwrap()])
        .output()
        .expect("binary runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(summary(&dir)["stop_reason"], "target_error");
    let html = assert_report_renders(&dir.join("report.html"), "report", 1, 0);
    assert!(
        html.contains("data-contours=\""),
        "the desk's map draws its isolux contours"
    );
}

fn reports_of_a_live_run_and_of_a_run_stopped_by_ctrl_c_render() {
    let dir = temp_dir("interrupted");
    let mut child = Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args(["run", "scenes/office.toml", "--photons", "100000000000"])
        .args(["--report-every", "1", "--quiet", "--threads", "1"])
        .args(["--out", dir.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary starts");
    // Readiness: the live report (rewritten every second) has a few epochs of history
    // to plot. Checked on a copy, which is also the page opened below.
    let report = dir.join("report.html");
    let live = dir.join("live.html");
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("wait") {
            panic!("the run ended ({status}) before its live report had 3 epochs");
        }
        if std::fs::copy(&report, &live).is_ok() && report_history_len(&live) >= 3 {
            break;
        }
        if start.elapsed() > Duration::from_secs(600) {
            let _ = child.kill();
            panic!("no live report.html with 3 epochs after 600 s: the run hangs");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let live_html = std::fs::read_to_string(&live).unwrap();
    assert!(
        live_html.contains("<meta http-equiv=\"refresh\" content=\"1\">"),
        "the live page reloads itself"
    );
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(kill.success());
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        // A bound only to end a hung run, no statement about speed.
        if start.elapsed() > Duration::from_secs(600) {
            let _ = child.kill();
            panic!("the run did not end within 600 s of SIGINT: it hangs");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        use std::io::Read;
        let _ = e.read_to_string(&mut err);
    }
    assert!(status.success(), "exit {status}: {err}");
    assert_eq!(summary(&dir)["stop_reason"], "interrupted");
    let html = std::fs::read_to_string(&report).unwrap();
    assert!(
        !html.contains("http-equiv"),
        "the final page stops reloading"
    );
    for f in ["scene_map.ply", "receivers/desk.exr", "receivers/desk.png"] {
        assert!(dir.join(f).exists(), "{f} written on Ctrl-C");
    }
    assert_report_renders(&live, "report_live", 1, 0);
    assert_report_renders(&report, "report_interrupted", 1, 0);
}

/// Writes `scene` as DIR/NAME.toml and runs it for `photons` into DIR/out.
fn run_scene(dir: &Path, name: &str, scene: &str, photons: u64) {
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, scene).expect("scene written");
    let out = Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args(["run", path.to_str().unwrap(), "--quiet"])
        .args(["--photons", &photons.to_string()])
        .args(["--out", dir.join("out").to_str().unwrap()])
        .output()
        .expect("binary runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn report_of_dark_tall_and_luminance_receivers_renders() {
    let dir = temp_dir("edge");
    // A receiver no photon reaches (nothing scored), a 1 × 600 strip, a luminance meter,
    // a surround excluding its task area (gaps in its contours).
    let scene = r#"
name = "edge"
[materials.floor]
reflectance = 0.5
[[objects]]
shape = "rect"
corner = [0, 0, 0]
u = [4, 0, 0]
v = [0, 4, 0]
material = "floor"
[[lights]]
type = "point"
position = [2, 2, 2]
intensity_cd = 100
[[receivers]]
name = "dark"
corner = [0, 0, 5]
u = [1, 0, 0]
v = [0, 1, 0]
cells = [3, 2]
[[receivers]]
name = "tall strip"
corner = [0, 2, 0.01]
u = [0, 0.1, 0]
v = [4, 0, 0]
cells = [1, 600]
[[receivers]]
name = "lum"
corner = [0, 0, 0.5]
u = [4, 0, 0]
v = [0, 4, 0]
cells = [20, 20]
quantity = "luminance"
view_direction = [0, 0, -1]
half_angle_deg = 10
[[receivers]]
name = "surround"
corner = [0, 0, 0.01]
u = [4, 0, 0]
v = [0, 4, 0]
cells = [8, 8]
exclude = ["task"]
[[receivers]]
name = "task"
corner = [1, 1, 0.01]
u = [2, 0, 0]
v = [0, 2, 0]
cells = [4, 4]
"#;
    run_scene(&dir, "edge", scene, 300_000);
    assert_report_renders(&dir.join("out/report.html"), "report_edge", 5, 0);
}

fn report_of_a_decided_run_draws_the_verdict_history() {
    let dir = temp_dir("decided");
    let out = Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args(["run", "scenes/en12464_office.toml", "--until", "decided"])
        .args(["--quiet", "--out", dir.to_str().unwrap()])
        .output()
        .expect("binary runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s = summary(&dir);
    assert_eq!(s["stop_reason"], "decided");
    let receivers = s["receivers"].as_object().unwrap().len();
    // Per photometric file: its polar diagram and, where it can be rated, its CIE 190
    // UGR table.
    let luminaires = s["luminaires"].as_array().unwrap();
    let tables = (luminaires.iter())
        .filter(|l| !l["ugr_table_png_base64"].as_str().unwrap_or("").is_empty())
        .count();
    assert!(tables > 0, "examp1.ies can be rated");
    let html = assert_report_renders(
        &dir.join("report.html"),
        "report_decided",
        receivers,
        1 + luminaires.len() + tables,
    );
    let decided = format!(
        "decided after {} photons",
        s["photons_emitted"]
            .as_u64()
            .unwrap()
            .to_string()
            .as_bytes()
            .rchunks(3)
            .rev()
            .map(|c| std::str::from_utf8(c).unwrap())
            .collect::<Vec<_>>()
            .join(",")
    );
    assert!(html.contains(&decided), "the page says `{decided}`");
}

/// A sunny sky with its sun in the east and an overcast one beside a `sun` in the west:
/// each sky gets its fisheye chart, drawn without errors, and the markers sit where the
/// projection puts them (east on the left, west on the right, radius (90° − altitude)/90°).
fn report_of_a_sky_scene_draws_each_skys_fisheye() {
    let dir = temp_dir("sky");
    let scene = r#"
name = "sky"
[[lights]]
type = "sky"
cie_type = 12
sun_altitude_deg = 30
sun_azimuth_deg = 90
horizontal_illuminance_lx = 10000
[[lights]]
type = "sky"
cie_type = 16
zenith_luminance_cdm2 = 2000
[[lights]]
type = "sun"
direct_normal_lx = 50000
sun_altitude_deg = 45
sun_azimuth_deg = 270
[[receivers]]
name = "open"
corner = [0, 0, 0]
u = [1, 0, 0]
v = [0, 1, 0]
cells = [4, 4]
"#;
    run_scene(&dir, "sky", scene, 20_000);
    let html = assert_report_renders(&dir.join("out/report.html"), "report_sky", 1, 2);
    for (chart, want) in [
        ("sky:lights[0]", [-2.0 / 3.0, 0.0]),
        ("sky:lights[1]", [0.5, 0.0]),
    ] {
        let tag = html
            .split(&format!("data-chart=\"{chart}\""))
            .nth(1)
            .and_then(|rest| rest.split('>').next())
            .unwrap_or_else(|| panic!("no chart {chart}"));
        let sun: Vec<f64> = tag
            .split("data-sun=\"")
            .nth(1)
            .and_then(|rest| rest.split('"').next())
            .unwrap_or_else(|| panic!("{chart} has no sun marker: {tag}"))
            .split(',')
            .map(|x| x.parse().expect("a number"))
            .collect();
        for (got, want) in sun.iter().zip(want) {
            assert!(
                (got - want).abs() < 2e-3,
                "{chart}: sun at {sun:?}, want {want}"
            );
        }
    }
}

/// The text of `function NAME(...) {...}` in the report's template (braces matched).
fn template_function(template: &str, name: &str) -> String {
    let start = template
        .find(&format!("function {name}("))
        .unwrap_or_else(|| panic!("report.html has no function {name}"));
    let mut depth = 0;
    for (k, c) in template[start..].char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 1 => return template[start..=start + k].to_string(),
            '}' => depth -= 1,
            _ => {}
        }
    }
    panic!("function {name} does not end");
}

/// The template's marching squares on small grids, in the browser: a peak in a 3 × 3
/// grid is ringed by a closed diamond of four segments; an unknown centre (NaN) leaves
/// every square without a line, a NaN corner its square; a saddle joins the corners its
/// centre's mean sides with;
/// the levels are round values strictly inside the known values' range.
fn contours_close_around_a_peak_skip_gaps_and_split_saddles() {
    let template = include_str!("../src/output/report.html");
    let functions: Vec<String> = ["niceTicks", "minOf", "maxOf", "isoLines", "contourLevels"]
        .iter()
        .map(|f| template_function(template, f))
        .collect();
    let checks = r#"
const out = [];
const text = a => JSON.stringify(a, (k, v) => (typeof v === "number" ? Math.round(v * 1e9) / 1e9 : v));
const same = (what, got, want) => { if (text(got) !== text(want)) out.push(what + ": " + text(got)); };
same("peak", isoLines([0, 0, 0, 0, 10, 0, 0, 0, 0], 3, 3, 5),
  [[[1.5, 1], [1, 1.5]], [[2, 1.5], [1.5, 1]], [[1, 1.5], [1.5, 2]], [[2, 1.5], [1.5, 2]]]);
same("gap", isoLines([0, 0, 0, 0, NaN, 0, 0, 0, 0], 3, 3, 5), []);
same("gap at a corner", isoLines([NaN, 0, 0, 10, 10, 10], 3, 2, 5), [[[2.5, 1], [1.5, 1]]]);
same("saddle, centre high", isoLines([10, 0, 0, 10], 2, 2, 5), [[[1, 0.5], [1.5, 1]], [[1, 1.5], [0.5, 1]]]);
same("saddle, centre low", isoLines([10, 0, 0, 10], 2, 2, 6), [[[0.5, 0.9], [0.9, 0.5]], [[1.5, 1.1], [1.1, 1.5]]]);
same("levels", contourLevels([300, 350, NaN, 820]), [400, 500, 600, 700, 800]);
same("flat", contourLevels([5, 5, NaN]), []);
document.body.setAttribute("data-checks", out.length ? out.join("; ") : "ok");
"#;
    let dir = temp_dir("contours");
    let page = dir.join("contours.html");
    let html = format!(
        "<!DOCTYPE html><html><body><script>\n{}\n{checks}</script></body></html>",
        functions.join("\n")
    );
    std::fs::write(&page, html).expect("page written");
    let dom = chromium(&["--dump-dom"], &page);
    let text = String::from_utf8_lossy(&dom.stdout);
    assert!(
        text.contains("data-checks=\"ok\""),
        "{}\n{}",
        text,
        String::from_utf8_lossy(&dom.stderr)
    );
}
