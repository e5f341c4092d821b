//! What every part of the scene file shares on its way in: deserialising one entry with
//! its key path for messages, the field names a serde struct accepts, and the checks of
//! user-written values (required keys, directions, photometric amounts). Used by `scene`
//! and by `light`, which each validate their own entries.

use crate::error::{Error, Result};
use glam::DVec3;
use serde::de::{self, DeserializeOwned, Deserializer, Visitor};

/// Collapses a possibly multi-line message into one line.
pub fn one_line(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Names for a message: "a, b or c" ("a" alone).
pub fn or_list<S: std::fmt::Display>(names: impl IntoIterator<Item = S>) -> String {
    let names: Vec<String> = names.into_iter().map(|n| n.to_string()).collect();
    match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => names.join(""),
    }
}

/// Deserialises one entry at key path `path` (`objects[2]`, empty for the top level);
/// messages name the full path of the key at fault (`objects[2].radius`).
pub fn entry<T: DeserializeOwned>(value: toml::Value, origin: &str, path: &str) -> Result<T> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let inner = match e.path().to_string() {
            p if p == "." => String::new(),
            p => p,
        };
        let full = match (path.is_empty(), inner.is_empty()) {
            (_, true) => path.to_string(),
            (true, false) => inner,
            (false, false) if inner.starts_with('[') => format!("{path}{inner}"),
            (false, false) => format!("{path}.{inner}"),
        };
        let message = one_line(e.inner().message());
        if full.is_empty() {
            Error::input(origin, message)
        } else {
            Error::input(format!("{origin}: {full}"), message)
        }
    })
}

/// A struct's key list, asked for when needed: `fields_of::<T>`.
pub type Fields = fn() -> &'static [&'static str];

/// The keys a derived `Deserialize` struct accepts, as its derive lists them (renames
/// applied): read by asking it to deserialise from a probe that records the list.
pub fn fields_of<T: DeserializeOwned>() -> &'static [&'static str] {
    let mut fields: &'static [&'static str] = &[];
    let _ = T::deserialize(FieldProbe(&mut fields));
    fields
}

struct FieldProbe<'a>(&'a mut &'static [&'static str]);

impl<'de> Deserializer<'de> for FieldProbe<'_> {
    type Error = de::value::Error;

    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> std::result::Result<V::Value, Self::Error> {
        Err(de::Error::custom("not a struct"))
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        fields: &'static [&'static str],
        _: V,
    ) -> std::result::Result<V::Value, Self::Error> {
        *self.0 = fields;
        Err(de::Error::custom("fields recorded"))
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes
        byte_buf option unit unit_struct newtype_struct seq tuple tuple_struct map enum
        identifier ignored_any
    }
}

/// Rejects the first key of `table` that `own` (the keys of `what`, e.g. `shape "box"`)
/// does not list: `at.key: does not apply to WHAT` when one of `others` takes it (a typo'd
/// type is loud), an unknown field otherwise.
pub fn check_keys(
    table: &toml::Table,
    own: &[&str],
    others: &[&[&str]],
    at: &str,
    what: &str,
) -> Result<()> {
    let Some(key) = table.keys().find(|k| !own.contains(&k.as_str())) else {
        return Ok(());
    };
    let message = if others.iter().any(|o| o.contains(&key.as_str())) {
        format!("does not apply to {what}")
    } else if own.is_empty() {
        format!("unknown field `{key}`")
    } else {
        format!(
            "unknown field `{key}` for {what} (expected one of `{}`)",
            own.join("`, `")
        )
    };
    Err(Error::input(format!("{at}.{key}"), message))
}

pub fn vec3(a: impl Into<[f64; 3]>) -> DVec3 {
    DVec3::from_array(a.into())
}

/// The largest coordinate or length, in metres, a scene may hold. Rays reach the ray
/// casters in f32, and Embree takes ray origins and directions only within ±1.844e18
/// (its `FLT_LARGE`; beyond, it aborts); the points made from the input (a box's far
/// corner, a directional light's disk beyond the scene, the scene re-centred) lie a few
/// scene sizes further at most.
pub const MAX_COORDINATE_M: f64 = 1e16;

/// Whether `p` is finite and within ±[`MAX_COORDINATE_M`] on every axis.
pub fn within_reach(p: DVec3) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_COORDINATE_M
}

/// What is wrong with a coordinate beyond reach.
pub fn beyond_reach(what: impl std::fmt::Display) -> String {
    format!(
        "{what} is beyond the ±{MAX_COORDINATE_M:e} m a scene may span (rays are traced in f32)"
    )
}

/// A point or a vector in metres, as the scene file writes it: three numbers, each
/// within ±[`MAX_COORDINATE_M`] (checked as it is read, so messages name the key).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coords(pub [f64; 3]);

impl From<Coords> for [f64; 3] {
    fn from(c: Coords) -> [f64; 3] {
        c.0
    }
}

impl<'de> serde::Deserialize<'de> for Coords {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Coords, D::Error> {
        Ok(Coords(<[Length; 3]>::deserialize(d)?.map(|l| l.0)))
    }
}

/// A length in metres, as the scene file writes it: within ±[`MAX_COORDINATE_M`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Length(pub f64);

impl<'de> serde::Deserialize<'de> for Length {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Length, D::Error> {
        let x = f64::deserialize(d)?;
        if x.abs() <= MAX_COORDINATE_M {
            Ok(Length(x))
        } else {
            Err(de::Error::custom(beyond_reach(format!("{x:e} m"))))
        }
    }
}

/// A key `what` (e.g. `type "spot" lights`) needs: `at.key: missing` otherwise.
pub fn required<T>(x: Option<T>, at: &str, key: &str, what: &str) -> Result<T> {
    x.ok_or_else(|| {
        Error::input(
            format!("{at}.{key}"),
            format!("missing (required for {what})"),
        )
    })
}

/// A direction the user wrote: normalised, zero rejected. Any finite non-zero
/// direction works: one whose length over- or underflows is scaled first.
pub fn direction(d: [f64; 3], at: &str, key: &str) -> Result<DVec3> {
    let v = vec3(d);
    v.try_normalize()
        .or_else(|| (v / v.abs().max_element()).try_normalize())
        .ok_or_else(|| Error::input(format!("{at}.{key}"), "zero direction"))
}

/// A photometric amount: finite and ≥ 0 (zero is allowed: a switched-off source).
pub fn amount(x: f64, at: &str, key: &str) -> Result<f64> {
    if x.is_finite() && x >= 0.0 {
        Ok(x)
    } else {
        Err(Error::input(
            format!("{at}.{key}"),
            format!("must be ≥ 0, got {x}"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Probe {
        a: f64,
        #[serde(rename = "type")]
        kind: Option<String>,
    }

    #[test]
    fn fields_of_lists_a_derived_structs_keys_renamed() {
        assert_eq!(fields_of::<Probe>(), &["a", "type"]);
    }

    #[test]
    fn or_list_joins_with_commas_and_a_final_or() {
        assert_eq!(or_list(["a", "b", "c"]), "a, b or c");
        assert_eq!(or_list(["a", "b"]), "a or b");
        assert_eq!(or_list(["a"]), "a");
    }
}
