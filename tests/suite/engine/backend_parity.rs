//! Ray-casting backends: Embree's four query APIs agree with each other, Embree and
//! obvhs agree (feature `obvhs`), results do not depend on where in the world a mesh
//! sits, and Embree errors surface as `Err`.

use glam::DVec3;
use luxtally::accel::embree::EmbreeScene;
use luxtally::accel::{HitBatch, RayApi, RayBatch, RayCaster, NO_HIT};
use luxtally::fixtures::{load_obj_geometry, local_bounds, random_rays, random_segments};
use luxtally::scene::Geometry;
use std::path::PathBuf;

const RAYS: usize = 100_000;

fn mesh(name: &str, offset: DVec3) -> Geometry {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/meshes")
        .join(name);
    load_obj_geometry(&path, offset).expect("test mesh loads")
}

/// Traces `rays` in batches whose lengths cycle through awkward sizes (not multiples of
/// the packet widths), concatenating the results.
fn trace_in_pieces(caster: &dyn RayCaster, api: RayApi, rays: &RayBatch) -> (HitBatch, Vec<bool>) {
    const LENGTHS: [usize; 6] = [1, 7, 17, 1000, 4096, 333];
    let mut all = HitBatch::default();
    let mut occ_all = Vec::new();
    let (mut hits, mut occ) = (HitBatch::default(), Vec::new());
    let mut start = 0;
    let mut k = 0;
    while start < rays.len() {
        let end = (start + LENGTHS[k % LENGTHS.len()]).min(rays.len());
        k += 1;
        let piece = RayBatch {
            ox: rays.ox[start..end].to_vec(),
            oy: rays.oy[start..end].to_vec(),
            oz: rays.oz[start..end].to_vec(),
            dx: rays.dx[start..end].to_vec(),
            dy: rays.dy[start..end].to_vec(),
            dz: rays.dz[start..end].to_vec(),
            tnear: rays.tnear[start..end].to_vec(),
            tfar: rays.tfar[start..end].to_vec(),
        };
        caster.intersect_with(api, &piece, &mut hits);
        caster.occluded_with(api, &piece, &mut occ);
        assert_eq!(hits.len(), piece.len());
        assert_eq!(occ.len(), piece.len());
        all.t.extend_from_slice(&hits.t);
        all.tri.extend_from_slice(&hits.tri);
        all.u.extend_from_slice(&hits.u);
        all.v.extend_from_slice(&hits.v);
        all.ngx.extend_from_slice(&hits.ngx);
        all.ngy.extend_from_slice(&hits.ngy);
        all.ngz.extend_from_slice(&hits.ngz);
        occ_all.extend_from_slice(&occ);
        start = end;
    }
    (all, occ_all)
}

/// Shadow rays between random points of the mesh's bounds.
fn shadow_rays(g: &Geometry, seed: u64) -> RayBatch {
    let (lo, hi) = local_bounds(g);
    random_segments(lo, hi, RAYS, seed)
}

