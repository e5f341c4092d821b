//! The secondary (indirect) illumination map the eye pass reads, per triangle face from
//! the photon pass's tallies, and its file `indirect_map.bin`, which `render --from`
//! reads to reuse a finished run.

use crate::scene::{fingerprint, Scene};
use crate::stats::{triangle_face_illuminance_lx, MapKind};
use crate::tally::Tallies;
use crate::{Error, Result};
use std::path::Path;

/// File name of the saved map in an output directory.
pub const MAP_FILE: &str = "indirect_map.bin";
const MAGIC: &[u8; 8] = b"LUXIMAP1";
const HEADER_BYTES: usize = 8 + 3 * 8;

/// Indirect illuminance (lx) of both faces of every triangle: `[front, back]`, front
/// being the side the triangle's normal points to.
#[derive(Clone, Debug, PartialEq)]
pub struct IndirectMap {
    pub face_lx: Vec<[f64; 2]>,
    /// Photons of the run the map comes from.
    pub photons: u64,
}

impl IndirectMap {
    /// The map of a finished photon pass.
    pub fn from_tallies(scene: &Scene, tallies: &Tallies, total_flux_lm: f64) -> IndirectMap {
        IndirectMap {
            face_lx: faces_of(scene, tallies, total_flux_lm).collect(),
            photons: tallies.photons,
        }
    }

    /// Writes the map of a finished photon pass straight from its tallies, face by face
    /// (the file [`IndirectMap::from_tallies`] then [`IndirectMap::save`] would write,
    /// without the map in memory).
    pub(super) fn save_from_tallies(
        path: &Path,
        scene: &Scene,
        tallies: &Tallies,
        total_flux_lm: f64,
    ) -> Result<()> {
        let faces = faces_of(scene, tallies, total_flux_lm);
        let count = scene.geometry.triangle_count();
        super::write_atomic(path, |w| write_map(w, scene, count, tallies.photons, faces))
    }

    /// A map of zeros (direct light only).
    pub fn zero(triangles: usize) -> IndirectMap {
        IndirectMap {
            face_lx: vec![[0.0; 2]; triangles],
            photons: 0,
        }
    }

    /// Writes the map: magic, then little-endian u64 triangle count, scene fingerprint
    /// (`scene::fingerprint::light_transport`) and photons, then f64 front and back illuminance per triangle.
    pub fn save(&self, path: &Path, scene: &Scene) -> Result<()> {
        let faces = self.face_lx.iter().copied();
        super::write_atomic(path, |w| {
            write_map(w, scene, self.face_lx.len(), self.photons, faces)
        })
    }

    /// Reads a map saved for `scene`; a map of another scene (other geometry, materials
    /// or lights) is an error.
    pub fn load(path: &Path, scene: &Scene) -> Result<IndirectMap> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        let bad = |message: &str| Error::input(path.display().to_string(), message.to_string());
        if bytes.len() < HEADER_BYTES || &bytes[..8] != MAGIC {
            return Err(bad("not a luxtally indirect map"));
        }
        let word = |i: usize| {
            let mut b = [0u8; 8];
            b.copy_from_slice(&bytes[8 + 8 * i..16 + 8 * i]);
            u64::from_le_bytes(b)
        };
        let (triangles, fingerprint, photons) = (word(0), word(1), word(2));
        if triangles != scene.geometry.triangle_count() as u64
            || fingerprint != fingerprint::light_transport(scene)
        {
            return Err(bad(&format!(
                "was made for another scene (or the scene `{}` changed since): run the photon pass again",
                scene.path.display()
            )));
        }
        if bytes.len() != HEADER_BYTES + 16 * triangles as usize {
            return Err(bad("truncated indirect map"));
        }
        let value = |i: usize| {
            let mut b = [0u8; 8];
            let at = HEADER_BYTES + 8 * i;
            b.copy_from_slice(&bytes[at..at + 8]);
            f64::from_le_bytes(b)
        };
        Ok(IndirectMap {
            face_lx: (0..triangles as usize)
                .map(|k| [value(2 * k), value(2 * k + 1)])
                .collect(),
            photons,
        })
    }
}

/// Indirect illuminance `[front, back]` (lx) of every triangle, from the tallies.
fn faces_of<'a>(
    scene: &'a Scene,
    tallies: &'a Tallies,
    total_flux_lm: f64,
) -> impl Iterator<Item = [f64; 2]> + 'a {
    let g = &scene.geometry;
    (0..g.triangle_count()).map(move |k| {
        let area_m2 = g.area_m2(k);
        let face = |back: bool| {
            triangle_face_illuminance_lx(
                tallies,
                MapKind::Indirect,
                k,
                area_m2,
                total_flux_lm,
                back,
            )
        };
        [face(false), face(true)]
    })
}

/// The file format of [`IndirectMap::save`], written to `w`.
fn write_map(
    w: &mut impl std::io::Write,
    scene: &Scene,
    count: usize,
    photons: u64,
    faces: impl Iterator<Item = [f64; 2]>,
) -> std::io::Result<()> {
    w.write_all(MAGIC)?;
    for x in [count as u64, fingerprint::light_transport(scene), photons] {
        w.write_all(&x.to_le_bytes())?;
    }
    for face in faces {
        for e in face {
            w.write_all(&e.to_le_bytes())?;
        }
    }
    Ok(())
}
