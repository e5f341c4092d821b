//! From the parsed file to a validated `Scene`: materials, objects (shapes and mesh files,
//! transformed and merged into one `Geometry`), lights, receivers and `[simulation]`.
//! Every check names the file and the key at fault; `objects.rs` reads the `[[objects]]`.

// `!(x > 0.0)` is deliberate: it also rejects NaN (e.g. from an overflowing cross product).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::file::{self, CameraFile, GridName, QuantityName, ReceiverFile, ValuesName};
use super::grid::{self, Grid, GridError, GridRule};
use super::objects::{load_object, GeometryBuilder};
use super::{
    requirements, Camera, Estimator, Material, Quantity, Receiver, Scene, SceneLight, Simulation,
};
use crate::criteria::{self, StopCriteria};
use crate::error::{Error, Result};
use crate::input::{direction, required, vec3};
use crate::light::{self, LoadContext};
use glam::DVec3;
use std::path::{Path, PathBuf};

/// Loads and validates the scene file at `path`; relative mesh paths resolve against its
/// directory.
pub fn load(path: &Path) -> Result<Scene> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let base_dir = path.parent().unwrap_or(Path::new(""));
    let mut scene = load_str(&text, base_dir, &path.display().to_string())?;
    scene.path = path.to_path_buf();
    Ok(scene)
}

/// Loads a scene from TOML text. `origin` (the file name) prefixes every message and gives
/// the default scene name; relative mesh paths resolve against `base_dir`.
pub fn load_str(text: &str, base_dir: &Path, origin: &str) -> Result<Scene> {
    let raw = file::parse(text, origin)?;
    let at = |key: &str| format!("{origin}: {key}");
    let name = match raw.name {
        Some(n) if n.trim().is_empty() => return Err(Error::input(at("name"), "empty name")),
        Some(n) => n,
        None => Path::new(origin)
            .file_stem()
            .map_or_else(|| "scene".to_string(), |s| s.to_string_lossy().into_owned()),
    };
    let mut materials = raw
        .materials
        .into_iter()
        .map(|(key, m)| Material::from_entry(key, m, origin))
        .collect::<Result<Vec<_>>>()?;
    let mut builder = GeometryBuilder::default();
    for (i, value) in raw.objects.into_iter().enumerate() {
        let entry = file::object(value, origin, &format!("objects[{i}]"))?;
        load_object(&entry, i, origin, base_dir, &mut materials, &mut builder)?;
    }
    let geometry = builder.finish()?;
    let maintenance_factor = match &raw.maintenance_factor {
        Some(m) => m.factor(&at("maintenance_factor"))?,
        None => 1.0,
    };
    let portals = portals(&raw.portals, origin)?;
    let lights = lights(
        raw.lights,
        origin,
        base_dir,
        maintenance_factor,
        portals.clone(),
    )?;
    let modelling_with: Vec<Option<String>> = (raw.receivers.iter())
        .map(|r| r.modelling_with.clone())
        .collect();
    let daylight_factor: Vec<usize> = (raw.receivers.iter().enumerate())
        .filter_map(|(i, r)| (r.daylight_factor == Some(true)).then_some(i))
        .collect();
    let mut receivers = receivers(raw.receivers, origin)?;
    let modelling = requirements::modelling_pairs(&modelling_with, &receivers, origin)?;
    let daylight_factor = daylight_factor_of(daylight_factor, &receivers, &lights, origin)?;
    let observers = super::observers::observers(raw.observers, &lights, &mut receivers, origin)?;
    let requirements =
        requirements::requirements(raw.requirements, &receivers, &modelling, &observers, origin)?;

    let simulation = match raw.simulation {
        Some(value) => simulation(value, origin)?,
        None => Simulation {
            seed: 1,
            ..Simulation::default()
        },
    };
    let annual = match raw.annual {
        Some(value) => {
            let table: super::annual::AnnualFile = crate::input::entry(value, origin, "annual")?;
            Some(table.validate(&at("annual"), base_dir, &receivers)?)
        }
        None => None,
    };
    let camera = match raw.camera {
        Some(c) => Some(camera(c, &at("camera"))?),
        None => None,
    };
    Ok(Scene {
        name,
        path: PathBuf::from(origin),
        materials,
        geometry,
        lights,
        receivers,
        requirements,
        modelling,
        daylight_factor,
        simulation,
        camera,
        observers,
        portals,
        annual,
    })
}

