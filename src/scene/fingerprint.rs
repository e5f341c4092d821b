//! Fingerprints of a loaded scene, carried by the files a run saves so that a file made
//! from another scene is refused: 64-bit FNV-1a over the geometry's bits and the `Debug`
//! prints of materials, lights and receivers (which print every f64 so that it reads
//! back to the same bits).

use super::Scene;

/// What the light on the scene's surfaces depends on: the geometry (vertices, triangles
/// and their materials, and the instanced objects that shadow them), the materials and
/// the lights (photometry included). The indirect map (indirect_map.bin) carries it:
/// receivers and the camera do not change the map.
pub fn light_transport(scene: &Scene) -> u64 {
    let mut h = Fnv::new();
    h.light_transport(scene);
    h.0
}

/// What a run's numbers depend on: [`light_transport`]'s inputs, the receivers and the
/// object each triangle and instance comes from. Checkpoints carry it.
pub fn run(scene: &Scene) -> u64 {
    let mut h = Fnv::new();
    h.light_transport(scene);
    let g = &scene.geometry;
    for o in g.object.iter() {
        h.eat(&o.to_le_bytes());
    }
    for i in &g.instanced.instances {
        h.eat(&i.object.to_le_bytes());
    }
    h.eat(format!("{:?}", scene.receivers).as_bytes());
    h.0
}

struct Fnv(u64);

impl Fnv {
    fn new() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }

    fn eat(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }

    fn floats(&mut self, xs: impl IntoIterator<Item = f32>) {
        for x in xs {
            self.eat(&x.to_le_bytes());
        }
    }

    fn triangles(&mut self, triangles: &[[u32; 3]], material: impl Iterator<Item = u32>) {
        for (t, m) in triangles.iter().zip(material) {
            for i in t {
                self.eat(&i.to_le_bytes());
            }
            self.eat(&m.to_le_bytes());
        }
    }

    /// The bytes of [`light_transport`], in an order indirect_map.bin files depend on.
    fn light_transport(&mut self, scene: &Scene) {
        let g = &scene.geometry;
        for x in g.origin.to_array() {
            self.eat(&x.to_le_bytes());
        }
        for v in &g.vertices {
            self.floats(v.to_array());
        }
        self.triangles(&g.triangles, g.material.iter());
        for p in &g.instanced.prototypes {
            self.eat(&(p.triangles.len() as u64).to_le_bytes());
            for v in &p.vertices {
                self.floats(v.to_array());
            }
            self.triangles(&p.triangles, p.material.iter().copied());
        }
        for i in &g.instanced.instances {
            self.eat(&i.prototype.to_le_bytes());
            self.floats(i.to_local);
        }
        self.eat(format!("{:?}", scene.materials).as_bytes());
        self.eat(format!("{:?}", scene.lights).as_bytes());
    }
}
