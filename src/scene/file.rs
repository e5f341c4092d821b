//! The scene file as written: serde structs mirroring the TOML of the contract, and the
//! TOML front end (syntax errors, non-finite numbers, deserialisation whose messages name
//! the key path, `objects[2].radius`, through `serde_path_to_error`). Nothing here checks
//! physics; `load` validates and converts.

use super::grid::GridRounding;
use super::shapes;
use super::Estimator;
use crate::error::{Error, Result};
use crate::input::{self, check_keys, Coords, Length};
pub use crate::surface::MaterialFile;
use serde::Deserialize;
use std::collections::BTreeMap;

/// The top level. Objects and lights stay raw `toml::Value`s: what they are depends on
/// a key (`shape`/`file`, `type`), and each is read as that with its own key path.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub name: Option<String>,
    /// By name, in name order (as TOML tables iterate).
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialFile>,
    #[serde(default)]
    pub objects: Vec<toml::Value>,
    #[serde(default)]
    pub lights: Vec<toml::Value>,
    #[serde(default)]
    pub receivers: Vec<ReceiverFile>,
    /// The maintenance factor of every luminaire without its own.
    pub maintenance_factor: Option<crate::light::MaintenanceFile>,
    #[serde(default)]
    pub requirements: Vec<super::requirements::RequirementFile>,
    pub simulation: Option<toml::Value>,
    pub camera: Option<CameraFile>,
    #[serde(default)]
    pub observers: Vec<super::observers::ObserverFile>,
    /// Openings daylight enters by: skies aim their next events at them.
    #[serde(default)]
    pub portals: Vec<PortalFile>,
    /// A year of daylight (`scene::annual`).
    pub annual: Option<toml::Value>,
}

/// A `[[portals]]` entry: a rectangle (`u`, `v` orthogonal) from `corner`.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct PortalFile {
    pub corner: crate::input::Coords,
    pub u: crate::input::Coords,
    pub v: crate::input::Coords,
}

/// `scale = 2` or `scale = [1, 2, 1]`.
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(untagged, expecting = "a number or an array of 3 numbers")]
pub enum ScaleFile {
    Uniform(f64),
    PerAxis([f64; 3]),
}

/// One `[[objects]]` entry: where its triangles come from (`shape = ...` and that
/// shape's keys, or `file = ...`), and the keys every object takes.
#[derive(Debug)]
pub struct ObjectEntry {
    pub source: Source,
    pub object: ObjectFile,
}

/// Where an object's triangles come from.
#[derive(Debug)]
pub enum Source {
    Shape(ShapeFile),
    /// A mesh file (OBJ, glTF), relative to the scene file.
    File(String),
}

/// A built-in shape: `shape = "box" | "rect" | "sphere"` and its keys. Keys are optional
/// here so that `load` names a missing one (`objects[0].max: missing`).
#[derive(Debug)]
pub enum ShapeFile {
    Box(BoxFile),
    Rect(RectFile),
    Sphere(SphereFile),
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct BoxFile {
    pub min: Option<Coords>,
    pub max: Option<Coords>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct RectFile {
    pub corner: Option<Coords>,
    pub u: Option<Coords>,
    pub v: Option<Coords>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SphereFile {
    pub center: Option<Coords>,
    pub radius: Option<Length>,
    pub subdivisions: Option<u32>,
}

/// A built-in shape's keys: `shape = NAME` selects them.
trait ShapeKeys: serde::de::DeserializeOwned {
    const NAME: &'static str;
    fn into_shape(self) -> ShapeFile;
}

impl ShapeKeys for BoxFile {
    const NAME: &'static str = "box";
    fn into_shape(self) -> ShapeFile {
        ShapeFile::Box(self)
    }
}

impl ShapeKeys for RectFile {
    const NAME: &'static str = "rect";
    fn into_shape(self) -> ShapeFile {
        ShapeFile::Rect(self)
    }
}

impl ShapeKeys for SphereFile {
    const NAME: &'static str = "sphere";
    fn into_shape(self) -> ShapeFile {
        ShapeFile::Sphere(self)
    }
}

/// One row of [`SHAPES`]: a shape's name, the keys it takes and how its entry is read.
struct ShapeKind {
    name: &'static str,
    fields: input::Fields,
    read: fn(toml::Value, &str, &str) -> Result<ShapeFile>,
}

impl ShapeKind {
    const fn of<S: ShapeKeys>() -> ShapeKind {
        ShapeKind {
            name: S::NAME,
            fields: input::fields_of::<S>,
            read: |value, origin, path| Ok(input::entry::<S>(value, origin, path)?.into_shape()),
        }
    }
}

/// The built-in shapes: what `shape = ...` may say.
const SHAPES: [ShapeKind; 3] = [
    ShapeKind::of::<BoxFile>(),
    ShapeKind::of::<RectFile>(),
    ShapeKind::of::<SphereFile>(),
];

impl ShapeFile {
    pub fn name(&self) -> &'static str {
        match self {
            ShapeFile::Box(_) => BoxFile::NAME,
            ShapeFile::Rect(_) => RectFile::NAME,
            ShapeFile::Sphere(_) => SphereFile::NAME,
        }
    }

    /// Triangles it will make, known before it is built.
    pub fn triangle_count(&self) -> Option<u64> {
        match self {
            ShapeFile::Box(_) => Some(shapes::BOX_TRIANGLES),
            ShapeFile::Rect(_) => Some(shapes::RECT_TRIANGLES),
            ShapeFile::Sphere(s) => shapes::sphere_triangle_count(s.subdivisions),
        }
    }
}

/// The keys of an object whatever its triangles come from.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct ObjectFile {
    pub material: Option<String>,
    pub scale: Option<ScaleFile>,
    pub rotate_deg: Option<[f64; 3]>,
    pub translate: Option<Coords>,
    /// Per-triangle tallies (the scene map) for this object; default true, false when
    /// the object has `instances` or `grid`.
    pub map: Option<bool>,
    /// Copies of the object, each placed after the object's own transform.
    pub instances: Option<Vec<InstanceFile>>,
    /// A regular grid of copies in the world x–y plane.
    pub grid: Option<GridFile>,
}

impl ObjectFile {
    /// Whether its triangles are flattened into the scene map: `map`, by default unless
    /// it has copies (`instances` or `grid`), which are otherwise instanced.
    pub fn mapped(&self) -> bool {
        self.map
            .unwrap_or(self.instances.is_none() && self.grid.is_none())
    }