/// The daylight-factor receivers (indices), validated: illuminance receivers, under a
/// CIE overcast sky (type 1 or 16, as EN 17037 allows) that is the scene's only light.
fn daylight_factor_of(
    receivers_with: Vec<usize>,
    receivers: &[Receiver],
    lights: &[SceneLight],
    origin: &str,
) -> Result<Option<super::DaylightFactor>> {
    use crate::light::sky::{Sky, SkyModel};
    let Some(&first) = receivers_with.first() else {
        return Ok(None);
    };
    let at = format!("{origin}: receivers[{first}].daylight_factor");
    if let Some(&k) =
        (receivers_with.iter()).find(|&&k| receivers[k].quantity != Quantity::Illuminance)
    {
        return Err(Error::input(
            format!("{origin}: receivers[{k}].daylight_factor"),
            "applies only to quantity = \"illuminance\"",
        ));
    }
    fn overcast(l: &SceneLight) -> Option<&Sky> {
        l.get::<Sky>().filter(|s| {
            matches!(
                s.model,
                SkyModel::TraditionalOvercast | SkyModel::Cie { kind: 1, .. }
            )
        })
    }
    match lights {
        [only] => match overcast(only) {
            Some(sky) => Ok(Some(super::DaylightFactor {
                receivers: receivers_with,
                outside_lx: sky.horizontal_lx,
                sky: crate::light::Light::describe(sky),
            })),
            None => Err(Error::input(
                at,
                format!(
                    "needs a CIE overcast sky (type = \"sky\", cie_type = 1 or 16); `{}` is not one",
                    only.label
                ),
            )),
        },
        _ => Err(Error::input(
            at,
            format!(
                "needs a CIE overcast sky (cie_type 1 or 16) as the scene's only light, \
                 and the scene has {} lights",
                lights.len()
            ),
        )),
    }
}

/// The `[[lights]]` entries, each read by its kind (`crate::light`).
fn lights(
    entries: Vec<toml::Value>,
    origin: &str,
    base_dir: &Path,
    maintenance_factor: f64,
    portals: Vec<light::distant::Portal>,
) -> Result<Vec<SceneLight>> {
    let mut lights = Vec::new();
    let mut cx = LoadContext::new(base_dir);
    cx.maintenance_factor = maintenance_factor;
    cx.portals = portals;
    for (i, value) in entries.into_iter().enumerate() {
        let label = format!("lights[{i}]");
        for (label, kind) in light::load_entry(value, &label, origin, &mut cx)? {
            lights.push(SceneLight { label, kind });
        }
    }
    Ok(lights)
}

/// The `[[portals]]`, validated: each a rectangle of non-zero area with orthogonal
/// edges, within reach.
fn portals(entries: &[file::PortalFile], origin: &str) -> Result<Vec<light::distant::Portal>> {
    let mut out = Vec::new();
    for (i, p) in entries.iter().enumerate() {
        let at = format!("{origin}: portals[{i}]");
        let (corner, u, v) = (vec3(p.corner), vec3(p.u), vec3(p.v));
        if !(u.cross(v).length() > 0.0) {
            return Err(Error::input(at, "zero-area portal: u × v = 0"));
        }
        if u.dot(v).abs() > 1e-9 * u.length() * v.length() {
            return Err(Error::input(
                at,
                "a portal is a rectangle: u and v must be orthogonal",
            ));
        }
        out.push(light::distant::Portal { corner, u, v });
    }
    Ok(out)
}