#[test]
fn embree_apis_agree_with_each_other() {
    let g = mesh("stanford-bunny.obj", DVec3::ZERO);
    let scene = EmbreeScene::new(&g).expect("embree builds");
    let (lo, hi) = local_bounds(&g);
    // Rays from a box twice the mesh's size, so some start outside it.
    let c = (lo + hi) * 0.5;
    let rays = random_rays(c + (lo - c) * 2.0, c + (hi - c) * 2.0, RAYS, 7);
    let shadow = shadow_rays(&g, 8);
    let (reference, _) = trace_in_pieces(&scene, RayApi::Single, &rays);
    let (_, occ_reference) = trace_in_pieces(&scene, RayApi::Single, &shadow);
    let hits = reference.tri.iter().filter(|&&t| t != NO_HIT).count();
    assert!(
        hits > RAYS / 10 && hits < RAYS,
        "{hits} hits: rays do not probe the mesh"
    );
    let blocked = occ_reference.iter().filter(|&&o| o).count();
    assert!(blocked > RAYS / 20 && blocked < RAYS, "{blocked} occluded");

    // Embree's normal is the triangle's (v1 − v0) × (v2 − v0), normalised.
    for i in (0..RAYS).filter(|&i| reference.tri[i] != NO_HIT) {
        let n = g.normal(reference.tri[i] as usize);
        let dot = n.x * reference.ngx[i] + n.y * reference.ngy[i] + n.z * reference.ngz[i];
        assert!(
            dot > 0.999,
            "ray {i}: normal disagrees with Geometry::normal ({dot})"
        );
    }

    for api in [RayApi::Packet8, RayApi::Packet16, RayApi::Stream] {
        let (h, _) = trace_in_pieces(&scene, api, &rays);
        let (_, occ) = trace_in_pieces(&scene, api, &shadow);
        for i in 0..RAYS {
            assert_eq!(h.tri[i], reference.tri[i], "{api:?} ray {i}: triangle");
            assert_eq!(
                h.t[i].to_bits(),
                reference.t[i].to_bits(),
                "{api:?} ray {i}: t"
            );
            assert_eq!(
                h.u[i].to_bits(),
                reference.u[i].to_bits(),
                "{api:?} ray {i}: u"
            );
            assert_eq!(
                h.v[i].to_bits(),
                reference.v[i].to_bits(),
                "{api:?} ray {i}: v"
            );
            assert_eq!(h.ngx[i], reference.ngx[i], "{api:?} ray {i}: normal");
        }
        assert_eq!(occ, occ_reference, "{api:?}: occlusion");
    }
}

#[test]
fn embree_respects_tnear_and_tfar() {
    // One triangle in the plane z = 0; rays along −z from z = 1.
    let g = Geometry::from_world(
        &[
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ],
        &[[0, 1, 2]],
        &[0],
        &[0],
    );
    let scene = EmbreeScene::new(&g).expect("embree builds");
    let mut rays = RayBatch::default();
    rays.push([0.0, 0.0, 1.0], [0.0, 0.0, -1.0], 0.0, f32::INFINITY); // hit at 1
    rays.push([0.0, 0.0, 1.0], [0.0, 0.0, -1.0], 0.0, 0.5); // too short
    rays.push([0.0, 0.0, 1.0], [0.0, 0.0, -1.0], 1.5, 3.0); // starts past it
    rays.push([0.0, 0.0, 1.0], [0.0, 0.0, 1.0], 0.0, f32::INFINITY); // away
    for api in RayApi::ALL {
        let mut hits = HitBatch::default();
        let mut occ = Vec::new();
        scene.intersect_with(api, &rays, &mut hits);
        scene.occluded_with(api, &rays, &mut occ);
        assert_eq!(hits.tri, [0, NO_HIT, NO_HIT, NO_HIT], "{api:?}");
        assert!((hits.t[0] - 1.0).abs() < 1e-6, "{api:?}");
        assert_eq!(hits.t[1], f32::INFINITY);
        assert_eq!(occ, [true, false, false, false], "{api:?}");
    }
}

/// World-space rays through a mesh placed at `offset`, converted to its local frame.
fn world_rays(g: &Geometry, offset: DVec3, template: &RayBatch) -> RayBatch {
    let mut rays = RayBatch::with_capacity(template.len());
    for i in 0..template.len() {
        let world = DVec3::new(
            template.ox[i] as f64,
            template.oy[i] as f64,
            template.oz[i] as f64,
        ) + offset;
        let local = (world - g.origin).as_vec3();
        rays.push(
            local.to_array(),
            [template.dx[i], template.dy[i], template.dz[i]],
            template.tnear[i],
            template.tfar[i],
        );
    }
    rays
}

