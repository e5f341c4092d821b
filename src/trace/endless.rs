//! Scenes whose exact answer is infinite: every surface keeps all the light it receives
//! and the geometry closes around a light, so no photon is ever absorbed or escapes and
//! every illuminance is infinite. Such a scene is refused before its first photon
//! (docs/method.md, *Bounce cap*); anything else runs, a lossless scene with the largest
//! bounce cap and its bias bound judged by what the cap stopped.

use super::emit::Emitters;
use crate::scene::{Material, Scene};
use crate::{Error, Result};
use glam::DVec3;
use rand_pcg::Pcg32;
use std::collections::HashMap;

/// The material keeps every photon it receives: its roulette never ends a path (albedo
/// above 1 − 2⁻³², [`super::survival_threshold`]) and it has no glossy lobe (GGX lobes
/// lose energy). Lambertian reflection and transmission, ideal mirrors and clear glass.
pub fn keeps_every_photon(m: &Material) -> bool {
    let kept = match &m.glazing {
        // Panes that absorb nothing reflect or pass every photon.
        Some(g) => g.transmissivities.iter().all(|&t| t == 1.0),
        None => super::survival_threshold(m.albedo()) == 1 << 32,
    };
    m.glossy_reflectance == 0.0 && m.glossy_transmittance == 0.0 && kept
}

/// [`keeps_every_photon`] and lets none through: no photon crosses a surface of it.
pub fn traps(m: &Material) -> bool {
    keeps_every_photon(m)
        && m.transmittance == 0.0
        && m.specular_transmittance == 0.0
        && m.glazing.is_none()
}

