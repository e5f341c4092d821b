//! Limits that fail cleanly: runs and renders that would not fit in memory, or whose
//! numbers would overflow the engine's indices, stop before allocating with one line
//! naming the part at fault and its figure, exit 1, no panic and no output folder.

use luxtally::accel::{Backend, Bvh};
use luxtally::limits::{self, Budget};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn luxtally(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args(args)
        .output()
        .expect("binary runs")
}

/// A fresh, empty temp directory for one test.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("luxtally-limits-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The office scene with `from` replaced by `to`, written into `dir`.
fn office_with(dir: &Path, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string("scenes/office.toml").unwrap();
    assert!(text.contains(from), "office.toml has no `{from}`");
    let path = dir.join("scene.toml");
    std::fs::write(&path, text.replace(from, to)).unwrap();
    path
}

/// `n` spheres of `subdivisions`, a material and a light.
fn spheres(dir: &Path, n: usize, subdivisions: u32) -> PathBuf {
    let mut text = String::from("[materials.m]\nreflectance = 0.5\n");
    for i in 0..n {
        text += &format!(
            "[[objects]]\nshape = \"sphere\"\ncenter = [{}, 0, 0]\nradius = 1\nsubdivisions = {subdivisions}\nmaterial = \"m\"\n",
            3 * i
        );
    }
    text += "[[lights]]\ntype = \"point\"\nposition = [0, 0, 5]\nintensity_cd = 100\n";
    let path = dir.join("spheres.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// Exit 1, exactly one stderr line `luxtally: …` holding every needle, no panic, and no
/// output folder at `out`.
fn assert_refused(output: &Output, needles: &[&str], out: &Path) -> String {
    let err = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(1), "exit code; stderr: {err}");
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    assert!(err.starts_with("luxtally: "), "{err}");
    assert!(
        !err.contains("panicked") && !err.contains("RUST_BACKTRACE"),
        "{err}"
    );
    for n in needles {
        assert!(err.contains(n), "`{n}` missing from: {err}");
    }
    assert!(!out.exists(), "output folder {} left behind", out.display());
    err
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn receiver_of_ten_billion_cells_is_refused_before_allocating() {
    let dir = temp_dir("cells-1e10");
    let scene = office_with(&dir, "cells = [64, 32]", "cells = [100000, 100000]");
    let out = dir.join("out");
    // Refused by memory (4.2 TB) or, where the memory available is unknown, because
    // 10^10 cells do not fit the 32-bit cell numbers.
    assert_refused(
        &luxtally(&["run", s(&scene), "--out", s(&out)]),
        &["receivers", "100000"],
        &out,
    );
    // With memory to spare, the cell numbers still refuse it.
    assert_refused(
        &luxtally(&["run", s(&scene), "--out", s(&out), "--max-memory", "100T"]),
        &["receivers: 10000000000 cells in all; at most 4294967295"],
        &out,
    );
}

#[test]
fn receiver_of_four_hundred_million_cells_names_its_figure_and_leaves_no_folder() {
    let dir = temp_dir("cells-4e8");
    let scene = office_with(&dir, "cells = [64, 32]", "cells = [20000, 20000]");
    let out = dir.join("out");
    let mut args = vec!["run", s(&scene), "--out", s(&out)];
    // Its tallies alone are 35 GB: on a machine with room for them, ask for less.
    if limits::available_bytes().is_none_or(|b| b > 100_000_000_000) {
        args.extend(["--max-memory", "16G"]);
    }
    let err = assert_refused(
        &luxtally(&args),
        &[
            "receivers[0] \"desk\": 20000 × 20000 cells need",
            " GB of tallies",
        ],
        &out,
    );
    assert!(
        err.contains(" available (--max-memory to change)")
            || err.contains("allowed by --max-memory"),
        "{err}"
    );
}

#[test]
fn max_memory_refuses_the_office_with_its_figure_and_a_gigabyte_runs_it() {
    let dir = temp_dir("office");
    let out = dir.join("out");
    let scene = "scenes/office.toml";
    assert_refused(
        &luxtally(&["run", scene, "--out", s(&out), "--max-memory", "2M"]),
        &[scene, " need ", " MB ", "; 2.0 MB allowed by --max-memory"],
        &out,
    );
    let ok = luxtally(&[
        "run",
        scene,
        "--out",
        s(&out),
        "--max-memory",
        "1GiB",
        "--photons",
        "20000",
        "--quiet",
    ]);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    assert!(out.join("summary.json").exists());
}

#[test]
fn unreadable_sizes_and_thread_counts_are_one_line_errors() {
    let dir = temp_dir("bad-args");
    let out = dir.join("out");
    for (args, needle) in [
        (
            vec!["--max-memory", "8X"],
            "--max-memory: `8X` is not a size",
        ),
        (
            vec!["--max-memory", "0"],
            "--max-memory: `0` is not more than 0 bytes",
        ),
        (
            vec!["--threads", "100000"],
            "--threads: 100000 is more than 1024",
        ),
    ] {
        let mut all = vec!["run", "scenes/office.toml", "--out", s(&out)];
        all.extend(args);
        assert_refused(&luxtally(&all), &[needle], &out);
    }
    // render too: refused before any thread starts (a pool of 100,000 threads panics).
    let render = [
        "render",
        "scenes/office.toml",
        "--out",
        s(&out),
        "--threads",
        "100000",
    ];
    assert_refused(
        &luxtally(&render),
        &["--threads: 100000 is more than 1024"],
        &out,
    );
}

#[test]
fn absurd_photon_count_with_a_time_limit_runs_to_the_time_limit() {
    let dir = temp_dir("photons");
    let out = dir.join("out");
    let result = luxtally(&[
        "run",
        "scenes/office.toml",
        "--photons",
        &u64::MAX.to_string(),
        "--time-limit",
        "0.5",
        "--quiet",
        "--out",
        s(&out),
    ]);
    let err = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{err}");
    assert!(err.is_empty(), "{err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["stop_reason"], "time");
    let photons = summary["photons_emitted"].as_u64().unwrap();
    assert!(photons > 0 && photons < u64::MAX);
}

#[test]
fn absurd_camera_is_refused_before_the_photon_pass() {
    let dir = temp_dir("camera");
    let text = std::fs::read_to_string("scenes/office.toml")
        .unwrap()
        .replace("resolution = [640, 480]", "resolution = [16384, 16384]")
        .replace("samples = 4", "samples = 65536");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    // 6.4 GB of image and 3 GB of ray buffers per thread: refused under 4 GB whatever
    // the machine (without the limit, a machine with the memory would start it).
    assert_refused(
        &luxtally(&["render", s(&scene), "--out", s(&out), "--max-memory", "4G"]),
        &["camera: ", " need ", "allowed by --max-memory"],
        &out,
    );
}

#[test]
fn scene_of_many_fine_spheres_is_refused_before_it_is_tessellated() {
    let dir = temp_dir("spheres");
    let out = dir.join("out");
    // 16 spheres of 1.3 M triangles: 21 M triangles, 2.2 GB of geometry and (compact) BVH.
    let scene = spheres(&dir, 16, 8);
    for command in ["run", "render"] {
        assert_refused(
            &luxtally(&[command, s(&scene), "--out", s(&out), "--max-memory", "256M"]),
            &[
                "objects: 20971520 triangles need",
                "of geometry and embree BVH",
            ],
            &out,
        );
    }
    // 1000 of them (1.3 G triangles) are refused from the file alone, without building
    // a single one.
    let many = spheres(&dir, 1000, 8);
    let budget = Budget::new(Some("64G")).unwrap();
    let err = limits::check_scene_file(&many, Backend::Embree, Bvh::Auto, &budget)
        .unwrap_err()
        .to_string();
    assert!(err.contains("objects: 1310720000 triangles need"), "{err}");
}

#[test]
fn a_run_that_fails_after_creating_its_folder_removes_it() {
    let dir = temp_dir("late-failure");
    let out = dir.join("out");
    assert_refused(
        &luxtally(&[
            "run",
            "scenes/office.toml",
            "--target",
            "receiver:nope",
            "--out",
            s(&out),
        ]),
        &["nope"],
        &out,
    );
    // A folder that existed before is left alone.
    std::fs::create_dir_all(&out).unwrap();
    let again = luxtally(&[
        "run",
        "scenes/office.toml",
        "--target",
        "receiver:nope",
        "--out",
        s(&out),
    ]);
    assert_eq!(again.status.code(), Some(1));
    assert!(out.exists());
}

/// `bvh` of a finished run's summary.json.
fn summary_bvh(out: &Path) -> String {
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["bvh"].as_str().expect("bvh key").to_string()
}

#[test]
fn the_compact_bvh_is_chosen_when_the_fast_one_would_not_fit() {
    let dir = temp_dir("bvh");
    // One sphere of 1.3 M triangles; a budget between its compact and fast estimates.
    let scene = spheres(&dir, 1, 8);
    let triangles = 20 * 4u64.pow(8);
    let need = |bvh| limits::geometry_estimate(triangles, 0, Backend::Embree, bvh).total_bytes();
    let (fast, compact) = (need(Bvh::Fast), need(Bvh::Compact));
    assert!(compact < fast, "compact {compact} B, fast {fast} B");
    let between = format!("{}", ((fast + compact) / 2.0) as u64);
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec!["run", s(&scene), "--out", s(out), "--photons", "2000"];
        args.extend_from_slice(&["--outputs", "none", "--threads", "1"]);
        args.extend_from_slice(extra);
        luxtally(&args)
    };

    for (name, extra) in [("auto", &[][..]), ("auto-named", &["--bvh", "auto"][..])] {
        let out = dir.join(name);
        let mut args = vec!["--max-memory", between.as_str()];
        args.extend_from_slice(extra);
        let r = run(&out, &args);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(r.status.success(), "{err}");
        assert!(err.contains("building the compact one"), "{name}: {err}");
        assert_eq!(summary_bvh(&out), "compact");
    }

    // Asked for by name, the fast BVH is refused under the same budget ...
    let out = dir.join("fast");
    assert_refused(
        &run(&out, &["--max-memory", &between, "--bvh", "fast"]),
        &["objects: 1310720 triangles need", "allowed by --max-memory"],
        &out,
    );
    // ... and chosen, without a word, when the budget holds it.
    let out = dir.join("roomy");
    let r = run(&out, &["--max-memory", "8G", "--quiet"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(
        r.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    assert_eq!(summary_bvh(&out), "fast");
    // obvhs has no compact BVH.
    let r = run(
        &dir.join("obvhs"),
        &["--backend", "obvhs", "--bvh", "compact"],
    );
    assert_eq!(r.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&r.stderr).contains("--bvh"));
}

#[test]
fn choose_bvh_prefers_speed_while_memory_allows() {
    let choose = |choice, backend, fast_fits: bool| {
        limits::choose_bvh(choice, backend, |bvh| bvh == Bvh::Compact || fast_fits)
    };
    assert_eq!(choose(Bvh::Auto, Backend::Embree, true), Bvh::Fast);
    assert_eq!(choose(Bvh::Auto, Backend::Embree, false), Bvh::Compact);
    assert_eq!(choose(Bvh::Auto, Backend::Obvhs, false), Bvh::Fast);
    assert_eq!(choose(Bvh::Fast, Backend::Embree, false), Bvh::Fast);
    assert_eq!(choose(Bvh::Compact, Backend::Embree, true), Bvh::Compact);
    // An unknown budget holds anything.
    assert!(Budget::unlimited().fits(&limits::geometry_estimate(
        1 << 40,
        0,
        Backend::Embree,
        Bvh::Fast
    )));
}

/// One sphere of 1.3 M triangles (subdivision 8) with `keys` added to its object, and a
/// light.
fn sphere_with(dir: &Path, keys: &str) -> PathBuf {
    let text = format!(
        "[materials.m]\nreflectance = 0.5\n\
         [[objects]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nsubdivisions = 8\nmaterial = \"m\"\n{keys}\n\
         [[lights]]\ntype = \"point\"\nposition = [0, 0, 5]\nintensity_cd = 100\n"
    );
    let path = dir.join("sphere.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn instanced_prototypes_triangles_count_in_a_runs_memory() {
    let dir = temp_dir("prototypes");
    // Unmapped: no triangle in the map, 1.3 M stored once for the instances (167 MB of
    // geometry and BVH), which 64 MB cannot hold.
    let scene = luxtally::scene::load(&sphere_with(
        &dir,
        "map = false\ninstances = [{}, {translate = [3, 0, 0]}]",
    ))
    .unwrap();
    assert_eq!(scene.geometry.triangle_count(), 0);
    let mut options = luxtally::run::RunOptions::from_scene(&scene);
    options.stop.photons = Some(4096);
    let budget = Budget::new(Some("64M")).unwrap();
    let err = limits::check_run(&scene, &options, None, true, &budget)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("objects: 1310720 triangles (1310720 in instanced prototypes) need"),
        "{err}"
    );
}

#[test]
fn scene_file_check_maps_only_mapped_shapes_and_maps_every_copy() {
    let dir = temp_dir("shape-maps");
    let per_triangle = limits::GEOMETRY_BYTES_PER_TRIANGLE_EMBREE;
    let triangles = 1_310_720.0;
    // Between the sphere's geometry alone and its geometry with a triangle map: an
    // unmapped sphere fits.
    let geometry = triangles * per_triangle;
    let budget = Budget {
        bytes: Some((geometry * 1.1) as u64),
        from_flag: true,
    };
    let unmapped = sphere_with(&dir, "map = false");
    limits::check_scene_file(&unmapped, Backend::Embree, Bvh::Auto, &budget).unwrap();
    // A mapped sphere in two copies holds two maps and twice the geometry, beyond a
    // budget that holds one mapped copy.
    let mapped = sphere_with(
        &dir,
        "map = true\ngrid = {count = [2, 1], spacing = [3, 0]}",
    );
    let budget = Budget {
        bytes: Some((geometry * 1.5) as u64),
        from_flag: true,
    };
    let err = limits::check_scene_file(&mapped, Backend::Embree, Bvh::Auto, &budget)
        .unwrap_err()
        .to_string();
    assert!(err.contains("objects: 2621440 triangles need"), "{err}");
}

#[test]
fn instances_count_in_a_runs_memory() {
    let dir = temp_dir("instances");
    // 250,000 copies of a box (12 triangles): 3 M triangles if flattened, a few hundred
    // bytes each as instances, which 64 MB cannot hold.
    let text = "[materials.m]\nreflectance = 0.5\n\
         [[objects]]\nshape = \"box\"\nmin = [0, 0, 0]\nmax = [0.1, 0.1, 0.1]\nmaterial = \"m\"\n\
         map = false\ngrid = {count = [500, 500], spacing = [0.2, 0.2]}\n\
         [[lights]]\ntype = \"point\"\nposition = [0, 0, 5]\nintensity_cd = 100\n";
    let path = dir.join("boxes.toml");
    std::fs::write(&path, text).unwrap();
    let scene = luxtally::scene::load(&path).unwrap();
    assert_eq!(scene.geometry.instanced.instances.len(), 250_000);
    let mut options = luxtally::run::RunOptions::from_scene(&scene);
    options.stop.photons = Some(4096);
    let check = |size: &str| {
        let budget = Budget::new(Some(size)).unwrap();
        limits::check_run(&scene, &options, None, true, &budget)
    };
    let err = check("64M").unwrap_err().to_string();
    assert!(err.contains("objects: 250000 instances need"), "{err}");
    assert!(check("1G").is_ok());
}

#[test]
fn the_tracers_surface_table_counts_where_the_tracer_builds_one() {
    use luxtally::trace::SURFACE_TABLE_MAX_TRIANGLES;
    // A triangle's first vertex and two edges (3 × 12 bytes) and its u32 material.
    assert_eq!(limits::SURFACE_TABLE_BYTES_PER_TRIANGLE, 40);
    let table = |mapped: u64| {
        let e = limits::geometry_estimate(mapped, 5, Backend::Embree, Bvh::Fast);
        let parts: Vec<f64> = e
            .parts
            .iter()
            .filter(|p| p.of == "of surface table")
            .map(|p| p.bytes)
            .collect();
        let others: f64 = e
            .parts
            .iter()
            .filter(|p| p.of != "of surface table")
            .map(|p| p.bytes)
            .sum();
        assert_eq!(e.total_bytes(), others + parts.iter().sum::<f64>());
        parts
    };
    let most = SURFACE_TABLE_MAX_TRIANGLES as u64;
    assert_eq!(table(14), [14.0 * 40.0]);
    // 2.6 MB at the largest table.
    assert_eq!(table(most), [most as f64 * 40.0]);
    // Above it, and for prototypes alone, the tracer builds none.
    assert!(table(most + 1).is_empty());
    assert!(table(0).is_empty());
    // A run's check counts it.
    let dir = temp_dir("surface-table");
    let scene = luxtally::scene::load(&spheres(&dir, 1, 4)).unwrap();
    let mapped = scene.geometry.triangle_count() as u64;
    assert_eq!(mapped, 5120);
    let mut options = luxtally::run::RunOptions::from_scene(&scene);
    options.stop.photons = Some(4096);
    options.bvh = Bvh::Fast;
    let need = limits::geometry_estimate(mapped, 0, Backend::Embree, Bvh::Fast).total_bytes()
        + limits::photon_pass_estimate(&scene, &options).total_bytes();
    let check = |bytes: f64| {
        let budget = Budget {
            bytes: Some(bytes as u64),
            from_flag: true,
        };
        limits::check_run(&scene, &options, None, true, &budget)
    };
    assert!(check(need).is_ok());
    // Room for all but half the table's 205 kB: refused.
    assert!(check(need - 0.5 * table(mapped)[0]).is_err());
}
