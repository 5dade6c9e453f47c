//! Textures a scene provides to the shader, by binding name.

use std::path::Path;

use serde::Deserialize;

/// Where a texture's texels come from.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(try_from = "RawSource")]
pub enum TextureSource {
    /// A PNG file, relative to the scene file.
    File { file: String, mipmaps: bool },
    /// A generated pattern.
    Generate {
        generate: Pattern,
        size: u32,
        mipmaps: bool,
    },
}

fn default_size() -> u32 {
    256
}

/// A `[textures.NAME]` table as written, before it is one source or the
/// other: read this way so that a table that is neither says so in the
/// scene's words, not serde's.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSource {
    file: Option<String>,
    generate: Option<Pattern>,
    size: Option<u32>,
    /// A full mip chain, each level the one above box-filtered, as a
    /// game's textures have (a colour texture only).
    #[serde(default)]
    mipmaps: bool,
}

/// The largest generated texture's side.
pub const MAX_GENERATED_SIZE: u32 = 4096;

impl TryFrom<RawSource> for TextureSource {
    type Error = String;

    fn try_from(raw: RawSource) -> Result<TextureSource, String> {
        let mipmaps = raw.mipmaps;
        match (raw.file, raw.generate, raw.size) {
            (Some(file), None, None) => Ok(TextureSource::File { file, mipmaps }),
            (Some(_), _, _) => Err(
                "a texture is either `file = \"PATH.png\"` or `generate = \"PATTERN\"` (with an optional `size`), not both".into(),
            ),
            (None, Some(generate), size) => {
                let size = size.unwrap_or_else(default_size);
                if size == 0 || size > MAX_GENERATED_SIZE {
                    return Err(format!(
                        "a generated texture's size is 1 to {MAX_GENERATED_SIZE} texels, not {size}"
                    ));
                }
                Ok(TextureSource::Generate {
                    generate,
                    size,
                    mipmaps,
                })
            }
            (None, None, _) => Err(
                "a texture needs `file = \"PATH.png\"` (relative to the scene) or `generate = \"checker\"` (checker, noise, flat-normal, sky, far, shadow-map or cells)".into(),
            ),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Pattern {
    /// 8×8 black and white checks.
    Checker,
    /// Smooth value noise in each channel.
    Noise,
    /// A flat normal map (0.5, 0.5, 1).
    FlatNormal,
    /// A sky gradient (for environment maps: each face alike).
    Sky,
    /// For depth textures (shadow maps): every texel at the far plane, 1.0.
    Far,
    /// For a 2D depth texture read with a comparison sampler: a shadow map
    /// rendered from the scene's light every frame ([`super::shadow`]).
    ShadowMap,
    /// For integer textures (`texture_2d<u32>`: counts, ids): 8×8 cells of
    /// small whole numbers, 0 to 7 in each channel, alpha 1.
    Cells,
}

pub use crate::runtime::Texels;

impl TextureSource {
    /// Whether this is the far-plane pattern a depth texture takes.
    pub fn is_far(&self) -> bool {
        matches!(
            self,
            TextureSource::Generate {
                generate: Pattern::Far,
                ..
            }
        )
    }

    /// Whether this is a shadow map rendered from the light.
    pub fn is_shadow_map(&self) -> bool {
        matches!(
            self,
            TextureSource::Generate {
                generate: Pattern::ShadowMap,
                ..
            }
        )
    }

    pub fn load(&self, dir: &Path) -> Result<Texels, String> {
        match *self {
            TextureSource::File { ref file, mipmaps } => {
                let path = dir.join(file);
                let image = image::open(&path)
                    .map_err(|err| format!("cannot read `{}`: {err}", path.display()))?;
                let rgba = image.to_rgba8();
                Ok(Texels {
                    width: rgba.width(),
                    height: rgba.height(),
                    rgba: rgba.into_raw(),
                    mipmaps,
                })
            }
            TextureSource::Generate {
                generate,
                size,
                mipmaps,
            } => Ok(Texels {
                mipmaps,
                ..generate_pattern(generate, size)
            }),
        }
    }
}

fn generate_pattern(pattern: Pattern, size: u32) -> Texels {
    let mut rgba = Vec::with_capacity((size * size * 4) as usize);
    // A small hash for value noise, so the pattern is the same everywhere.
    let hash = |x: u32, y: u32, c: u32| -> f32 {
        let mut h = x.wrapping_mul(374_761_393)
            ^ y.wrapping_mul(668_265_263)
            ^ c.wrapping_mul(2_246_822_519);
        h = (h ^ (h >> 13)).wrapping_mul(1_274_126_177);
        (h ^ (h >> 16)) as f32 / u32::MAX as f32
    };
    for y in 0..size {
        for x in 0..size {
            let (u, v) = (x as f32 / size as f32, y as f32 / size as f32);
            let texel: [f32; 4] = match pattern {
                Pattern::Checker => {
                    let on = ((x * 8 / size) + (y * 8 / size)).is_multiple_of(2);
                    let c = if on { 0.9 } else { 0.1 };
                    [c, c, c, 1.0]
                }
                Pattern::Noise => {
                    let cell = 16.0;
                    let (fx, fy) = (u * cell, v * cell);
                    let (ix, iy) = (fx.floor() as u32, fy.floor() as u32);
                    let (tx, ty) = (fx.fract(), fy.fract());
                    let mut out = [0.0; 4];
                    for (c, slot) in out.iter_mut().enumerate() {
                        let c = c as u32;
                        let a = hash(ix, iy, c) * (1.0 - tx) + hash(ix + 1, iy, c) * tx;
                        let b = hash(ix, iy + 1, c) * (1.0 - tx) + hash(ix + 1, iy + 1, c) * tx;
                        *slot = a * (1.0 - ty) + b * ty;
                    }
                    out[3] = 0.5 + 0.5 * out[3];
                    out
                }
                Pattern::FlatNormal => [0.5, 0.5, 1.0, 1.0],
                Pattern::Sky => [0.3 + 0.4 * v, 0.5 + 0.3 * v, 0.9, 1.0],
                Pattern::Far | Pattern::ShadowMap => [1.0, 1.0, 1.0, 1.0],
                Pattern::Cells => {
                    let (cx, cy) = (x * 8 / size, y * 8 / size);
                    let whole = |c: u32| (hash(cx, cy, c) * 8.0).floor().min(7.0) / 255.0;
                    [whole(0), whole(1), whole(2), 1.0 / 255.0]
                }
            };
            rgba.extend(texel.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8));
        }
    }
    Texels {
        width: size,
        height: size,
        rgba,
        mipmaps: false,
    }
}
