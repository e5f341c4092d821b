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
    /// With [`VertexFaces::by_position`]: each vertex's representative among the
    /// vertices at its position (rows are the representatives').
    representative: Option<Vec<u32>>,
}

impl VertexFaces {
    pub fn new(triangles: &[[u32; 3]], vertex_count: usize) -> VertexFaces {
        Self::rows(triangles, vertex_count, |i| i)
    }

    /// [`VertexFaces::new`] with the vertices at one position counted as one vertex, so
    /// that the neighbours of a mesh whose triangles keep their own vertices (a
    /// flat-shaded OBJ or glTF, an STL export, a crease split for its normals) are found
    /// all the same.
    pub fn by_position(triangles: &[[u32; 3]], vertices: &[glam::Vec3]) -> VertexFaces {
        use rayon::prelude::*;
        // + 0.0 makes −0.0 +0.0: one point, one key.
        let key = |i: u32| vertices[i as usize].to_array().map(|x| (x + 0.0).to_bits());
        // Only vertices whose key's hash bucket holds another vertex can share a point:
        // one pass over two bit sets (bucket seen, seen twice) leaves the sort those few
        // on a mesh that shares its vertices (all of them on one that does not).
        let buckets = (8 * vertices.len()).next_power_of_two().max(64);
        let bucket = |i: u32| {
            let [x, y, z] = key(i).map(u64::from);
            let h = (x | y << 32).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ z;
            (h.wrapping_mul(0xbf58_476d_1ce4_e5b9) >> 32) as usize & (buckets - 1)
        };
        let (mut seen, mut twice) = (vec![0u64; buckets / 64], vec![0u64; buckets / 64]);
        for i in 0..vertices.len() as u32 {
            let b = bucket(i);
            let (word, bit) = (b / 64, 1u64 << (b % 64));
            twice[word] |= seen[word] & bit;
            seen[word] |= bit;
        }
        drop(seen);
        let shared_bucket = |i: &u32| {
            let b = bucket(*i);
            twice[b / 64] & (1 << (b % 64)) != 0
        };
        let mut order: Vec<u32> = (0..vertices.len() as u32).filter(shared_bucket).collect();
        drop(twice);
        order.par_sort_unstable_by_key(|&i| (key(i), i));
        let mut representative: Vec<u32> = (0..vertices.len() as u32).collect();
        for run in order.chunk_by(|&a, &b| key(a) == key(b)) {
            for &i in run {
                representative[i as usize] = run[0];
            }
        }
        drop(order);
        if representative
            .iter()
            .enumerate()
            .all(|(i, &r)| r as usize == i)
        {
            // Every vertex at its own point: the plain rows, without the mapping's memory.
            drop(representative);
            return Self::new(triangles, vertices.len());
        }
        let mut rows = Self::rows(triangles, vertices.len(), |i| representative[i as usize]);
        rows.representative = Some(representative);
        rows
    }

    /// The rows of the vertices `vertex(i)` stands for each triangle corner i.
    fn rows(
        triangles: &[[u32; 3]],
        vertex_count: usize,
        vertex: impl Fn(u32) -> u32,
    ) -> VertexFaces {
        let mut start = vec![0usize; vertex_count + 1];
        for t in triangles {
            for &i in t {
                start[vertex(i) as usize + 1] += 1;
            }
        }
        for i in 0..vertex_count {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut faces = vec![0u32; start[vertex_count]];
        for (k, t) in triangles.iter().enumerate() {
            for &i in t {
                let v = vertex(i) as usize;
                faces[fill[v]] = k as u32;
                fill[v] += 1;
            }
        }
        VertexFaces {
            start,
            faces,
            representative: None,
        }
    }

    /// The triangles sharing vertex `v` (with [`VertexFaces::by_position`]: sharing its
    /// position), in increasing order.
    pub fn faces(&self, v: usize) -> &[u32] {
        let v = self.representative.as_ref().map_or(v, |r| r[v] as usize);
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
    fn vertices_at_one_position_share_their_faces() {
        use glam::Vec3;
        // Two triangles with their own vertices meeting along an edge (x = 1), a third
        // touching at one corner with −0.0 for 0.
        let vertices = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-0.0, 0.0, -0.0),
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(0.0, -1.0, 0.0),
        ];
        let triangles = [[0, 1, 2], [3, 4, 5], [6, 7, 8]];
        let welded = VertexFaces::by_position(&triangles, &vertices);
        assert_eq!(welded.faces(1), &[0, 1]);
        assert_eq!(welded.faces(3), &[0, 1]);
        assert_eq!(welded.faces(5), &[0, 1]);
        assert_eq!(welded.faces(0), &[0, 2]);
        assert_eq!(welded.faces(6), &[0, 2]);
        assert_eq!(welded.faces(4), &[1]);
        let by_index = VertexFaces::new(&triangles, vertices.len());
        assert_eq!(by_index.faces(1), &[0]);
        assert_eq!(by_index.faces(6), &[2]);
    }

    #[test]
    fn by_position_finds_every_vertex_at_a_point() {
        use glam::Vec3;
        // 3000 vertices on a 12 × 12 × 12 lattice (many at one point, some alone), one
        // triangle per three: the faces of each vertex against a search of all.
        let mut rng = crate::rng::aux_stream(9);
        let mut coordinate = || (crate::sampling::uniform(&mut rng) * 12.0).floor() as f32;
        let vertices: Vec<Vec3> = (0..3000)
            .map(|_| Vec3::new(coordinate(), coordinate(), coordinate()))
            .collect();
        let triangles: Vec<[u32; 3]> = (0..1000).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let welded = VertexFaces::by_position(&triangles, &vertices);
        for (v, p) in vertices.iter().enumerate() {
            let expected: Vec<u32> = (0..triangles.len() as u32)
                .filter(|&t| {
                    triangles[t as usize]
                        .iter()
                        .any(|&i| vertices[i as usize] == *p)
                })
                .flat_map(|t| {
                    let corners = triangles[t as usize].iter();
                    corners
                        .filter(|&&i| vertices[i as usize] == *p)
                        .map(move |_| t)
                })
                .collect();
            assert_eq!(welded.faces(v), &expected[..], "vertex {v} at {p}");
        }
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