/// The `[[receivers]]` entries, validated; names are unique.
fn receivers(entries: Vec<ReceiverFile>, origin: &str) -> Result<Vec<Receiver>> {
    let mut receivers: Vec<Receiver> = Vec::new();
    let mut excludes = Vec::new();
    for (i, mut r) in entries.into_iter().enumerate() {
        let at = format!("{origin}: receivers[{i}]");
        excludes.push(r.exclude.take().unwrap_or_default());
        let receiver = receiver(r, &at)?;
        if receivers.iter().any(|o| o.name == receiver.name) {
            return Err(Error::input(
                format!("{at}.name"),
                format!("duplicate receiver name `{}`", receiver.name),
            ));
        }
        receivers.push(receiver);
    }
    for (i, names) in excludes.into_iter().enumerate() {
        let at = format!("{origin}: receivers[{i}].exclude");
        receivers[i].exclude = exclusions(&names, &receivers, i, &at)?;
    }
    Ok(receivers)
}

/// Receiver `i`'s `exclude` names as indices: other receivers, leaving some cell in.
fn exclusions(names: &[String], receivers: &[Receiver], i: usize, at: &str) -> Result<Vec<usize>> {
    let mut out = Vec::new();
    for name in names {
        let k = (receivers.iter().position(|r| &r.name == name))
            .ok_or_else(|| Error::input(at, format!("no receiver named `{name}`")))?;
        if k == i {
            return Err(Error::input(at, "a receiver cannot exclude itself"));
        }
        out.push(k);
    }
    let within = receivers[i].cells_within(&out, receivers);
    if !within.is_empty() && within.iter().all(|&x| x) {
        return Err(Error::input(
            at,
            "leaves no cell in: every cell's centre is excluded",
        ));
    }
    Ok(out)
}

fn receiver(r: ReceiverFile, at: &str) -> Result<Receiver> {
    if r.name.trim().is_empty() {
        return Err(Error::input(format!("{at}.name"), "empty receiver name"));
    }
    let (corner, u, v) = (vec3(r.corner), vec3(r.u), vec3(r.v));
    if !(u.cross(v).length() > 0.0) {
        return Err(Error::input(at, "zero-area receiver: u × v = 0"));
    }
    let (area, grid) = receiver_cells(&r, corner, u, v, at)?;
    let quantity = receiver_quantity(&r, at)?;
    let estimator = r.estimator.unwrap_or(Estimator::Auto);
    let points = r.values == Some(ValuesName::Point);
    if points && matches!(quantity, Quantity::Luminance { .. }) {
        return Err(Error::input(
            format!("{at}.values"),
            "\"point\" applies to illuminance and the cylinders, not to a luminance meter \
             (its cone meets the plane in an area)",
        ));
    }
    if points && estimator == Estimator::Track {
        return Err(Error::input(format!("{at}.values"), POINTS_NEED_NEXT_EVENT));
    }
    Ok(Receiver {
        name: r.name,
        corner: area.corner,
        u: area.u,
        v: area.v,
        cells: area.cells,
        quantity,
        estimator,
        grid,
        points,
        exclude: Vec::new(),
    })
}

/// Why `values = "point"` refuses the track estimator.
pub const POINTS_NEED_NEXT_EVENT: &str = "\"point\" needs the next-event estimator: \
     photons crossing a plane score areas, and a point has none";

