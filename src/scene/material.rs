//! A material: its `[materials.KEY]` entry (the keys), its validation and its
//! description, in one place. Its physics is `surface`, whose `Bsdf::new` turns the
//! fields into lobes.

use crate::error::{Error, Result};
use serde::Deserialize;

/// A material: any mix of Lambertian reflection/transmission, ideal specular
/// reflection/refraction and glossy (GGX microfacet) reflection/refraction
/// (`surface`). The fractions sum to at most 1; the rest is absorbed.
///
/// Its `Debug` print is part of the scene fingerprint (checkpoints, indirect_map.bin).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Diffuse (Lambertian) reflectance ρ.
    pub reflectance: f64,
    /// Diffuse (Lambertian) transmittance τ.
    pub transmittance: f64,
    /// Ideal mirror reflectance.
    pub specular_reflectance: f64,
    /// Ideal refraction (dielectric of index `ior`, with Fresnel reflection at its face).
    pub specular_transmittance: f64,
    /// Index of refraction of the dielectric lobes (ideal and rough).
    pub ior: f64,
    /// Glossy reflector: a GGX lobe of this albedo weight (Fresnel factor 1).
    pub glossy_reflectance: f64,
    /// Rough dielectric (index `ior`, Fresnel reflection and refraction through GGX
    /// microfacets) of this albedo weight.
    pub glossy_transmittance: f64,
    /// Perceptual roughness of the glossy lobes, in (0, 1]; GGX α = roughness².
    pub roughness: f64,
}

/// A `[materials.KEY]` entry as written.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct MaterialFile {
    #[serde(default)]
    pub reflectance: f64,
    #[serde(default)]
    pub transmittance: f64,
    #[serde(default)]
    pub specular_reflectance: f64,
    #[serde(default)]
    pub specular_transmittance: f64,
    #[serde(default = "default_ior")]
    pub ior: f64,
    #[serde(default)]
    pub glossy_reflectance: f64,
    #[serde(default)]
    pub glossy_transmittance: f64,
    /// Required when a glossy part is set.
    pub roughness: Option<f64>,
}

fn default_ior() -> f64 {
    1.5
}

impl Material {
    /// A Lambertian reflector of reflectance `rho`.
    pub fn lambertian(name: &str, rho: f64) -> Self {
        Material {
            name: name.to_string(),
            reflectance: rho,
            transmittance: 0.0,
            specular_reflectance: 0.0,
            specular_transmittance: 0.0,
            ior: 1.5,
            glossy_reflectance: 0.0,
            glossy_transmittance: 0.0,
            roughness: 1.0,
        }
    }

    /// `[materials.KEY]` of file `origin`, validated.
    pub fn from_entry(key: String, m: MaterialFile, origin: &str) -> Result<Material> {
        let at = format!("{origin}: materials.{key}");
        if m.roughness.is_none() && m.glossy_reflectance + m.glossy_transmittance > 0.0 {
            return Err(Error::input(
                format!("{at}.roughness"),
                "required with glossy_reflectance or glossy_transmittance",
            ));
        }
        let material = Material {
            name: key,
            reflectance: m.reflectance,
            transmittance: m.transmittance,
            specular_reflectance: m.specular_reflectance,
            specular_transmittance: m.specular_transmittance,
            ior: m.ior,
            glossy_reflectance: m.glossy_reflectance,
            glossy_transmittance: m.glossy_transmittance,
            roughness: m.roughness.unwrap_or(1.0),
        };
        material.validate(&at)?;
        Ok(material)
    }

    /// The albedo weights by key, in the order the BSDF stacks its lobes.
    fn parts(&self) -> [(&'static str, f64); 6] {
        [
            ("reflectance", self.reflectance),
            ("transmittance", self.transmittance),
            ("specular_reflectance", self.specular_reflectance),
            ("specular_transmittance", self.specular_transmittance),
            ("glossy_reflectance", self.glossy_reflectance),
            ("glossy_transmittance", self.glossy_transmittance),
        ]
    }

    /// Total albedo: the fraction of incident flux that is not absorbed.
    pub fn albedo(&self) -> f64 {
        // Summed left to right (the bounce cap depends on the bits).
        self.parts().iter().fold(0.0, |sum, (_, x)| sum + x)
    }

    /// Every fraction finite and ≥ 0, `ior` ≥ 1, roughness in (0, 1], and no energy
    /// created; messages name `at` and the key.
    pub fn validate(&self, at: &str) -> Result<()> {
        for (key, x) in self.parts() {
            if !x.is_finite() || x < 0.0 {
                return Err(Error::input(
                    format!("{at}.{key}"),
                    format!("must be a number ≥ 0, got {x}"),
                ));
            }
        }
        if !self.ior.is_finite() || self.ior < 1.0 {
            return Err(Error::input(
                format!("{at}.ior"),
                format!("must be ≥ 1, got {}", self.ior),
            ));
        }
        if !(self.roughness > 0.0 && self.roughness <= 1.0) {
            return Err(Error::input(
                format!("{at}.roughness"),
                format!("must be in (0, 1], got {}", self.roughness),
            ));
        }
        // A little slack so that fractions written in decimal (0.7 + 0.2 + 0.1) sum to 1.
        let total = self.albedo();
        if total > 1.0 + 1e-9 {
            // Rounded so that 0.8 + 0.4 reads 1.2, not 1.2000000000000002.
            let total = (total * 1e9).round() / 1e9;
            return Err(Error::input(
                at,
                format!("energy-creating material: reflectance + transmittance + specular and glossy parts = {total} > 1"),
            ));
        }
        Ok(())
    }

    /// What `luxtally info` prints about it, one or more lines.
    pub fn describe(&self) -> String {
        let mut s = format!(
            "ρ {} τ {} mirror {} glass {} (ior {})",
            self.reflectance,
            self.transmittance,
            self.specular_reflectance,
            self.specular_transmittance,
            self.ior
        );
        if self.glossy_reflectance + self.glossy_transmittance > 0.0 {
            s += &format!(
                "\n    glossy reflector {} rough glass {} (roughness {}, α {})",
                self.glossy_reflectance,
                self.glossy_transmittance,
                self.roughness,
                self.roughness * self.roughness
            );
        }
        s
    }
}