fn far_from_origin(build: impl Fn(&Geometry) -> Box<dyn RayCaster>) {
    let offset = DVec3::splat(1e5);
    let near = mesh("stanford-bunny.obj", DVec3::ZERO);
    let far = mesh("stanford-bunny.obj", offset);
    assert_eq!(near.triangles, far.triangles);
    // Template rays in the near mesh's world frame.
    let (lo, hi) = local_bounds(&near);
    let local = random_rays(lo, hi, RAYS, 11);
    let mut template = local.clone(); // local → world (the near mesh sits near 0)
    for i in 0..RAYS {
        template.ox[i] = (local.ox[i] as f64 + near.origin.x) as f32;
        template.oy[i] = (local.oy[i] as f64 + near.origin.y) as f32;
        template.oz[i] = (local.oz[i] as f64 + near.origin.z) as f32;
    }
    let (a, b) = (build(&near), build(&far));
    let (mut ha, mut hb) = (HitBatch::default(), HitBatch::default());
    a.intersect(&world_rays(&near, DVec3::ZERO, &template), &mut ha);
    b.intersect(&world_rays(&far, offset, &template), &mut hb);
    let mut hits = 0;
    for i in 0..RAYS {
        assert_eq!(ha.tri[i], hb.tri[i], "ray {i}: triangle");
        if ha.tri[i] != NO_HIT {
            hits += 1;
            let rel = (ha.t[i] - hb.t[i]).abs() / ha.t[i].max(1e-3);
            assert!(rel <= 1e-5, "ray {i}: t {} vs {}", ha.t[i], hb.t[i]);
        }
    }
    assert!(hits > RAYS / 10, "only {hits} hits");
}

#[test]
fn embree_far_from_origin_matches_origin() {
    far_from_origin(|g| Box::new(EmbreeScene::new(g).expect("embree builds")));
}

#[test]
fn embree_errors_become_err() {
    // An unknown device option: Embree reports it, we return it.
    let g = mesh("teapot.obj", DVec3::ZERO);
    match EmbreeScene::with_device_config(&g, "no_such_option=1,threads=banana") {
        Err(luxtally::Error::Embree(msg)) => assert!(!msg.is_empty()),
        Err(other) => panic!("wrong error kind: {other}"),
        Ok(_) => panic!("a bad device config was accepted"),
    }
    // Triangles pointing past the vertex array never reach Embree.
    let mut bad = g.clone();
    bad.triangles[0][1] = bad.vertices.len() as u32;
    assert!(matches!(
        EmbreeScene::new(&bad),
        Err(luxtally::Error::Embree(_))
    ));
    // An empty scene is fine and hits nothing.
    let empty = EmbreeScene::new(&Geometry::default()).expect("empty scene builds");
    let rays = random_rays(glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0), 100, 3);
    let mut hits = HitBatch::default();
    empty.intersect(&rays, &mut hits);
    assert!(hits.tri.iter().all(|&t| t == NO_HIT));
}

#[cfg(feature = "obvhs")]
mod parity {
    use super::*;
    use luxtally::accel::obvhs::ObvhsScene;
    use luxtally::fixtures::procedural_geometry;

    /// Distances agree to 1e-4 relative, or to 1e-6 of the scene's size (f32 positions
    /// cannot pin down hits closer than that to the ray origin any better).
    fn close(a: f32, b: f32, scale: f32) -> bool {
        (a - b).abs() <= 1e-4 * a.abs().max(b.abs()) + 1e-6 * scale
    }

    fn parity(name: &str, g: &Geometry) {
        let embree = EmbreeScene::new(g).expect("embree builds");
        let obvhs = ObvhsScene::new(g);
        let (lo, hi) = local_bounds(g);
        let scale = (hi - lo).length();
        let rays = random_rays(lo, hi, RAYS, 21);
        let shadow = random_segments(lo, hi, RAYS, 22);
        let (mut he, mut ho) = (HitBatch::default(), HitBatch::default());
        embree.intersect(&rays, &mut he);
        obvhs.intersect(&rays, &mut ho);
        let (mut oe, mut oo) = (Vec::new(), Vec::new());
        embree.occluded(&shadow, &mut oe);
        obvhs.occluded(&shadow, &mut oo);

        let mut tolerated = 0; // grazing / coplanar cases
        let mut hits = 0;
        for i in 0..RAYS {
            let (te, to) = (he.tri[i], ho.tri[i]);
            if te == NO_HIT && to == NO_HIT {
                continue;
            }
            hits += 1;
            if (te == NO_HIT) != (to == NO_HIT) {
                tolerated += 1;
                continue;
            }
            assert!(
                close(he.t[i], ho.t[i], scale),
                "{name} ray {i}: t embree {} (tri {te}) vs obvhs {} (tri {to})",
                he.t[i],
                ho.t[i]
            );
            if te != to {
                tolerated += 1;
            } else {
                assert!((he.u[i] - ho.u[i]).abs() < 1e-3 && (he.v[i] - ho.v[i]).abs() < 1e-3);
                let dot = he.ngx[i] * ho.ngx[i] + he.ngy[i] * ho.ngy[i] + he.ngz[i] * ho.ngz[i];
                assert!(dot > 0.999, "{name} ray {i}: normals");
            }
        }
        let occl_diff = oe.iter().zip(&oo).filter(|(a, b)| a != b).count();
        let blocked = oe.iter().filter(|&&o| o).count();
        eprintln!(
            "{name}: {} triangles, {hits} hits, {tolerated} tolerated hit mismatches, {blocked} occluded, {occl_diff} occlusion mismatches",
            g.triangle_count()
        );
        assert!(hits > RAYS / 10, "{name}: only {hits} hits");
        assert!(
            tolerated * 10_000 < RAYS,
            "{name}: {tolerated} hit mismatches"
        );
        assert!(
            occl_diff * 10_000 < RAYS,
            "{name}: {occl_diff} occlusion mismatches"
        );
    }