/// What a receiver measures, with the keys of its quantity (a luminance meter's
/// `view_direction` and `half_angle_deg`, a semi-cylinder's `facing`); another
/// quantity's keys are errors.
fn receiver_quantity(r: &ReceiverFile, at: &str) -> Result<Quantity> {
    let name = r.quantity.unwrap_or(QuantityName::Illuminance);
    let keys = [
        (
            "view_direction",
            r.view_direction.is_some(),
            QuantityName::Luminance,
        ),
        (
            "half_angle_deg",
            r.half_angle_deg.is_some(),
            QuantityName::Luminance,
        ),
        ("facing", r.facing.is_some(), QuantityName::SemiCylindrical),
    ];
    for (key, given, owner) in keys {
        if given && name != owner {
            let owner = match owner {
                QuantityName::Luminance => "luminance",
                _ => "semi_cylindrical",
            };
            return Err(Error::input(
                format!("{at}.{key}"),
                format!("applies only to quantity = \"{owner}\""),
            ));
        }
    }
    Ok(match name {
        QuantityName::Illuminance => Quantity::Illuminance,
        QuantityName::Cylindrical => Quantity::Cylindrical,
        QuantityName::Luminance => {
            let what = "quantity = \"luminance\"";
            let view_direction = direction(
                required(r.view_direction, at, "view_direction", what)?,
                at,
                "view_direction",
            )?;
            let half_angle_deg = required(r.half_angle_deg, at, "half_angle_deg", what)?;
            if !(half_angle_deg > 0.0 && half_angle_deg <= 90.0) {
                return Err(Error::input(
                    format!("{at}.half_angle_deg"),
                    format!("must be in (0, 90], got {half_angle_deg}"),
                ));
            }
            Quantity::Luminance {
                view_direction,
                half_angle_deg,
            }
        }
        QuantityName::SemiCylindrical => {
            let what = "quantity = \"semi_cylindrical\"";
            let f = direction(required(r.facing, at, "facing", what)?, at, "facing")?;
            if !(f.z.abs() <= FACING_SLACK) {
                return Err(Error::input(
                    format!("{at}.facing"),
                    format!(
                        "must be horizontal (z = 0 within {FACING_SLACK:e} once normalised): \
                         the semi-cylinder stands upright; got z = {:.6}",
                        f.z
                    ),
                ));
            }
            Quantity::SemiCylindrical {
                facing: DVec3::new(f.x, f.y, 0.0).normalize(),
            }
        }
    })
}

/// How far from horizontal (z of the normalised vector) a semi-cylinder's `facing` may be.
const FACING_SLACK: f64 = 1e-6;

/// A receiver's area and cells: `cells = [nu, nv]` as given, or `grid = "en12464"`
/// (the rule of `scene::grid`, after its `grid_band_m` edge band, rounded as
/// `grid_rounding` says). Exactly one of `cells` and `grid`.
fn receiver_cells(
    r: &ReceiverFile,
    corner: DVec3,
    u: DVec3,
    v: DVec3,
    at: &str,
) -> Result<(Grid, Option<GridRule>)> {
    let key = |k: &str| format!("{at}.{k}");
    match (r.cells, r.grid) {
        (Some(_), Some(_)) => Err(Error::input(
            key("grid"),
            "give either cells = [nu, nv] or grid = \"en12464\", not both",
        )),
        (None, None) => Err(Error::input(
            key("cells"),
            "missing (give cells = [nu, nv] or grid = \"en12464\")",
        )),
        (Some(cells), None) => {
            for (k, given) in [
                ("grid_band_m", r.grid_band_m.is_some()),
                ("grid_rounding", r.grid_rounding.is_some()),
            ] {
                if given {
                    return Err(Error::input(key(k), "applies only to grid = \"en12464\""));
                }
            }
            if cells[0] == 0 || cells[1] == 0 {
                return Err(Error::input(
                    key("cells"),
                    format!("zero cells: {cells:?} (each must be ≥ 1)"),
                ));
            }
            Ok((
                Grid {
                    corner,
                    u,
                    v,
                    cells,
                },
                None,
            ))
        }
        (None, Some(GridName::En12464)) => {
            let band_m = r.grid_band_m.map_or(grid::DEFAULT_BAND_M, |b| b.0);
            if !(band_m >= 0.0) {
                return Err(Error::input(
                    key("grid_band_m"),
                    format!("must be ≥ 0, got {band_m}"),
                ));
            }
            let rule = GridRule {
                band_m,
                rounding: r.grid_rounding.unwrap_or_default(),
            };
            let g = rule.apply(corner, u, v).map_err(|e| {
                let k = match e {
                    GridError::BandTooWide { .. } => "grid_band_m",
                    GridError::TooManyPoints { .. } => "grid",
                };
                Error::input(key(k), e.to_string())
            })?;
            Ok((g, Some(rule)))
        }
    }
}

