//! `grid = "en12464"` receivers: the EN 12464-1 rule's cells and edge band, read from a
//! scene file (the rule itself is unit-tested in `src/scene/grid.rs`).

use crate::common;

use glam::DVec3;
use luxtally::scene::grid::{GridRounding, GridRule};

/// A 6 m × 4 m room's working plane at 0.8 m, once by the rule with its default band
/// and rounding, once without a band and rounded to the nearest integer, and a 1 m
/// square without a band.
const ROOM: &str = r#"
    [[receivers]]
    name = "plane"
    corner = [0, 0, 0.8]
    u = [6, 0, 0]
    v = [0, 4, 0]
    grid = "en12464"

    [[receivers]]
    name = "whole"
    corner = [0, 0, 0.8]
    u = [6, 0, 0]
    v = [0, 4, 0]
    grid = "en12464"
    grid_band_m = 0
    grid_rounding = "nearest"

    [[receivers]]
    name = "square"
    corner = [1, 1, 0.8]
    u = [0, 1, 0]
    v = [-1, 0, 0]
    grid = "en12464"
    grid_band_m = 0.0
"#;

#[test]
fn the_rule_grids_a_room_after_its_wall_band() {
    let s = common::scene(ROOM);
    // Band 0.5 m: 5 m × 3 m left, d = 5 m, p = 0.2·5^log10(5) = 0.6160 m:
    // 5/p = 8.09 → 9, 3/p = 4.86 → 5 (rounded up).
    let plane = &s.receivers[0];
    assert_eq!(plane.corner, DVec3::new(0.5, 0.5, 0.8));
    assert_eq!((plane.u, plane.v), (DVec3::X * 5.0, DVec3::Y * 3.0));
    assert_eq!(plane.cells, [9, 5]);
    assert_eq!(
        plane.grid,
        Some(GridRule {
            band_m: 0.5,
            rounding: GridRounding::Up
        })
    );
    // No band: 6 m × 4 m, d = 6 m, p = 0.6997 m: 6/p = 8.57 → 9, 4/p = 5.71 → 6.
    let whole = &s.receivers[1];
    assert_eq!(whole.corner, DVec3::new(0.0, 0.0, 0.8));
    assert_eq!(whole.cells, [9, 6]);
    assert_eq!(whole.grid.map(|g| g.rounding), Some(GridRounding::Nearest));
    // 1 m: p = 0.2 m, 5 × 5 points, whatever the edges' directions.
    let square = &s.receivers[2];
    assert_eq!(square.cells, [5, 5]);
    assert!((square.cell_area_m2() - 0.04).abs() < 1e-15);
    assert_eq!(square.grid.map(|g| g.band_m), Some(0.0));
}

#[test]
fn the_points_are_the_cell_centres_p_over_2_from_the_edges() {
    let s = common::scene(ROOM);
    let r = &s.receivers[2];
    // Cell (0, 0)'s centre: 0.1 m along u and v from the corner.
    let (nu, nv) = (r.cells[0] as f64, r.cells[1] as f64);
    let centre = r.corner + r.u * (0.5 / nu) + r.v * (0.5 / nv);
    assert!(
        (centre - DVec3::new(0.9, 1.1, 0.8)).length() < 1e-12,
        "{centre}"
    );
}

#[test]
fn a_grid_receiver_runs_like_any_other() {
    let toml = format!(
        "{}{ROOM}
        [[lights]]
        type = \"point\"
        position = [3, 2, 2.8]
        intensity_cd = 1000
        ",
        common::BLACK_FLOOR
    );
    let summary = common::run_scene(&toml, 20_000);
    let plane = &summary.receivers["plane"];
    assert_eq!(plane.cells, [9, 5]);
    assert_eq!(plane.values.len(), 45);
    assert!(plane.values.iter().all(|&v| v > 0.0));
}
