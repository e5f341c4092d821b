//! Calculation grids by the EN 12464-1 / EN 12193 rule (`grid = "en12464"` on a
//! receiver): an edge band taken off the area, then the maximum cell size
//! p = 0.2 · 5^log10(d) (≤ 10 m) from the area's reference side d, points along each
//! side by rounding side/p, and cells no more elongated than 2 : 1. The receiver's cells
//! are the grid's: their centres are the standard's points (the first p/2 from the
//! edge), and each cell reports its mean. Pure functions; `load` names the keys.

use glam::DVec3;
use serde::Deserialize;

/// The wall band of `grid = "en12464"` when `grid_band_m` is not given (m): EN 12464-1
/// leaves a 0.5 m band along the walls out of the calculation area.
pub const DEFAULT_BAND_M: f64 = 0.5;

/// The largest cell the rule makes (m).
pub const MAX_CELL_M: f64 = 10.0;

/// Cells are made no more elongated than this (length over width).
pub const MAX_ASPECT: f64 = 2.0;

/// Relative slack when a count is rounded up: side/p is a float, and a side that is an
/// exact multiple of p (1 m at p = 0.2 m) must give its exact count, not one more
/// because the division came out a rounding error above the integer.
const ROUNDING_SLACK: f64 = 1e-12;

/// The next integer ≥ x, where x within [`ROUNDING_SLACK`] of an integer is that integer.
fn ceil_snapped(x: f64) -> f64 {
    let r = libm::round(x);
    if (x - r).abs() <= ROUNDING_SLACK * r.max(1.0) {
        r
    } else {
        libm::ceil(x)
    }
}

/// How side/p becomes a number of points (`grid_rounding`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GridRounding {
    /// The next integer ≥ side/p: the EN 12464-1:2011 text (cells never larger than p).
    #[default]
    Up,
    /// The nearest integer (some tools and readings of EN 12464-1:2021): cells may be
    /// up to p·n/(n − ½) wide.
    Nearest,
}

impl GridRounding {
    /// As in the scene file.
    pub fn name(self) -> &'static str {
        match self {
            GridRounding::Up => "up",
            GridRounding::Nearest => "nearest",
        }
    }
}

/// A receiver whose cells were made by the rule: how (the summary can report it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridRule {
    /// Band taken off each of the four sides before gridding (m).
    pub band_m: f64,
    pub rounding: GridRounding,
}

/// The rule applied to a receiver: the area left after the band and its cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub corner: DVec3,
    pub u: DVec3,
    pub v: DVec3,
    /// Points (cells) along u, along v.
    pub cells: [u32; 2],
}

/// Why the rule cannot grid an area.
#[derive(Clone, Debug, PartialEq)]
pub enum GridError {
    /// The band leaves no area: the side (m) it eats.
    BandTooWide { band_m: f64, side_m: f64 },
    /// More points along a side than a receiver holds: the side's index (0 = u) and
    /// the count.
    TooManyPoints { side: usize, points: f64 },
}

impl std::fmt::Display for GridError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GridError::BandTooWide { band_m, side_m } => write!(
                f,
                "a {band_m} m band on both sides of a {side_m} m side leaves no area to grid"
            ),
            GridError::TooManyPoints { side, points } => write!(
                f,
                "the rule gives {points:e} points along {}, more than {} a receiver may have",
                ["u", "v"][*side],
                u32::MAX
            ),
        }
    }
}

/// The side the rule's cell size comes from: the longer of the two, but the shorter
/// when the longer is at least twice as long.
pub fn reference_side(a: f64, b: f64) -> f64 {
    let (long, short) = if a >= b { (a, b) } else { (b, a) };
    if long >= 2.0 * short {
        short
    } else {
        long
    }
}

/// The largest cell size for reference side `d` (m): p = 0.2 · 5^log10(d), at most
/// [`MAX_CELL_M`].
pub fn max_cell_m(d: f64) -> f64 {
    (0.2 * libm::pow(5.0, libm::log10(d))).min(MAX_CELL_M)
}

/// Points along a side of `side_m` at cell size at most about `p`: side/p rounded as
/// `rounding` says, at least 1.
pub fn points_along(side_m: f64, p: f64, rounding: GridRounding) -> f64 {
    let x = side_m / p;
    let n = match rounding {
        GridRounding::Up => ceil_snapped(x),
        GridRounding::Nearest => libm::round(x),
    };
    n.max(1.0)
}

