//! Instanced objects: one mesh drawn `count` times in one draw call, each
//! instance placed by a layout (a grid or a ring in the object's xz plane)
//! and, with `object-motion`, spinning about its own centre and orbiting
//! the object's vertical axis at its own rate.
//!
//! Values given per instance — here the motion, in storage buffers the
//! members ([`super::storage`]) — share one form, [`per_instance`]: one
//! value for every instance, a list of exactly one value per instance,
//! `{ cycle = [...] }` to repeat a shorter list, or (for colours)
//! `{ palette = "rainbow" }`.

use std::f32::consts::TAU;

use glam::{Mat4, Vec3};
use serde::Deserialize;

/// The most instances one object may draw.
pub const MAX_INSTANCES: u32 = 65536;

/// How an object's instances are placed and move.
#[derive(Clone, Debug, PartialEq)]
pub struct Instances {
    /// How many instances the draw draws.
    pub count: u32,
    /// How they are placed.
    pub layout: Layout,
    /// Each instance's initial rotation, degrees about x, y, z.
    pub rotation_degrees: Vec<Vec3>,
    /// With `object-motion`: each instance's rotation about its centre,
    /// degrees per frame about x, y, z.
    pub spin_degrees_per_frame: Vec<Vec3>,
    /// With `object-motion`: each instance's orbit about the object's y
    /// axis, degrees per frame.
    pub orbit_degrees_per_frame: Vec<f32>,
}

/// Where the instances sit, in the object's xz plane, centred on its
/// origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Layout {
    /// Rows of ⌈√count⌉ instances, `spacing` apart.
    Grid { spacing: f32 },
    /// A circle of `radius`, instance 0 on +z, the others counter-clockwise
    /// seen from above.
    Ring { radius: f32 },
}

const DEFAULT_SPACING: f32 = 2.5;
const DEFAULT_RADIUS: f32 = 2.0;

impl Instances {
    /// `count` instances in a grid `spacing` apart, unmoving.
    pub fn grid(count: u32, spacing: f32) -> Instances {
        let n = count as usize;
        Instances {
            count,
            layout: Layout::Grid { spacing },
            rotation_degrees: vec![Vec3::ZERO; n],
            spin_degrees_per_frame: vec![Vec3::ZERO; n],
            orbit_degrees_per_frame: vec![0.0; n],
        }
    }

    /// Instance `index`'s position in the layout, before any orbit.
    pub fn position(&self, index: u32) -> Vec3 {
        match self.layout {
            Layout::Grid { spacing } => {
                let columns = (self.count as f32).sqrt().ceil().max(1.0) as u32;
                let rows = self.count.div_ceil(columns);
                let centre = |i: u32, n: u32| (i as f32 - (n - 1) as f32 / 2.0) * spacing;
                Vec3::new(
                    centre(index % columns, columns),
                    0.0,
                    centre(index / columns, rows),
                )
            }
            Layout::Ring { radius } => {
                let angle = TAU * index as f32 / self.count as f32;
                Vec3::new(radius * angle.sin(), 0.0, radius * angle.cos())
            }
        }
    }

    /// Instance `index`'s transform in the object's space after `frames`
    /// frames of motion (0 when the scene does not declare
    /// `object-motion`).
    pub fn transform(&self, index: u32, frames: f32) -> Mat4 {
        let i = index as usize;
        let degrees = self.rotation_degrees[i] + self.spin_degrees_per_frame[i] * frames;
        let spin = Mat4::from_euler(
            glam::EulerRot::XYZ,
            degrees.x.to_radians(),
            degrees.y.to_radians(),
            degrees.z.to_radians(),
        );
        let orbit = Mat4::from_rotation_y((self.orbit_degrees_per_frame[i] * frames).to_radians());
        orbit * Mat4::from_translation(self.position(index)) * spin
    }
}

