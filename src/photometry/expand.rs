//! Symmetry expansion: the planes a file stores, reflected into the full table.

use super::Symmetry;

/// Angles closer than this (degrees) are the same plane.
const SAME_DEG: f64 = 1e-9;

/// Type C planes: the stored planes (angles in degrees, any of them may be beyond 360 or
/// negative, as EULUMDAT's C270 … C90) and their γ rows, reflected as `symmetry` says,
/// → planes 0 … 360 (C = 0 repeated at 360) and their rows. Where the images miss C = 0,
/// a node is inserted by linear interpolation across the wrap, which leaves the
/// interpolant unchanged.
pub fn c_planes(
    stored_deg: &[f64],
    rows: &[Vec<f64>],
    symmetry: Symmetry,
) -> (Vec<f64>, Vec<Vec<f64>>) {
    if symmetry == Symmetry::Rotational {
        return (vec![0.0, 360.0], vec![rows[0].clone(), rows[0].clone()]);
    }
    let images: &[fn(f64) -> f64] = match symmetry {
        Symmetry::Quadrant => &[|a| a, |a| 180.0 - a, |a| 180.0 + a, |a| 360.0 - a],
        Symmetry::BilateralC0C180 => &[|a| a, |a| -a],
        Symmetry::BilateralC90C270 => &[|a| a, |a| 180.0 - a],
        _ => &[|a| a],
    };
    let mut nodes: Vec<(f64, usize)> = Vec::new();
    for image in images {
        for (k, &a) in stored_deg.iter().enumerate() {
            nodes.push((image(a).rem_euclid(360.0) + 0.0, k));
        }
    }
    // Stable: of coinciding images, the stored plane listed first is kept.
    nodes.sort_by(|a, b| a.0.total_cmp(&b.0));
    nodes.dedup_by(|b, a| (b.0 - a.0).abs() <= SAME_DEG);
    if let Some(&(last, _)) = nodes.last() {
        if 360.0 - last <= SAME_DEG && nodes.len() > 1 {
            nodes.pop();
        }
    }
    let mut angles: Vec<f64> = nodes.iter().map(|n| n.0).collect();
    let mut out: Vec<Vec<f64>> = nodes.iter().map(|n| rows[n.1].clone()).collect();
    if angles[0] > SAME_DEG {
        let (a_last, a_first) = (angles[angles.len() - 1] - 360.0, angles[0]);
        let w = -a_last / (a_first - a_last);
        let (r_last, r_first) = (&out[out.len() - 1], &out[0]);
        let at_zero = r_last
            .iter()
            .zip(r_first)
            .map(|(l, f)| l + w * (f - l))
            .collect();
        angles.insert(0, 0.0);
        out.insert(0, at_zero);
    }
    angles[0] = 0.0;
    angles.push(360.0);
    out.push(out[0].clone());
    (angles, out)
}

/// Types A and B: planes stored for 0 … a (symmetric about 0) → −a … a.
pub fn mirror_about_zero(stored_deg: &[f64], rows: &[Vec<f64>]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let mut angles = Vec::new();
    let mut out = Vec::new();
    for k in (1..stored_deg.len()).rev() {
        angles.push(-stored_deg[k]);
        out.push(rows[k].clone());
    }
    angles.extend_from_slice(stored_deg);
    out.extend_from_slice(rows);
    (angles, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(n: usize) -> Vec<Vec<f64>> {
        (0..n).map(|k| vec![k as f64]).collect()
    }

    #[test]
    fn quadrant_reflects_into_four_quadrants() {
        let (a, r) = c_planes(&[0.0, 45.0, 90.0], &rows(3), Symmetry::Quadrant);
        assert_eq!(
            a,
            [0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0, 360.0]
        );
        let v: Vec<f64> = r.iter().map(|r| r[0]).collect();
        assert_eq!(v, [0.0, 1.0, 2.0, 1.0, 0.0, 1.0, 2.0, 1.0, 0.0]);
    }

    #[test]
    fn c90_c270_half_reflects_across_its_plane() {
        // 90, 135, 225, 270 stored: C = 0 is no image, so it is interpolated between
        // 315 (image of 225) and 45 (image of 135).
        let (a, r) = c_planes(
            &[90.0, 135.0, 225.0, 270.0],
            &rows(4),
            Symmetry::BilateralC90C270,
        );
        assert_eq!(a, [0.0, 45.0, 90.0, 135.0, 225.0, 270.0, 315.0, 360.0]);
        let v: Vec<f64> = r.iter().map(|r| r[0]).collect();
        assert_eq!(v, [1.5, 1.0, 0.0, 1.0, 2.0, 3.0, 2.0, 1.5]);
    }

    #[test]
    fn full_circle_keeps_c0_and_repeats_it_at_360() {
        let (a, r) = c_planes(&[0.0, 120.0, 240.0], &rows(3), Symmetry::None);
        assert_eq!(a, [0.0, 120.0, 240.0, 360.0]);
        assert_eq!(r[3], r[0]);
        let (a, _) = c_planes(&[0.0, 180.0, 360.0], &rows(3), Symmetry::None);
        assert_eq!(a, [0.0, 180.0, 360.0]);
    }

    #[test]
    fn eulumdat_c270_to_c90_wraps() {
        let (a, r) = c_planes(&[270.0, 360.0, 450.0], &rows(3), Symmetry::BilateralC90C270);
        assert_eq!(a, [0.0, 90.0, 180.0, 270.0, 360.0]);
        let v: Vec<f64> = r.iter().map(|r| r[0]).collect();
        assert_eq!(v, [1.0, 2.0, 1.0, 0.0, 1.0]);
    }
}
