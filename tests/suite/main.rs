//! The integration tests as one binary: the crate is linked into one test binary instead
//! of ~30 (the target directory is less than half the size; the build takes about as
//! long, BENCHMARKS.md), and a crash in any test shows in `.ci/run`'s totals.
//! Its modules are themes, one folder each, holding the files that were binaries of
//! their own (their test names gain the prefix `theme::file::`). Run one theme or file
//! with a filter: `cargo test --release --test suite physics::render::`.
//!
//! The tests share one process and run on parallel threads, so none may change
//! process-wide state (environment variables, the current directory, rayon's global
//! pool, signal handlers): a test that needs such a change gives it to a child process
//! (`Command::env`, `current_dir`). Three binaries stay on their own: `huge_pages`
//! (turns transparent huge pages off for the whole process and measures the process's
//! huge pages, which any other test's large build here would change), `report_browser`
//! (its own harness, libtest-mimic) and `mpi` (feature `mpi`, launched by scripts/test.sh).

// Themes hold files named as they were as binaries: `physics::physics`, `cli::cli`.
#![allow(clippy::module_inception)]

mod common;

mod physics {
    mod accuracy;
    mod annual;
    mod bounce_cap;
    mod calibration;
    mod custom_light;
    mod cylindrical;
    mod daylight;
    mod direct_light;
    mod extremes;
    mod figures;
    mod glossy;
    mod luminaires;
    mod openings;
    mod perez;
    mod physics;
    mod points;
    mod portal_photons;
    mod reflected;
    mod render;
    mod surroundings;
    mod ugr;
    mod ugr_table;
    mod verdict;
}

mod engine {
    mod backend_parity;
    mod bit_identity;
    mod engine;
    mod instancing;
}

mod io {
    mod bad_input;
    mod calculation_grid;
    mod f32_range;
    mod fuzz;
    mod outputs;
    mod photometry;
    mod scene_loading;
    mod scene_paths;
    mod weather;
}

mod cli {
    mod cli;
    mod limits;
    mod progress;
}

mod distributed {
    mod resume;
}

mod project {
    mod bundled_scenes;
    mod ci_totals;
    mod layering;
    mod setup_script;
}