/// Largest image side: beyond it an image is surely a typo (and a gigabyte of pixels).
const MAX_RESOLUTION: u32 = 16_384;

fn camera(c: CameraFile, at: &str) -> Result<Camera> {
    let key = |k: &str| format!("{at}.{k}");
    let position = vec3(c.position);
    let look_at = vec3(c.look_at);
    let view = (look_at - position)
        .try_normalize()
        .ok_or_else(|| Error::input(key("look_at"), "is the same point as position"))?;
    let up = direction(c.up.unwrap_or([0.0, 0.0, 1.0]), at, "up")?;
    if view.cross(up).length() < 1e-6 {
        return Err(Error::input(key("up"), "is parallel to the view direction"));
    }
    if !(c.fov_deg > 0.0 && c.fov_deg < 180.0) {
        return Err(Error::input(
            key("fov_deg"),
            format!("must be between 0 and 180 degrees, got {}", c.fov_deg),
        ));
    }
    for (i, side) in c.resolution.iter().enumerate() {
        if *side == 0 || *side > MAX_RESOLUTION {
            return Err(Error::input(
                key("resolution"),
                format!(
                    "{} must be 1 to {MAX_RESOLUTION} pixels, got {side}",
                    ["width", "height"][i]
                ),
            ));
        }
    }
    let at_least_one = |x: Option<u32>, k: &str, default: u32, max: u32| match x {
        None => Ok(default),
        Some(n) if n >= 1 && n <= max => Ok(n),
        Some(n) => Err(Error::input(key(k), format!("must be 1 to {max}, got {n}"))),
    };
    Ok(Camera {
        position,
        look_at,
        up,
        fov_deg: c.fov_deg,
        resolution: c.resolution,
        samples: at_least_one(c.samples, "samples", 1, 65_536)?,
        interpolate: c.interpolate.unwrap_or(true),
        area_light_samples: at_least_one(c.area_light_samples, "area_light_samples", 8, 64)?,
        max_depth: match c.max_depth {
            None => 8,
            Some(n) if n <= 64 => n,
            Some(n) => {
                return Err(Error::input(
                    key("max_depth"),
                    format!("must be 0 to 64, got {n}"),
                ))
            }
        },
    })
}

/// The `[simulation]` table: the seed, and the stop criteria (one type with the command
/// line's, checked by its one validation).
fn simulation(value: toml::Value, origin: &str) -> Result<Simulation> {
    let at = format!("{origin}: simulation");
    let mut table: toml::Table = file::entry(value, origin, "simulation")?;
    let seed = table
        .remove("seed")
        .map(|v| file::entry::<u64>(v, origin, "simulation.seed"))
        .transpose()?;
    let confidence = table
        .remove("confidence")
        .map(|v| file::entry::<f64>(v, origin, "simulation.confidence"))
        .transpose()?;
    let qmc = table
        .remove("qmc")
        .map(|v| file::entry::<bool>(v, origin, "simulation.qmc"))
        .transpose()?;
    if let Some(c) = confidence {
        if !(c > 0.0 && c < 1.0) {
            return Err(Error::input(
                format!("{at}.confidence"),
                format!("must be between 0 and 1 (e.g. 0.95), got {c}"),
            ));
        }
    }
    // `seed`, `confidence`, `qmc` and the stop criteria's keys, named together when one
    // is unknown.
    let own: Vec<&str> = ["seed", "confidence", "qmc"]
        .into_iter()
        .chain(crate::input::fields_of::<StopCriteria>().iter().copied())
        .collect();
    crate::input::check_keys(&table, &own, &[], &at, "[simulation]")?;
    let stop: StopCriteria = file::entry(toml::Value::Table(table), origin, "simulation")?;
    stop.validate(criteria::scene_key(&at))?;
    Ok(Simulation {
        stop,
        seed: seed.unwrap_or(1),
        confidence: confidence.unwrap_or(super::DEFAULT_CONFIDENCE),
        qmc: qmc.unwrap_or(false),
    })
}