    #[test]
    fn parity_bunny() {
        parity("bunny", &mesh("stanford-bunny.obj", DVec3::ZERO));
    }

    #[test]
    fn parity_teapot() {
        parity("teapot", &mesh("teapot.obj", DVec3::ZERO));
    }

    #[test]
    fn parity_procedural_million() {
        let g = procedural_geometry(1_000_000);
        assert!(g.triangle_count() >= 1_000_000, "{}", g.triangle_count());
        parity("procedural", &g);
    }

    #[test]
    fn obvhs_far_from_origin_matches_origin() {
        far_from_origin(|g| Box::new(ObvhsScene::new(g)));
    }
}

/// A square of side `side_m` (two triangles) hit head-on at a point off its diagonal:
/// the hit normal each backend reports.
fn normal_of_square(backend: luxtally::accel::Backend, side_m: f64) -> [f32; 3] {
    let text = format!(
        "[materials.m]\nreflectance = 0.5\n[[objects]]\nshape = \"rect\"\n\
         corner = [0, 0, 0]\nu = [{side_m:e}, 0, 0]\nv = [0, {side_m:e}, 0]\nmaterial = \"m\"\n\
         [[lights]]\ntype = \"point\"\nposition = [0, 0, 1]\nintensity_cd = 1\n"
    );
    let scene = luxtally::scene::load_str(&text, std::path::Path::new("."), "square.toml")
        .expect("square loads");
    let caster = luxtally::accel::build(backend, &scene.geometry).expect("backend builds");
    // The local frame is centred on the square; the ray starts at least 1 m above it
    // (obvhs loses hits closer than ~10⁻⁹ m to the ray's origin, see accel/obvhs.rs).
    let s = side_m as f32;
    let mut rays = RayBatch::default();
    rays.push(
        [0.1 * s, 0.2 * s, s.max(1.0)],
        [0.0, 0.0, -1.0],
        0.0,
        f32::INFINITY,
    );
    let mut hits = HitBatch::default();
    caster.intersect_with(caster.default_intersect_api(), &rays, &mut hits);
    assert_ne!(hits.tri[0], NO_HIT, "side {side_m} m: the ray misses");
    [hits.ngx[0], hits.ngy[0], hits.ngz[0]]
}

#[test]
fn hit_normals_are_unit_for_tiny_and_huge_triangles() {
    let mut backends = vec![luxtally::accel::Backend::Embree];
    if cfg!(feature = "obvhs") {
        backends.push(luxtally::accel::Backend::Obvhs);
    }
    for backend in backends {
        // Edges of 10⁻¹² m and 10¹² m: Embree's unnormalised normal has a squared length
        // below f32's smallest subnormal, or above f32's largest value.
        for side_m in [1e-12, 1e-3, 1.0, 1e12] {
            let n = normal_of_square(backend, side_m);
            let length = n.iter().map(|c| c * c).sum::<f32>().sqrt();
            assert!(
                (length - 1.0).abs() < 1e-6 && n[2].abs() > 0.999_999,
                "{backend:?}, side {side_m} m: normal {n:?}"
            );
        }
    }
}
