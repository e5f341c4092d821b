//! Which triangles share each vertex, and the area-weighted vertex average of face
//! values over them: the one rule behind the scene map's vertex illuminance
//! (`output::ply`, every face: [`vertex_means`]) and the eye pass's interpolated indirect
//! light (`render::map`, faces filtered: [`VertexFaces::area_weighted_mean`]).

/// Σ a_j·value(j) / Σ a_j over every triangle j of each vertex (0 where their area is
/// 0): [`VertexFaces::area_weighted_mean`] with no filter, summed in the same triangle
/// order (same bits) without building the adjacency.
pub fn vertex_means(
    triangles: &[[u32; 3]],
    vertex_count: usize,
    area_m2: impl Fn(usize) -> f64,
    value: impl Fn(usize) -> f64,
) -> Vec<f64> {
    let mut sum = vec![0.0f64; vertex_count];
    let mut area = vec![0.0f64; vertex_count];
    for (j, t) in triangles.iter().enumerate() {
        let (a, x) = (area_m2(j), value(j));
        for &v in t {
            sum[v as usize] += a * x;
            area[v as usize] += a;
        }
    }
    for (s, &a) in sum.iter_mut().zip(&area) {
        *s = if a > 0.0 { *s / a } else { 0.0 };
    }
    sum
}

/// Vertex → adjacent triangles, in triangle order (compressed rows).
pub struct VertexFaces {
    start: Vec<usize>,
    faces: Vec<u32>,
}

impl VertexFaces {
    pub fn new(triangles: &[[u32; 3]], vertex_count: usize) -> VertexFaces {
        let mut start = vec![0usize; vertex_count + 1];
        for t in triangles {
            for &i in t {
                start[i as usize + 1] += 1;
            }
        }
        for i in 0..vertex_count {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut faces = vec![0u32; start[vertex_count]];
        for (k, t) in triangles.iter().enumerate() {
            for &i in t {
                faces[fill[i as usize]] = k as u32;
                fill[i as usize] += 1;
            }
        }
        VertexFaces { start, faces }
    }

    /// The triangles sharing vertex `v`, in increasing order.
    pub fn faces(&self, v: usize) -> &[u32] {
        &self.faces[self.start[v]..self.start[v + 1]]
    }

    /// Σ a_j·value(j) / Σ a_j over the triangles j of vertex `v` that `keep` accepts
    /// (summed in triangle order); None when their area is 0.
    pub fn area_weighted_mean<const N: usize>(
        &self,
        v: usize,
        area_m2: impl Fn(usize) -> f64,
        keep: impl Fn(usize) -> bool,
        value: impl Fn(usize) -> [f64; N],
    ) -> Option<[f64; N]> {
        let (mut sum, mut area) = ([0.0f64; N], 0.0f64);
        for &j in self.faces(v) {
            let j = j as usize;
            if !keep(j) {
                continue;
            }
            let (a, x) = (area_m2(j), value(j));
            for c in 0..N {
                sum[c] += a * x[c];
            }
            area += a;
        }
        (area > 0.0).then(|| sum.map(|s| s / area))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertex_mean_weighs_faces_by_area() {
        let vf = VertexFaces::new(&[[0, 1, 2], [0, 2, 3]], 5);
        assert_eq!(vf.faces(0), &[0, 1]);
        let mean = vf.area_weighted_mean(0, |j| [1.0, 3.0][j], |_| true, |j| [[10.0, 20.0][j]]);
        assert_eq!(mean, Some([17.5]));
        assert_eq!(
            vf.area_weighted_mean(4, |j| [1.0, 3.0][j], |_| true, |_| [1.0]),
            None
        );
    }

    #[test]
    fn vertex_means_are_the_unfiltered_means_bit_for_bit() {
        let triangles = [[0, 1, 2], [0, 2, 3], [3, 2, 4], [1, 1, 2]];
        let area_m2 = [0.1, 0.3, 0.7, 0.0];
        let value = |j: usize| [1.0 / 3.0, 7.1, 0.2, 5.0][j];
        let vf = VertexFaces::new(&triangles, 6);
        let means = vertex_means(&triangles, 6, |j| area_m2[j], value);
        for (v, &m) in means.iter().enumerate() {
            let expected = vf.area_weighted_mean(v, |j| area_m2[j], |_| true, |j| [value(j)]);
            assert_eq!(
                m.to_bits(),
                expected.map_or(0.0, |[e]| e).to_bits(),
                "vertex {v}"
            );
        }
    }
}