/// `instances = N` or a table.
impl<'de> Deserialize<'de> for Instances {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Instances, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Instances;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an instance count or a table with `count`")
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Instances, E> {
                let count = check_count(v).map_err(E::custom)?;
                Ok(Instances::grid(count, DEFAULT_SPACING))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Instances, E> {
                self.visit_i64(i64::try_from(v).unwrap_or(i64::MAX))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<Instances, A::Error> {
                let raw =
                    RawInstances::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                raw.resolve().map_err(serde::de::Error::custom)
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawInstances {
    count: i64,
    #[serde(default)]
    layout: LayoutName,
    spacing: Option<f32>,
    radius: Option<f32>,
    rotation_degrees: Option<toml::Value>,
    spin_degrees_per_frame: Option<toml::Value>,
    orbit_degrees_per_frame: Option<toml::Value>,
}

#[derive(Clone, Copy, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
enum LayoutName {
    #[default]
    Grid,
    Ring,
}

fn check_count(count: i64) -> Result<u32, String> {
    match u32::try_from(count) {
        Ok(n @ 1..=MAX_INSTANCES) => Ok(n),
        _ => Err(format!(
            "an object draws 1 to {MAX_INSTANCES} instances, not {count}"
        )),
    }
}

impl RawInstances {
    fn resolve(self) -> Result<Instances, String> {
        let count = check_count(self.count)?;
        let layout = match (self.layout, self.spacing, self.radius) {
            (LayoutName::Grid, spacing, None) => Layout::Grid {
                spacing: spacing.unwrap_or(DEFAULT_SPACING),
            },
            (LayoutName::Ring, None, radius) => Layout::Ring {
                radius: radius.unwrap_or(DEFAULT_RADIUS),
            },
            (LayoutName::Grid, _, Some(_)) => {
                return Err("`radius` is for layout = \"ring\"; a grid takes `spacing`".into())
            }
            (LayoutName::Ring, Some(_), _) => {
                return Err("`spacing` is for layout = \"grid\"; a ring takes `radius`".into())
            }
        };
        let (Layout::Grid { spacing: size } | Layout::Ring { radius: size }) = layout;
        if !size.is_finite() {
            return Err(format!("the layout's size {size} is not finite"));
        }
        let vectors = |name: &str, value: Option<toml::Value>| -> Result<Vec<Vec3>, String> {
            let Some(value) = value else {
                return Ok(vec![Vec3::ZERO; count as usize]);
            };
            let values =
                per_instance(&value, 3, count, false).map_err(|e| format!("`{name}`: {e}"))?;
            Ok(values
                .iter()
                .map(|v| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))
                .collect())
        };
        let orbit = match self.orbit_degrees_per_frame {
            None => vec![0.0; count as usize],
            Some(value) => per_instance(&value, 1, count, false)
                .map_err(|e| format!("`orbit_degrees_per_frame`: {e}"))?
                .iter()
                .map(|v| v[0] as f32)
                .collect(),
        };
        Ok(Instances {
            count,
            layout,
            rotation_degrees: vectors("rotation_degrees", self.rotation_degrees)?,
            spin_degrees_per_frame: vectors("spin_degrees_per_frame", self.spin_degrees_per_frame)?,
            orbit_degrees_per_frame: orbit,
        })
    }
}

/// Resolves a value given per instance into `count` values of
/// `components` numbers each:
///
/// * one value (a number, or an array of `components` numbers, or matrix
///   columns) is every instance's;
/// * a list of values (an array whose items are each one value) must have
///   exactly one per instance;
/// * `{ cycle = [v0, v1, ...] }` repeats a list over the instances;
/// * `{ palette = "rainbow" }` (only where `colour`, for 3 or 4
///   components) spreads hues evenly over the instances, alpha 1.
pub fn per_instance(
    value: &toml::Value,
    components: usize,
    count: u32,
    colour: bool,
) -> Result<Vec<Vec<f64>>, String> {
    let count = count as usize;
    let one = |value: &toml::Value| -> Result<Vec<f64>, String> {
        let numbers = super::layout::numbers(value)?;
        if numbers.len() != components {
            return Err(format!(
                "expected {components} number(s) per value, found {}",
                numbers.len()
            ));
        }
        Ok(numbers)
    };
    // An item of a list is a value: a number when values are numbers, an
    // array otherwise, with `components` numbers.
    let is_item = |item: &toml::Value| {
        let shaped = if components == 1 {
            item.is_integer() || item.is_float() || item.is_bool()
        } else {
            item.is_array()
        };
        shaped && super::layout::numbers(item).is_ok_and(|n| n.len() == components)
    };
    match value {
        toml::Value::Table(table) => {
            let keys: Vec<&str> = table.keys().map(String::as_str).collect();
            match (keys.as_slice(), table.values().next()) {
                (["cycle"], Some(toml::Value::Array(items))) if !items.is_empty() => {
                    let values = items.iter().map(one).collect::<Result<Vec<_>, _>>()?;
                    Ok((0..count).map(|i| values[i % values.len()].clone()).collect())
                }
                (["cycle"], _) => Err("`cycle` takes a non-empty list of values".into()),
                (["palette"], Some(toml::Value::String(name))) => {
                    if !colour || !(components == 3 || components == 4) {
                        return Err("a palette gives colours: f32 vec3 or vec4 members".into());
                    }
                    match name.as_str() {
                        "rainbow" => Ok((0..count)
                            .map(|i| {
                                let mut rgb = hsv(i as f64 / count as f64, 0.7, 0.9).to_vec();
                                rgb.truncate(components);
                                rgb.resize(components, 1.0);
                                rgb
                            })
                            .collect()),
                        other => Err(format!(
                            "unknown palette `{other}` (palettes: \"rainbow\")"
                        )),
                    }
                }
                _ => Err(format!(
                    "expected a value, a list of values, {{ cycle = [...] }} or {{ palette = \"rainbow\" }}, found a table with {}",
                    if keys.is_empty() {
                        "no keys".to_string()
                    } else {
                        keys.iter()
                            .map(|k| format!("`{k}`"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    }
                )),
            }
        }
        toml::Value::Array(items) if !items.is_empty() && items.iter().all(is_item) => {
            if items.len() != count {
                return Err(format!(
                    "lists {} value{} for {count} instance{}: give one per instance, or repeat a shorter list with {{ cycle = [...] }}",
                    items.len(),
                    if items.len() == 1 { "" } else { "s" },
                    if count == 1 { "" } else { "s" },
                ));
            }
            items.iter().map(one).collect()
        }
        value => {
            let numbers = one(value)?;
            Ok(vec![numbers; count])
        }
    }
}

/// RGB of a hue in [0, 1) at saturation `s` and value `v`.
fn hsv(h: f64, s: f64, v: f64) -> [f64; 3] {
    let channel = |n: f64| {
        let k = (n + h * 6.0) % 6.0;
        v - v * s * (k.min(4.0 - k).clamp(0.0, 1.0))
    };
    [channel(5.0), channel(3.0), channel(1.0)]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn value(text: &str) -> toml::Value {
        let table: toml::Table = toml::from_str(&format!("v = {text}")).unwrap();
        table["v"].clone()
    }

    #[test]
    fn values_per_instance_take_every_form() {
        let four = |text: &str, count| per_instance(&value(text), 4, count, true);
        assert_eq!(
            four("[1, 0, 0, 1]", 3).unwrap(),
            vec![vec![1.0, 0.0, 0.0, 1.0]; 3]
        );
        let listed = four("[[1, 0, 0, 1], [0, 1, 0, 1]]", 2).unwrap();
        assert_eq!(listed[1], [0.0, 1.0, 0.0, 1.0]);
        let err = four("[[1, 0, 0, 1], [0, 1, 0, 1]]", 3).unwrap_err();
        assert!(err.contains("lists 2 values for 3 instances"), "{err}");
        assert!(err.contains("cycle"), "{err}");
        let cycled = four("{ cycle = [[1, 0, 0, 1], [0, 1, 0, 1]] }", 5).unwrap();
        assert_eq!(cycled[4], cycled[0]);
        assert_eq!(cycled[3], cycled[1]);
        let rainbow = four("{ palette = \"rainbow\" }", 6).unwrap();
        assert_eq!(rainbow.len(), 6);
        assert!(rainbow.iter().all(|c| c.len() == 4 && c[3] == 1.0));
        assert_ne!(rainbow[0], rainbow[3]);
        assert!(rainbow.iter().flatten().all(|c| (0.0..=1.0).contains(c)));
        assert!(four("[1, 0, 0]", 2).unwrap_err().contains("expected 4"));
        assert!(four("{ palette = \"fire\" }", 2).is_err());
        assert!(four("{ colours = [] }", 2)
            .unwrap_err()
            .contains("`colours`"));
        assert!(per_instance(&value("{ palette = \"rainbow\" }"), 3, 2, false).is_err());

        // Scalars: a number is one value, an array a list.
        let scalars = |text: &str, count| per_instance(&value(text), 1, count, false);
        assert_eq!(scalars("2.5", 2).unwrap(), [[2.5], [2.5]]);
        assert_eq!(scalars("[1, 2]", 2).unwrap(), [[1.0], [2.0]]);
        assert!(scalars("[1, 2]", 3).is_err());
        // Matrices: columns are one value; a list of them is a list.
        let identity = "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]";
        let matrices = |text: &str, count| per_instance(&value(text), 16, count, false);
        assert_eq!(matrices(identity, 2).unwrap().len(), 2);
        assert_eq!(
            matrices(&format!("[{identity}, {identity}]"), 2)
                .unwrap()
                .len(),
            2
        );
    }

    #[test]
    fn layouts_place_instances_apart() {
        let grid = Instances::grid(9, 2.0);
        let positions: Vec<Vec3> = (0..9).map(|i| grid.position(i)).collect();
        assert_eq!(positions[0], Vec3::new(-2.0, 0.0, -2.0));
        assert_eq!(positions[4], Vec3::ZERO);
        assert_eq!(positions[8], Vec3::new(2.0, 0.0, 2.0));
        let ring = Instances {
            layout: Layout::Ring { radius: 3.0 },
            ..Instances::grid(4, 1.0)
        };
        assert!((ring.position(0) - Vec3::new(0.0, 0.0, 3.0)).length() < 1e-6);
        assert!((ring.position(1) - Vec3::new(3.0, 0.0, 0.0)).length() < 1e-5);
        // An orbit turns the instance about the object's y axis.
        let orbiting = Instances {
            orbit_degrees_per_frame: vec![90.0; 4],
            ..ring
        };
        let moved = orbiting.transform(0, 1.0).transform_point3(Vec3::ZERO);
        assert!(
            (moved - Vec3::new(3.0, 0.0, 0.0)).length() < 1e-5,
            "{moved}"
        );
    }
}