/// Counts (nu, nv) of the sides `a` (along u) and `b` at cell size `p`, then the
/// aspect rule: where the cells come out more than [`MAX_ASPECT`] times longer than
/// wide, points are added along their long side until they are not.
pub fn counts(a: f64, b: f64, p: f64, rounding: GridRounding) -> [f64; 2] {
    let (mut nu, mut nv) = (points_along(a, p, rounding), points_along(b, p, rounding));
    let (cu, cv) = (a / nu, b / nv);
    if cu > MAX_ASPECT * cv {
        // The fewest nu with a/nu ≤ 2·cv.
        nu = ceil_snapped(a / (MAX_ASPECT * cv)).max(nu);
    } else if cv > MAX_ASPECT * cu {
        nv = ceil_snapped(b / (MAX_ASPECT * cu)).max(nv);
    }
    [nu, nv]
}

impl GridRule {
    /// The grid of the receiver `corner`, `u`, `v` (u × v ≠ 0): the band taken off all
    /// four sides (the corner moves by the band along u and along v, each side shortens
    /// by twice the band), then [`counts`] at the cell size of the remaining area's
    /// [`reference_side`].
    pub fn apply(&self, corner: DVec3, u: DVec3, v: DVec3) -> Result<Grid, GridError> {
        let (lu, lv) = (u.length(), v.length());
        let band = self.band_m;
        for side_m in [lu, lv] {
            if !(side_m - 2.0 * band > 0.0) {
                return Err(GridError::BandTooWide {
                    band_m: band,
                    side_m,
                });
            }
        }
        let (eu, ev) = (u / lu, v / lv);
        let (a, b) = (lu - 2.0 * band, lv - 2.0 * band);
        let p = max_cell_m(reference_side(a, b));
        let n = counts(a, b, p, self.rounding);
        for (side, &points) in n.iter().enumerate() {
            if !(points <= u32::MAX as f64) {
                return Err(GridError::TooManyPoints { side, points });
            }
        }
        Ok(Grid {
            corner: corner + (eu + ev) * band,
            u: eu * a,
            v: ev * b,
            cells: n.map(|x| x as u32),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(a: f64, b: f64, band_m: f64, rounding: GridRounding) -> Grid {
        GridRule { band_m, rounding }
            .apply(DVec3::ZERO, DVec3::X * a, DVec3::Y * b)
            .unwrap()
    }

    #[test]
    fn cell_size_follows_the_standard_at_1_10_and_100_m() {
        for (d, p, n) in [(1.0, 0.2, 5), (10.0, 1.0, 10), (100.0, 5.0, 20)] {
            assert!(
                (max_cell_m(d) - p).abs() < 1e-12,
                "d = {d}: p = {}",
                max_cell_m(d)
            );
            let g = grid(d, d, 0.0, GridRounding::Up);
            assert_eq!(g.cells, [n, n], "d = {d} m");
            let g = grid(d, d, 0.0, GridRounding::Nearest);
            assert_eq!(g.cells, [n, n], "d = {d} m, nearest");
        }
        // d/p = 5·d^log10(2): 5 points at 1 m, 10 at 10 m, 20 at 100 m.
        assert!((2.0 / max_cell_m(2.0) - 5.0 * libm::pow(2.0, libm::log10(2.0))).abs() < 1e-12);
    }

    #[test]
    fn cells_are_never_larger_than_10_m() {
        assert_eq!(max_cell_m(1000.0), 10.0);
        assert_eq!(
            grid(1000.0, 1000.0, 0.0, GridRounding::Up).cells,
            [100, 100]
        );
    }

    #[test]
    fn the_shorter_side_sets_the_size_once_the_longer_is_twice_as_long() {
        assert_eq!(reference_side(3.0, 2.0), 3.0);
        assert_eq!(reference_side(2.0, 3.0), 3.0);
        assert_eq!(reference_side(4.0, 2.0), 2.0);
        assert_eq!(reference_side(2.0, 10.0), 2.0);
        // 10 m × 1 m: p from d = 1 m is 0.2 m: 50 × 5 points, square cells.
        assert_eq!(grid(10.0, 1.0, 0.0, GridRounding::Up).cells, [50, 5]);
    }

    #[test]
    fn rounding_up_and_to_nearest_differ_below_the_half() {
        // 3 m × 3 m: p = 0.2·5^0.477 = 0.4310 m, 3/p = 6.96: 7 either way.
        assert_eq!(grid(3.0, 3.0, 0.0, GridRounding::Up).cells, [7, 7]);
        assert_eq!(grid(3.0, 3.0, 0.0, GridRounding::Nearest).cells, [7, 7]);
        // 4 m × 4.2 m: p = 0.2·5^0.623 = 0.5453 m, 4/p = 7.33: up 8, nearest 7;
        // 4.2/p = 7.70: 8 either way.
        let p = max_cell_m(4.2);
        assert!((4.0 / p - 7.335).abs() < 0.001, "{}", 4.0 / p);
        assert_eq!(grid(4.0, 4.2, 0.0, GridRounding::Up).cells, [8, 8]);
        assert_eq!(grid(4.0, 4.2, 0.0, GridRounding::Nearest).cells, [7, 8]);
        // A side far below p still has its one point.
        assert_eq!(points_along(0.01, 1.0, GridRounding::Nearest), 1.0);
        assert_eq!(points_along(0.01, 1.0, GridRounding::Up), 1.0);
        // An exact multiple is not rounded up for the division's last bit.
        assert_eq!(points_along(0.6, 0.2, GridRounding::Up), 3.0);
    }

    #[test]
    fn elongated_cells_get_points_along_their_long_side() {
        // p = 1 m at d = 10 m; a 0.4 m side gets 1 point: cells 1 m × 0.4 m are 2.5 : 1,
        // so the 10 m side gets 13 points (0.77 m ≤ 2 × 0.4 m).
        assert_eq!(counts(10.0, 0.4, 1.0, GridRounding::Up), [13.0, 1.0]);
        assert_eq!(counts(0.4, 10.0, 1.0, GridRounding::Up), [1.0, 13.0]);
        // Exactly 2 : 1 is within the range.
        assert_eq!(counts(4.0, 0.5, 1.0, GridRounding::Up), [4.0, 1.0]);
        for (a, b) in [(10.0, 0.4), (7.3, 0.11), (0.3, 5.0), (2.0, 1.9)] {
            for rounding in [GridRounding::Up, GridRounding::Nearest] {
                let g = grid(a, b, 0.0, rounding);
                let ratio = (a / g.cells[0] as f64) / (b / g.cells[1] as f64);
                assert!(
                    (0.5 - 1e-9..=2.0 + 1e-9).contains(&ratio),
                    "{a} × {b}: {:?}, ratio {ratio}",
                    g.cells
                );
            }
        }
    }

    #[test]
    fn the_band_comes_off_all_four_sides_before_gridding() {
        let rule = GridRule {
            band_m: 0.5,
            rounding: GridRounding::Up,
        };
        let g = rule
            .apply(
                DVec3::new(1.0, 2.0, 0.8),
                DVec3::new(0.0, 11.0, 0.0),
                DVec3::new(-4.0, 0.0, 0.0),
            )
            .unwrap();
        assert_eq!(g.corner, DVec3::new(0.5, 2.5, 0.8));
        assert_eq!(g.u, DVec3::new(0.0, 10.0, 0.0));
        assert_eq!(g.v, DVec3::new(-3.0, 0.0, 0.0));
        // 10 m × 3 m: d = 3 m (10 ≥ 2·3), p = 0.4310 m: 10/p = 23.2 → 24, 3/p = 6.96 → 7.
        assert_eq!(g.cells, [24, 7]);
        assert_eq!(
            rule.apply(DVec3::ZERO, DVec3::X * 5.0, DVec3::Y),
            Err(GridError::BandTooWide {
                band_m: 0.5,
                side_m: 1.0
            })
        );
        // No band: the area as given.
        let g = grid(1.0, 1.0, 0.0, GridRounding::Up);
        assert_eq!((g.corner, g.u, g.v), (DVec3::ZERO, DVec3::X, DVec3::Y));
    }

    #[test]
    fn too_many_points_is_an_error_not_a_wrapped_count() {
        let rule = GridRule {
            band_m: 0.0,
            rounding: GridRounding::Up,
        };
        let e = rule
            .apply(DVec3::ZERO, DVec3::X * 1e12, DVec3::Y * 1e12)
            .unwrap_err();
        assert!(
            matches!(e, GridError::TooManyPoints { side: 0, .. }),
            "{e:?}"
        );
        assert!(e.to_string().contains("along u"), "{e}");
    }
}
