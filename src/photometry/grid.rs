//! The normalised candela table: a grid of (plane angle φ, polar angle θ) about a polar
//! axis, the bilinear interpolant on it, and that interpolant's exact flux.
//!
//! Type C files use the C-planes as φ (0 … 360°, C = 0 repeated at 360) and γ as θ (from
//! the nadir, −z). Types A and B keep their own grid, in their own polar system (see
//! [`Axes`]): resampling them onto a (C, γ) grid would change the interpolant and so
//! the flux, while every direction can be converted exactly.

use glam::DVec3;

/// Where a grid's polar system sits in the luminaire frame (x = C0, y = C90, z = up).
/// A direction at (φ, θ) is `cos θ · pole + sin θ · (cos φ · zero + sin φ · ninety)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axes {
    /// θ = 0.
    pub pole: DVec3,
    /// θ = 90°, φ = 0.
    pub zero: DVec3,
    /// θ = 90°, φ = 90°.
    pub ninety: DVec3,
    /// φ wraps around (type C: 0 … 360°); otherwise the grid is zero outside its φ range.
    pub periodic: bool,
}

/// Type C: φ = C from +x towards +y, θ = γ from the nadir.
pub const TYPE_C: Axes = Axes {
    pole: DVec3::NEG_Z,
    zero: DVec3::X,
    ninety: DVec3::Y,
    periodic: true,
};

/// Type B: φ = V (the plane about the y axis, from the nadir towards +x), θ = 90° + H
/// (H the latitude, positive towards −y).
pub const TYPE_B: Axes = Axes {
    pole: DVec3::Y,
    zero: DVec3::NEG_Z,
    ninety: DVec3::X,
    periodic: false,
};

/// Type A: φ = H (the plane about the x axis, from the nadir towards −y), θ = 90° + V
/// (V the latitude, positive towards +x).
pub const TYPE_A: Axes = Axes {
    pole: DVec3::NEG_X,
    zero: DVec3::NEG_Z,
    ninety: DVec3::NEG_Y,
    periodic: false,
};

impl Axes {
    /// The unit direction at plane angle `phi_deg`, polar angle `theta_deg`.
    pub fn direction(&self, phi_deg: f64, theta_deg: f64) -> DVec3 {
        let (st, ct) = libm::sincos(theta_deg.to_radians());
        let (sp, cp) = libm::sincos(phi_deg.to_radians());
        ct * self.pole + st * (cp * self.zero + sp * self.ninety)
    }

    /// (φ, θ) of a direction (any length > 0), degrees; φ in (−180, 180], or [0, 360)
    /// when periodic.
    pub fn angles_deg(&self, dir: DVec3) -> (f64, f64) {
        let len = dir.length();
        let c = if len > 0.0 {
            (dir.dot(self.pole) / len).clamp(-1.0, 1.0)
        } else {
            1.0
        };
        let theta = libm::acos(c).to_degrees();
        let mut phi = libm::atan2(dir.dot(self.ninety), dir.dot(self.zero)).to_degrees();
        if self.periodic && phi < 0.0 {
            phi += 360.0;
            // -tiny + 360 rounds to 360, which is the same plane as 0.
            if phi >= 360.0 {
                phi = 0.0;
            }
        }
        (phi, theta)
    }
}

/// A candela table on a (φ, θ) grid, both axes strictly increasing, θ within [0, 180];
/// zero outside the grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    pub axes: Axes,
    pub phi_deg: Vec<f64>,
    pub theta_deg: Vec<f64>,
    /// cd[i * theta_deg.len() + j] at (phi_deg[i], theta_deg[j]).
    pub cd: Vec<f64>,
}

/// The cell [a[k], a[k+1]] holding x (a strictly increasing, len ≥ 2), and x's fraction
/// across it; None outside [a[0], a[last]].
#[inline]
fn locate(a: &[f64], x: f64) -> Option<(usize, f64)> {
    let n = a.len();
    if !(x >= a[0] && x <= a[n - 1]) {
        return None;
    }
    let k = a.partition_point(|&v| v <= x).clamp(1, n - 1) - 1;
    Some((k, (x - a[k]) / (a[k + 1] - a[k])))
}

impl Grid {
    pub fn n_theta(&self) -> usize {
        self.theta_deg.len()
    }

    #[inline]
    pub fn at(&self, i: usize, j: usize) -> f64 {
        self.cd[i * self.n_theta() + j]
    }

    /// The bilinear interpolant at (φ, θ) in degrees; 0 outside the grid.
    pub fn value(&self, phi_deg: f64, theta_deg: f64) -> f64 {
        let phi = if self.axes.periodic {
            phi_deg.rem_euclid(360.0)
        } else {
            phi_deg
        };
        let (Some((i, t)), Some((j, s))) = (
            locate(&self.phi_deg, phi),
            locate(&self.theta_deg, theta_deg),
        ) else {
            return 0.0;
        };
        let a = self.at(i, j) + s * (self.at(i, j + 1) - self.at(i, j));
        let b = self.at(i + 1, j) + s * (self.at(i + 1, j + 1) - self.at(i + 1, j));
        a + t * (b - a)
    }

