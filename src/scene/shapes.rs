//! Built-in shapes (box, parallelogram, icosphere) as indexed triangle meshes in f64, and
//! the object transform (scale → rotate → translate) applied to every object's vertices.

use glam::{DAffine3, DMat3, DVec3};
use std::collections::HashMap;

/// An indexed triangle mesh in world (or object) coordinates, f64 until `Geometry`.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub vertices: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// Axis-aligned box, 12 triangles with outward normals. Caller ensures `min < max`.
pub fn make_box(min: DVec3, max: DVec3) -> Mesh {
    // Vertex k has x from bit 0, y from bit 1, z from bit 2.
    let vertices = (0..8)
        .map(|k| {
            DVec3::new(
                if k & 1 == 0 { min.x } else { max.x },
                if k & 2 == 0 { min.y } else { max.y },
                if k & 4 == 0 { min.z } else { max.z },
            )
        })
        .collect();
    // Each face as a quad wound counter-clockwise seen from outside.
    let quads: [[u32; 4]; 6] = [
        [0, 4, 6, 2], // x = min, normal −x
        [1, 3, 7, 5], // x = max, normal +x
        [0, 1, 5, 4], // y = min, normal −y
        [2, 6, 7, 3], // y = max, normal +y
        [0, 2, 3, 1], // z = min, normal −z
        [4, 5, 7, 6], // z = max, normal +z
    ];
    let triangles = quads
        .iter()
        .flat_map(|[a, b, c, d]| [[*a, *b, *c], [*a, *c, *d]])
        .collect();
    Mesh {
        vertices,
        triangles,
    }
}

/// Parallelogram corner, corner+u, corner+u+v, corner+v: two triangles, normal u × v.
pub fn make_rect(corner: DVec3, u: DVec3, v: DVec3) -> Mesh {
    Mesh {
        vertices: vec![corner, corner + u, corner + u + v, corner + v],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// Sphere subdivisions when the scene file gives none, and the most it may give
/// (8: 1.3 M triangles per sphere).
pub const DEFAULT_SPHERE_SUBDIVISIONS: u32 = 3;
pub const MAX_SPHERE_SUBDIVISIONS: u32 = 8;

/// Triangles of [`make_box`] and [`make_rect`], known before they are built (so a scene
/// can be sized before it is tessellated).
pub const BOX_TRIANGLES: u64 = 12;
pub const RECT_TRIANGLES: u64 = 2;

/// Triangles of [`make_sphere`] with `subdivisions` (default when `None`); `None` out
/// of range.
pub fn sphere_triangle_count(subdivisions: Option<u32>) -> Option<u64> {
    let s = subdivisions.unwrap_or(DEFAULT_SPHERE_SUBDIVISIONS);
    (s <= MAX_SPHERE_SUBDIVISIONS).then(|| 20 << (2 * s))
}

/// Icosphere: an icosahedron whose faces are split in four `subdivisions` times, vertices
/// projected onto the sphere, shared between faces, normals outward.
pub fn make_sphere(center: DVec3, radius: f64, subdivisions: u32) -> Mesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut unit: Vec<DVec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| DVec3::from_array(*p).normalize())
    .collect();
    // Counter-clockwise seen from outside.
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        // Edge midpoints are cached so neighbouring faces share them (no cracks).
        let mut midpoint: HashMap<(u32, u32), u32> = HashMap::new();
        let mut mid = |a: u32, b: u32, unit: &mut Vec<DVec3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *midpoint.entry(key).or_insert_with(|| {
                let p = (unit[a as usize] + unit[b as usize]).normalize();
                unit.push(p);
                (unit.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let ab = mid(a, b, &mut unit);
            let bc = mid(b, c, &mut unit);
            let ca = mid(c, a, &mut unit);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    Mesh {
        vertices: unit.iter().map(|p| center + radius * *p).collect(),
        triangles: faces,
    }
}

/// The per-object transform: scale, then rotate (R = Rz·Ry·Rx, degrees), then translate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub scale: DVec3,
    pub rotate_deg: DVec3,
    pub translate: DVec3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            scale: DVec3::ONE,
            rotate_deg: DVec3::ZERO,
            translate: DVec3::ZERO,
        }
    }
}

impl Transform {
    pub fn rotation(&self) -> DMat3 {
        let r = self.rotate_deg * (std::f64::consts::PI / 180.0);
        DMat3::from_rotation_z(r.z) * DMat3::from_rotation_y(r.y) * DMat3::from_rotation_x(r.x)
    }

    /// The transform as one affine map: x ↦ R·(S·x) + t.
    pub fn affine(&self) -> DAffine3 {
        DAffine3::from_mat3_translation(
            self.rotation() * DMat3::from_diagonal(self.scale),
            self.translate,
        )
    }

    /// Applies the transform to every vertex in place, in f64.
    pub fn apply(&self, vertices: &mut [DVec3]) {
        if *self == Transform::default() {
            return;
        }
        let rotation = self.rotation();
        for p in vertices {
            *p = rotation * (*p * self.scale) + self.translate;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_counts_match_the_shapes_built() {
        let (o, x) = (DVec3::ZERO, DVec3::X);
        assert_eq!(
            BOX_TRIANGLES,
            make_box(o, DVec3::ONE).triangles.len() as u64
        );
        assert_eq!(
            RECT_TRIANGLES,
            make_rect(o, x, DVec3::Y).triangles.len() as u64
        );
        for s in 0..=4 {
            let built = make_sphere(o, 1.0, s).triangles.len() as u64;
            assert_eq!(sphere_triangle_count(Some(s)), Some(built));
        }
        assert_eq!(
            sphere_triangle_count(None),
            Some(
                make_sphere(o, 1.0, DEFAULT_SPHERE_SUBDIVISIONS)
                    .triangles
                    .len() as u64
            )
        );
        assert_eq!(
            sphere_triangle_count(Some(MAX_SPHERE_SUBDIVISIONS + 1)),
            None
        );
    }
}
