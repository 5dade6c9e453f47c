use serde::{Deserialize, Serialize};

/// The cost of one scalar operation of each class, in abstract units where a
/// scalar add costs 1. Vector operations cost per component.
///
/// These are starting values chosen from the relative throughputs of current
/// GPUs (transcendentals on a quarter-rate unit, texture fetches bounded by
/// the texture units and memory). The profiler calibrates them against
/// measured pass times; nothing else in the crate hard-codes a cost.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Weights {
    /// add, subtract, multiply, negate, compare, select, logic, bit
    /// operations, conversions.
    pub arithmetic: f64,
    /// divide and modulo.
    pub division: f64,
    /// abs, min, max, clamp, floor, fract, mix, step, smoothstep and the
    /// like: a few arithmetic operations each.
    pub simple_math: f64,
    /// sin, cos, tan, exp, log, pow, sqrt, inverseSqrt and the other
    /// functions evaluated on the special-function unit.
    pub transcendental: f64,
    /// A filtered texture sample (any `textureSample*` or gather).
    pub texture_sample: f64,
    /// An unfiltered texel fetch (`textureLoad`).
    pub texture_load: f64,
    /// `textureDimensions`, `textureNumLevels` and other queries.
    pub texture_query: f64,
    /// `dpdx`, `dpdy`, `fwidth` and their coarse/fine forms.
    pub derivative: f64,
    /// A load from uniform or storage memory (per load, not per component).
    /// Loads of local and private variables are registers and cost nothing.
    pub load: f64,
    /// The overhead of a helper call beyond its body (usually inlined).
    pub call: f64,
    /// Trip count assumed for a loop whose bounds are not constant.
    pub default_loop_trips: f64,
}

impl Default for Weights {
    fn default() -> Self {
        Weights {
            arithmetic: 1.0,
            division: 4.0,
            simple_math: 2.0,
            transcendental: 8.0,
            texture_sample: 16.0,
            texture_load: 12.0,
            texture_query: 2.0,
            derivative: 2.0,
            load: 1.0,
            call: 0.0,
            default_loop_trips: 8.0,
        }
    }
}

/// The largest weight: over sixty thousand texture samples at the
/// default weights. A weight beyond it (or an infinite one) makes every
/// cost infinite and every ratio undefined.
pub const MAX_WEIGHT: f64 = 1.0e6;

impl Weights {
    /// Reads weights from JSON; missing fields keep their defaults.
    pub fn from_json(text: &str) -> Result<Self, serde_json::Error> {
        serde_json::from_str(text)
    }

    /// The first weight outside `0..=MAX_WEIGHT`, by its JSON name, with
    /// why: a negative cost would rank a node by what it saves below
    /// nothing. The names come from serde, so a new weight is checked
    /// too.
    pub fn out_of_bounds(&self) -> Option<(String, String)> {
        let serde_json::Value::Object(fields) = serde_json::to_value(self).ok()? else {
            return None;
        };
        fields.into_iter().find_map(|(name, value)| {
            // serde_json writes a non-finite number as null.
            let value = value.as_f64().unwrap_or(f64::INFINITY);
            (!(0.0..=MAX_WEIGHT).contains(&value)).then(|| {
                let why =
                    format!("weight `{name}` is {value}: weights go from 0 to {MAX_WEIGHT:e}");
                (name, why)
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_out_of_bounds_are_named() {
        assert_eq!(Weights::default().out_of_bounds(), None);
        for (json, name) in [
            (r#"{"division": -1}"#, "division"),
            (r#"{"default_loop_trips": 1e300}"#, "default_loop_trips"),
        ] {
            let weights = Weights::from_json(json).unwrap_or_default();
            let (found, why) = weights.out_of_bounds().unwrap_or_default();
            assert_eq!(found, name, "{why}");
        }
    }
}
