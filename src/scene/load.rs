//! From the parsed file to a validated `Scene`: materials, objects (shapes and mesh files,
//! transformed and merged into one `Geometry`), lights, receivers and `[simulation]`.
//! Every check names the file and the key at fault; `objects.rs` reads the `[[objects]]`.

// `!(x > 0.0)` is deliberate: it also rejects NaN (e.g. from an overflowing cross product).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::file::{self, CameraFile, QuantityName, ReceiverFile, RequirementFile};
use super::objects::{load_object, GeometryBuilder};
use super::{
    Camera, Check, Estimator, FigureName, Material, Quantity, Receiver, Requirement, Scene,
    SceneLight, Simulation,
};
use crate::criteria::{self, StopCriteria};
use crate::error::{Error, Result};
use crate::input::{direction, required, vec3};
use crate::light::{self, LoadContext};
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
    let lights = lights(raw.lights, origin, base_dir)?;
    let mut receivers = receivers(raw.receivers, origin)?;
    let requirements = requirements(raw.requirements, &receivers, origin)?;
    let observers = super::observers::observers(raw.observers, &lights, &mut receivers, origin)?;

    let simulation = match raw.simulation {
        Some(value) => simulation(value, origin)?,
        None => Simulation {
            seed: 1,
            ..Simulation::default()
        },
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
        simulation,
        camera,
        observers,
    })
}

/// The `[[lights]]` entries, each read by its kind (`crate::light`).
fn lights(entries: Vec<toml::Value>, origin: &str, base_dir: &Path) -> Result<Vec<SceneLight>> {
    let mut lights = Vec::new();
    let mut cx = LoadContext::new(base_dir);
    for (i, value) in entries.into_iter().enumerate() {
        let label = format!("lights[{i}]");
        for (label, kind) in light::load_entry(value, &label, origin, &mut cx)? {
            lights.push(SceneLight { label, kind });
        }
    }
    Ok(lights)
}

/// The `[[receivers]]` entries, validated; names are unique.
fn receivers(entries: Vec<ReceiverFile>, origin: &str) -> Result<Vec<Receiver>> {
    let mut receivers: Vec<Receiver> = Vec::new();
    for (i, r) in entries.into_iter().enumerate() {
        let at = format!("{origin}: receivers[{i}]");
        let receiver = receiver(r, &at)?;
        if receivers.iter().any(|o| o.name == receiver.name) {
            return Err(Error::input(
                format!("{at}.name"),
                format!("duplicate receiver name `{}`", receiver.name),
            ));
        }
        receivers.push(receiver);
    }
    Ok(receivers)
}

fn receiver(r: ReceiverFile, at: &str) -> Result<Receiver> {
    if r.name.trim().is_empty() {
        return Err(Error::input(format!("{at}.name"), "empty receiver name"));
    }
    let (corner, u, v) = (vec3(r.corner), vec3(r.u), vec3(r.v));
    if !(u.cross(v).length() > 0.0) {
        return Err(Error::input(at, "zero-area receiver: u × v = 0"));
    }
    if r.cells[0] == 0 || r.cells[1] == 0 {
        return Err(Error::input(
            format!("{at}.cells"),
            format!("zero cells: {:?} (each must be ≥ 1)", r.cells),
        ));
    }
    let quantity = match r.quantity.unwrap_or(QuantityName::Illuminance) {
        QuantityName::Illuminance => {
            if r.view_direction.is_some() || r.half_angle_deg.is_some() {
                let key = if r.view_direction.is_some() {
                    "view_direction"
                } else {
                    "half_angle_deg"
                };
                return Err(Error::input(
                    format!("{at}.{key}"),
                    "applies only to quantity = \"luminance\"",
                ));
            }
            Quantity::Illuminance
        }
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
    };
    let estimator = r.estimator.unwrap_or(Estimator::Auto);
    Ok(Receiver {
        name: r.name,
        corner,
        u,
        v,
        cells: r.cells,
        quantity,
        estimator,
    })
}

/// The `[[requirements]]` entries, validated against the scene's `receivers`.
fn requirements(
    entries: Vec<RequirementFile>,
    receivers: &[Receiver],
    origin: &str,
) -> Result<Vec<Requirement>> {
    let mut out: Vec<Requirement> = Vec::new();
    for (i, r) in entries.into_iter().enumerate() {
        let at = format!("{origin}: requirements[{i}]");
        let receiver = receivers
            .iter()
            .position(|x| x.name == r.receiver)
            .ok_or_else(|| {
                Error::input(
                    format!("{at}.receiver"),
                    format!("no receiver named `{}`", r.receiver),
                )
            })?;
        let mut checks = Vec::new();
        for (figure, value) in [
            (FigureName::Mean, r.em),
            (FigureName::Min, r.emin),
            (FigureName::U0, r.u0),
            (FigureName::G2, r.g2),
        ] {
            let Some(at_least) = value else { continue };
            let ratio = matches!(figure, FigureName::U0 | FigureName::G2);
            let ok = if ratio {
                at_least > 0.0 && at_least <= 1.0
            } else {
                at_least > 0.0 && at_least <= f64::MAX
            };
            if !ok {
                let range = if ratio { "in (0, 1]" } else { "positive" };
                return Err(Error::input(
                    format!("{at}.{}", figure.key()),
                    format!("must be {range}, got {at_least}"),
                ));
            }
            checks.push(Check { figure, at_least });
        }
        if checks.is_empty() {
            return Err(Error::input(
                at,
                "sets no figure to check (em, emin, u0 or g2)",
            ));
        }
        let name = r.name.unwrap_or_else(|| r.receiver.clone());
        if out.iter().any(|o| o.name == name) {
            return Err(Error::input(
                format!("{at}.name"),
                format!("duplicate requirement name `{name}`"),
            ));
        }
        out.push(Requirement {
            name,
            receiver,
            checks,
        });
    }
    Ok(out)
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
    if let Some(c) = confidence {
        if !(c > 0.0 && c < 1.0) {
            return Err(Error::input(
                format!("{at}.confidence"),
                format!("must be between 0 and 1 (e.g. 0.95), got {c}"),
            ));
        }
    }
    // `seed`, `confidence` and the stop criteria's keys, named together when one is
    // unknown.
    let own: Vec<&str> = ["seed", "confidence"]
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
    })
}
