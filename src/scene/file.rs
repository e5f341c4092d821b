//! The scene file as written: serde structs mirroring the TOML of the contract, and the
//! TOML front end (syntax errors, non-finite numbers, per-entry deserialisation with a key
//! path). Nothing here checks physics; `load` validates and converts.

use crate::error::{Error, Result};
use serde::Deserialize;

/// The top level. Entries stay raw `toml::Value`s so each one is deserialised with its own
/// key path (`objects[2]`) for messages: serde does not report array indices.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub name: Option<String>,
    #[serde(default)]
    pub materials: toml::Table,
    #[serde(default)]
    pub objects: Vec<toml::Value>,
    #[serde(default)]
    pub lights: Vec<toml::Value>,
    #[serde(default)]
    pub receivers: Vec<toml::Value>,
    pub simulation: Option<toml::Value>,
    pub camera: Option<toml::Value>,
}

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

/// `scale = 2` or `scale = [1, 2, 1]`.
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(untagged)]
pub enum ScaleFile {
    Uniform(f64),
    PerAxis([f64; 3]),
}

/// One `[[objects]]` entry. All shape parameters are optional here; `load` checks that the
/// ones the shape needs are present and that no other shape's parameters are set.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct ObjectFile {
    pub shape: Option<String>,
    pub file: Option<String>,
    pub material: Option<String>,
    pub min: Option<[f64; 3]>,
    pub max: Option<[f64; 3]>,
    pub corner: Option<[f64; 3]>,
    pub u: Option<[f64; 3]>,
    pub v: Option<[f64; 3]>,
    pub center: Option<[f64; 3]>,
    pub radius: Option<f64>,
    pub subdivisions: Option<u32>,
    pub scale: Option<ScaleFile>,
    pub rotate_deg: Option<[f64; 3]>,
    pub translate: Option<[f64; 3]>,
    /// Per-triangle tallies (the scene map) for this object; default true, false when
    /// the object has `instances` or `grid`.
    pub map: Option<bool>,
    /// Copies of the object, each placed after the object's own transform.
    pub instances: Option<Vec<InstanceFile>>,
    /// A regular grid of copies in the world x–y plane.
    pub grid: Option<GridFile>,
}

/// One entry of `instances = [...]`: scale → rotate → translate, after the object's own.
/// A negative scale mirrors.
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct InstanceFile {
    pub scale: Option<ScaleFile>,
    pub rotate_deg: Option<[f64; 3]>,
    pub translate: Option<[f64; 3]>,
}

/// `grid = {count = [nx, ny], spacing = [dx, dy]}`: copies at (i·dx, j·dy, 0).
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct GridFile {
    pub count: [u64; 2],
    pub spacing: [f64; 2],
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct ReceiverFile {
    pub name: String,
    pub corner: [f64; 3],
    pub u: [f64; 3],
    pub v: [f64; 3],
    pub cells: [u32; 2],
    pub quantity: Option<String>,
    pub view_direction: Option<[f64; 3]>,
    pub half_angle_deg: Option<f64>,
    pub estimator: Option<String>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SimulationFile {
    pub photons: Option<u64>,
    pub seed: Option<u64>,
    pub time_limit: Option<f64>,
    pub target_error: Option<f64>,
    pub target: Option<String>,
    #[serde(default)]
    pub absolute: bool,
    pub min_hits: Option<u64>,
}

/// The `[camera]` table: the eye of `luxtally render`.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    pub up: Option<[f64; 3]>,
    pub fov_deg: f64,
    pub resolution: [u32; 2],
    pub samples: Option<u32>,
    pub interpolate: Option<bool>,
    pub area_light_samples: Option<u32>,
    pub max_depth: Option<u32>,
}

pub use crate::input::{entry, one_line};

/// Parses the TOML text, rejects non-finite numbers, and deserialises the top level.
pub fn parse(text: &str, origin: &str) -> Result<SceneFile> {
    let table: toml::Table = toml::from_str(text).map_err(|e| syntax_error(text, origin, &e))?;
    let mut path = String::new();
    check_finite(&toml::Value::Table(table.clone()), &mut path, origin)?;
    entry(toml::Value::Table(table), origin, "")
}

/// `office.toml: line 3, column 7: invalid float` from toml's multi-line report.
fn syntax_error(text: &str, origin: &str, e: &toml::de::Error) -> Error {
    let message = one_line(e.message());
    match e.span() {
        Some(span) => {
            let before = text.get(..span.start).unwrap_or(text);
            let line = before.matches('\n').count() + 1;
            let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            Error::input(origin, format!("line {line}, column {column}: {message}"))
        }
        None => Error::input(origin, message),
    }
}

/// TOML allows `nan` and `inf`; no scene quantity may be either. Names the key path.
fn check_finite(value: &toml::Value, path: &mut String, origin: &str) -> Result<()> {
    match value {
        toml::Value::Float(x) if !x.is_finite() => Err(Error::input(
            format!("{origin}: {path}"),
            "value is not finite",
        )),
        toml::Value::Array(items) => {
            // A vector is reported as a whole (`lights[0].position`); arrays of tables
            // by element (`objects[2].radius`).
            for (i, item) in items.iter().enumerate() {
                let len = path.len();
                if item.is_table() {
                    path.push_str(&format!("[{i}]"));
                }
                check_finite(item, path, origin)?;
                path.truncate(len);
            }
            Ok(())
        }
        toml::Value::Table(table) => {
            for (key, item) in table {
                let len = path.len();
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(key);
                check_finite(item, path, origin)?;
                path.truncate(len);
            }
            Ok(())
        }
        _ => Ok(()),
    }
}