    /// The interpolant toward a direction of the luminaire frame.
    pub fn value_toward(&self, dir: DVec3) -> f64 {
        let (phi, theta) = self.axes.angles_deg(dir);
        self.value(phi, theta)
    }

    /// ∫ I dΩ over cell (i, j), lm: the bilinear interpolant integrated exactly.
    pub fn cell_flux_lm(&self, i: usize, j: usize) -> f64 {
        let dphi = (self.phi_deg[i + 1] - self.phi_deg[i]).to_radians();
        let (w0, w1) = polar_weights(
            self.theta_deg[j].to_radians(),
            self.theta_deg[j + 1].to_radians(),
        );
        // Linear in φ: its integral over φ is the mean of the two planes.
        let lo = 0.5 * (self.at(i, j) + self.at(i + 1, j));
        let hi = 0.5 * (self.at(i, j + 1) + self.at(i + 1, j + 1));
        dphi * (lo * w0 + hi * w1)
    }

    /// The interpolant's flux over the sphere, lm.
    pub fn flux_lm(&self) -> f64 {
        let mut sum = 0.0;
        for i in 0..self.phi_deg.len() - 1 {
            for j in 0..self.n_theta() - 1 {
                sum += self.cell_flux_lm(i, j);
            }
        }
        sum
    }

    /// The largest table value and its (φ, θ); the bilinear interpolant peaks at a node.
    pub fn peak(&self) -> (f64, f64, f64) {
        let mut best = (f64::NEG_INFINITY, 0.0, 0.0);
        for (i, &phi) in self.phi_deg.iter().enumerate() {
            for (j, &theta) in self.theta_deg.iter().enumerate() {
                if self.at(i, j) > best.0 {
                    best = (self.at(i, j), phi, theta);
                }
            }
        }
        best
    }
}

/// (∫ (1 − s) sin θ dθ, ∫ s sin θ dθ) over [a, b] (radians), s = (θ − a)/(b − a): the
/// weights of a cell's lower and upper γ row in its exact flux.
pub fn polar_weights(a: f64, b: f64) -> (f64, f64) {
    let h = b - a;
    let m = 0.5 * (a + b);
    let sh = libm::sin(0.5 * h);
    // cos a − cos b and sin b − sin a without cancellation.
    let dcos = 2.0 * libm::sin(m) * sh;
    let dsin = 2.0 * libm::cos(m) * sh;
    // ∫ s sin θ dθ = −cos b + (sin b − sin a)/h, and ∫ sin θ dθ = cos a − cos b.
    let w1 = if h > 1e-4 {
        dsin / h - libm::cos(b)
    } else {
        // Series of the same in h (the two terms above cancel to O(h)).
        let (sb, cb) = libm::sincos(b);
        h * (0.5 * sb - h * cb / 6.0 - h * h * sb / 24.0)
    };
    (dcos - w1, w1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polar_weights_match_quadrature() {
        for (a, b) in [
            (0.0, 0.1),
            (0.3, 0.30001),
            (1.0, 2.0),
            (3.0, std::f64::consts::PI),
        ] {
            let n = 20000;
            let (mut q0, mut q1) = (0.0, 0.0);
            for k in 0..n {
                let s = (k as f64 + 0.5) / n as f64;
                let t = a + s * (b - a);
                q0 += (1.0 - s) * libm::sin(t) * (b - a) / n as f64;
                q1 += s * libm::sin(t) * (b - a) / n as f64;
            }
            let (w0, w1) = polar_weights(a, b);
            assert!((w0 - q0).abs() < 1e-8 * (b - a), "{a} {b}: {w0} vs {q0}");
            assert!((w1 - q1).abs() < 1e-8 * (b - a), "{a} {b}: {w1} vs {q1}");
        }
    }

    #[test]
    fn axes_round_trip() {
        for axes in [TYPE_C, TYPE_B, TYPE_A] {
            for (phi, theta) in [(10.0, 20.0), (-80.0, 170.0), (45.0, 90.0)] {
                let phi = if axes.periodic && phi < 0.0 {
                    phi + 360.0
                } else {
                    phi
                };
                let d = axes.direction(phi, theta);
                assert!((d.length() - 1.0).abs() < 1e-12);
                let (p, t) = axes.angles_deg(d);
                assert!((p - phi).abs() < 1e-9 && (t - theta).abs() < 1e-9);
            }
        }
        // Type C: C = 90° is +y, γ = 0 the nadir.
        let d = TYPE_C.direction(90.0, 90.0);
        assert!((d - DVec3::Y).length() < 1e-12);
        assert!((TYPE_C.direction(0.0, 0.0) - DVec3::NEG_Z).length() < 1e-12);
        // Type B: V = +90° is +x, H = +90° is −y; type A: V = +90° is +x, H = +90° is −y.
        assert!((TYPE_B.direction(90.0, 90.0) - DVec3::X).length() < 1e-12);
        assert!((TYPE_B.direction(0.0, 180.0) - DVec3::NEG_Y).length() < 1e-12);
        assert!((TYPE_A.direction(0.0, 180.0) - DVec3::X).length() < 1e-12);
        assert!((TYPE_A.direction(90.0, 90.0) - DVec3::NEG_Y).length() < 1e-12);
    }
}