    /// Copies it makes: each `instances` entry (one without) at each `grid` point
    /// (saturating: the loader refuses past `objects::MAX_INSTANCES`).
    pub fn copy_count(&self) -> u64 {
        let listed = self.instances.as_ref().map_or(1, |l| l.len() as u64);
        let [nx, ny] = self.grid.map_or([1, 1], |g| g.count);
        nx.saturating_mul(ny).saturating_mul(listed)
    }
}

/// Reads `[[objects]]` entry `path` (`objects[i]`): `shape` or `file` says what it is;
/// keys of another shape are reported as not applying to this one (or to a mesh file).
pub fn object(value: toml::Value, origin: &str, path: &str) -> Result<ObjectEntry> {
    let at = format!("{origin}: {path}");
    let toml::Value::Table(mut table) = value else {
        return Err(Error::input(at, "must be a table"));
    };
    let mut string = |key: &str| match table.remove(key) {
        None => Ok(None),
        Some(toml::Value::String(s)) => Ok(Some(s)),
        Some(_) => Err(Error::input(format!("{at}.{key}"), "must be a string")),
    };
    let (shape, file) = (string("shape")?, string("file")?);
    let common = input::fields_of::<ObjectFile>();
    let (own, rest): (toml::Table, toml::Table) = table
        .into_iter()
        .partition(|(k, _)| common.contains(&k.as_str()));
    let object = input::entry(toml::Value::Table(own), origin, path)?;
    let others: Vec<&[&str]> = SHAPES.iter().map(|k| (k.fields)()).collect();
    let source = match (shape, file) {
        (Some(_), Some(_)) => {
            return Err(Error::input(at, "give either `shape` or `file`, not both"));
        }
        (None, None) => return Err(Error::input(at, "needs `shape` or `file`")),
        (None, Some(file)) => {
            check_keys(&rest, &[], &others, &at, "a mesh file")?;
            Source::File(file)
        }
        (Some(shape), None) => {
            let Some(kind) = SHAPES.iter().find(|k| k.name == shape) else {
                let names = input::or_list(SHAPES.iter().map(|k| format!("\"{}\"", k.name)));
                return Err(Error::input(
                    format!("{at}.shape"),
                    format!("unknown shape `{shape}` (expected {names})"),
                ));
            };
            let what = format!("shape \"{}\"", kind.name);
            check_keys(&rest, (kind.fields)(), &others, &at, &what)?;
            Source::Shape((kind.read)(toml::Value::Table(rest), origin, path)?)
        }
    };
    Ok(ObjectEntry { source, object })
}

/// One entry of `instances = [...]`: scale → rotate → translate, after the object's own.
/// A negative scale mirrors.
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct InstanceFile {
    pub scale: Option<ScaleFile>,
    pub rotate_deg: Option<[f64; 3]>,
    pub translate: Option<Coords>,
}

/// `grid = {count = [nx, ny], spacing = [dx, dy]}`: copies at (i·dx, j·dy, 0).
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct GridFile {
    pub count: [u64; 2],
    pub spacing: [Length; 2],
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct ReceiverFile {
    pub name: String,
    pub corner: Coords,
    pub u: Coords,
    pub v: Coords,
    /// Exactly one of `cells` and `grid`.
    pub cells: Option<[u32; 2]>,
    pub grid: Option<GridName>,
    pub grid_band_m: Option<Length>,
    pub grid_rounding: Option<GridRounding>,
    pub quantity: Option<QuantityName>,
    pub view_direction: Option<[f64; 3]>,
    pub half_angle_deg: Option<f64>,
    pub facing: Option<[f64; 3]>,
    pub estimator: Option<Estimator>,
    /// A cylindrical receiver's horizontal partner: its modelling ratio Ēz/Ēh.
    pub modelling_with: Option<String>,
    pub values: Option<ValuesName>,
    /// Receivers whose areas this one's figures leave out (a task area inside its
    /// surrounding).
    pub exclude: Option<Vec<String>>,
    /// Report the illuminance as a daylight factor too (an overcast sky the only light).
    pub daylight_factor: Option<bool>,
}

/// `values = "cell_average" | "point"`: what a receiver's cells score.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ValuesName {
    CellAverage,
    Point,
}

/// `grid = "en12464"`: the receiver's cells by the EN 12464-1 rule (`scene::grid`).
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub enum GridName {
    #[serde(rename = "en12464")]
    En12464,
}

/// `quantity = "illuminance" | "luminance" | "cylindrical" | "semi_cylindrical"`; a
/// luminance meter's keys and a semi-cylinder's `facing` come with theirs.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum QuantityName {
    Illuminance,
    Luminance,
    Cylindrical,
    SemiCylindrical,
}

/// The `[camera]` table: the eye of `luxtally render`.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    pub position: Coords,
    pub look_at: Coords,
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