/// Per triangle, whether it belongs to a closed surface: its connected component (the
/// triangles joined through shared edges, vertices welded by position) has every edge
/// shared by an even number of its triangles, so it has no boundary (mod 2) and how
/// often a ray from a point crosses it has the same parity along every ray, odd exactly
/// when the point is enclosed.
pub fn closed_triangles(triangles: &[[u32; 3]], vertices: &[glam::Vec3]) -> Vec<bool> {
    let mut welded: HashMap<[u32; 3], u32> = HashMap::new();
    let id: Vec<u32> = vertices
        .iter()
        .map(|v| {
            let key = v.to_array().map(|x| (x + 0.0).to_bits());
            let next = welded.len() as u32;
            *welded.entry(key).or_insert(next)
        })
        .collect();
    // Union-find over triangles joined through an edge.
    let mut parent: Vec<usize> = (0..triangles.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut edges: HashMap<(u32, u32), (u32, usize)> = HashMap::new();
    for (k, t) in triangles.iter().enumerate() {
        let c = t.map(|i| id[i as usize]);
        for (a, b) in [(c[0], c[1]), (c[1], c[2]), (c[2], c[0])] {
            if a == b {
                continue;
            }
            let e = edges.entry((a.min(b), a.max(b))).or_insert((0, k));
            e.0 += 1;
            let (ra, rb) = (root(&mut parent, e.1), root(&mut parent, k));
            parent[ra] = rb;
        }
    }
    let mut open = vec![false; triangles.len()];
    for &(count, k) in edges.values() {
        if count % 2 == 1 {
            let r = root(&mut parent, k);
            open[r] = true;
        }
    }
    (0..triangles.len())
        .map(|k| !open[root(&mut parent, k)])
        .collect()
}

/// How many triangles the ray from `o` along `d` crosses (Möller–Trumbore in f64).
fn crossings(triangles: &[[u32; 3]], vertices: &[glam::Vec3], o: DVec3, d: DVec3) -> usize {
    triangles
        .iter()
        .filter(|t| {
            let [a, b, c] = t.map(|i| vertices[i as usize].as_dvec3());
            let (e1, e2) = (b - a, c - a);
            let p = d.cross(e2);
            let det = e1.dot(p);
            if det.abs() < 1e-300 {
                return false;
            }
            let s = o - a;
            let u = s.dot(p) / det;
            let q = s.cross(e1);
            let v = d.dot(q) / det;
            let t = e2.dot(q) / det;
            u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0
        })
        .count()
}

/// Three fixed directions, none along an axis or a diagonal (so that rays miss the
/// edges of boxes and grids).
const PROBES: [[f64; 3]; 3] = [
    [0.267_261, 0.534_522, 0.801_784],
    [-0.639_602, 0.301_511, -0.690_143],
    [0.154_303, -0.925_820, 0.345_033],
];

/// Photon origins sampled per light for the enclosure test.
const ORIGINS_PER_LIGHT: usize = 4;

/// Refuses, in one line, a scene whose exact answer is infinite: every material its
/// triangles use keeps every photon ([`keeps_every_photon`]), no instanced object (whose
/// meshes are not looked at here), and some light's photons start enclosed by closed
/// surfaces ([`closed_triangles`]) that let no photon through ([`traps`]): odd crossings
/// of those along three rays from each of a few sampled photon origins. Such a photon
/// can never leave and is never absorbed. Every test errs towards running: a scene it
/// lets through runs with the largest cap and says what the cap stopped.
pub fn refuse_endless(scene: &Scene, emitters: &Emitters) -> Result<()> {
    let g = &scene.geometry;
    if !(emitters.total_flux_lm > 0.0) || g.triangle_count() == 0 || !g.instanced.is_empty() {
        return Ok(());
    }
    let mut used = vec![false; scene.materials.len()];
    for m in g.material.iter() {
        used[m as usize] = true;
    }
    let lossless = (used.iter().zip(&scene.materials)).all(|(&u, m)| !u || keeps_every_photon(m));
    if !lossless {
        return Ok(());
    }
    let closed = closed_triangles(&g.triangles, &g.vertices);
    let walls: Vec<[u32; 3]> = (g.triangles.iter().enumerate())
        .filter(|&(k, _)| closed[k] && traps(&scene.materials[g.material.get(k) as usize]))
        .map(|(_, t)| *t)
        .collect();
    if walls.is_empty() {
        return Ok(());
    }
    // The walls' own components may have lost triangles to the filter (a closed surface
    // partly of glass): only the ones still closed count.
    let still_closed = closed_triangles(&walls, &g.vertices);
    let walls: Vec<[u32; 3]> = (walls.iter().zip(&still_closed))
        .filter(|(_, &c)| c)
        .map(|(t, _)| *t)
        .collect();
    let mut rng = Pcg32::new(0x5eed_c105ed, 0);
    for (light, &flux) in emitters.flux_lm.iter().enumerate() {
        if !(flux > 0.0) {
            continue;
        }
        for _ in 0..ORIGINS_PER_LIGHT {
            let (o, _) = emitters.sample(light, &mut rng);
            let enclosed = !walls.is_empty()
                && PROBES.iter().all(|d| {
                    let d = DVec3::from_array(*d).normalize();
                    crossings(&walls, &g.vertices, o, d) % 2 == 1
                });
            if enclosed {
                let label = scene.lights.get(light).map_or("a light", |l| &l.label);
                return Err(Error::input(
                    scene.path.display().to_string(),
                    format!(
                        "the exact answer is infinite: every surface keeps all the light it \
                         receives (albedo 1, nothing absorbed) and closed opaque surfaces enclose \
                         {label}, so no photon ever ends; give a material an albedo below 1 or \
                         open the geometry"
                    ),
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A unit cube's 12 triangles with their own vertices (as an STL would), the top
    /// face left out if `open`.
    fn cube(open: bool) -> (Vec<[u32; 3]>, Vec<Vec3>) {
        let (mut tris, mut verts) = (vec![], vec![]);
        let quads = [
            [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
            [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
            [[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]],
            [[0, 1, 0], [1, 1, 0], [1, 1, 1], [0, 1, 1]],
            [[0, 0, 0], [0, 1, 0], [0, 1, 1], [0, 0, 1]],
            [[1, 0, 0], [1, 1, 0], [1, 1, 1], [1, 0, 1]],
        ];
        for (k, q) in quads.iter().enumerate() {
            if open && k == 1 {
                continue;
            }
            let p: Vec<Vec3> = q
                .iter()
                .map(|c| Vec3::from_array(c.map(|x| x as f32)))
                .collect();
            for tri in [[0, 1, 2], [0, 2, 3]] {
                let base = verts.len() as u32;
                verts.extend(tri.map(|i| p[i]));
                tris.push([base, base + 1, base + 2]);
            }
        }
        (tris, verts)
    }

    #[test]
    fn a_welded_cube_is_closed_and_encloses_its_centre() {
        let (t, v) = cube(false);
        assert!(closed_triangles(&t, &v).iter().all(|&c| c));
        let (to, vo) = cube(true);
        assert!(closed_triangles(&to, &vo).iter().all(|&c| !c));
        // A closed cube beside an open one: only the first one's triangles are closed.
        let (mut both, mut bv) = (t.clone(), v.clone());
        let shift = Vec3::new(3.0, 0.0, 0.0);
        both.extend(to.iter().map(|tri| tri.map(|i| i + v.len() as u32)));
        bv.extend(vo.iter().map(|p| *p + shift));
        let closed = closed_triangles(&both, &bv);
        assert!(closed[..12].iter().all(|&c| c) && closed[12..].iter().all(|&c| !c));
        for d in PROBES {
            let d = DVec3::from_array(d).normalize();
            assert_eq!(crossings(&t, &v, DVec3::splat(0.5), d), 1);
            assert_eq!(crossings(&t, &v, DVec3::new(0.5, 0.5, 3.0), d) % 2, 0);
        }
    }

    #[test]
    fn only_lossless_opaque_materials_keep_every_photon() {
        let white = Material::lambertian("w", 1.0);
        assert!(traps(&white));
        assert!(!keeps_every_photon(&Material::lambertian("g", 0.99995)));
        let glass = Material {
            specular_transmittance: 1.0,
            ..Material::lambertian("glass", 0.0)
        };
        assert!(keeps_every_photon(&glass) && !traps(&glass));
        let glossy = Material {
            glossy_reflectance: 1.0,
            ..Material::lambertian("glossy", 0.0)
        };
        assert!(!keeps_every_photon(&glossy));
        let mirror = Material {
            specular_reflectance: 1.0,
            ..Material::lambertian("m", 0.0)
        };
        assert!(traps(&mirror));
    }
}
