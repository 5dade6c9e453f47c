//! Shadow maps rendered from the scene's light.
//!
//! A shader that reads a depth texture with a comparison sampler (PCF
//! shadows) needs a shadow map that shows the scene from its light: with
//! every texel at the far plane every pixel is lit, and a shadow shader's
//! figures say nothing about its shadows. For `generate = "shadow-map"`
//! the simulation draws every object's triangles (each instance, as the
//! frame places it) through `light_clip_from_world` — the matrix it gives
//! members with the role of that name — and keeps the nearest depth per
//! texel, in the layout a GPU depth pass through that matrix would write
//! (texel x from clip x, texel y down from clip y, depth in [0, 1]).
//!
//! It is drawn on the CPU, once per frame, and uploaded to the depth
//! texture before the frame's passes, so the reference and every variant
//! read the same map and no pass of theirs pays for it. A few thousand
//! triangles at [`SIZE`]² take well under a millisecond; a rasteriser
//! crate would bring a colour pipeline this needs none of, so this is the
//! dozen lines of edge functions it takes.

use glam::{Mat4, Vec3, Vec4};

use super::{FrameState, Mesh};
use crate::runtime::DepthTexels;

/// The shadow map's side, in texels: the runtime's 2D depth textures'.
pub const SIZE: u32 = crate::runtime::DEPTH_MAP_SIZE;

/// The shadow map of `meshes` (object `i` drawn with `meshes[i]`) at
/// frame `state`, seen through its `light_clip_from_world`.
pub fn render(state: &FrameState, meshes: &[&Mesh]) -> DepthTexels {
    let size = SIZE as usize;
    let mut depth = vec![1.0f32; size * size];
    for (object, mesh) in meshes.iter().enumerate() {
        for world in state.instance_worlds(object) {
            let clip_from_local = state.light_clip_from_world * world;
            draw(&mut depth, size, clip_from_local, mesh);
        }
    }
    DepthTexels {
        size: SIZE,
        depth: depth
            .iter()
            .map(|d| (d.clamp(0.0, 1.0) * 65535.0).round() as u16)
            .collect(),
    }
}

/// Draws `mesh`'s triangles through `clip_from_local` into `depth`,
/// keeping the nearest. A triangle with a vertex behind the light, or off
/// the depth range, is left out (the light looks at the scene from
/// outside it).
fn draw(depth: &mut [f32], size: usize, clip_from_local: Mat4, mesh: &Mesh) {
    let to_texel = |p: Vec3| -> Option<Vec3> {
        let clip: Vec4 = clip_from_local * p.extend(1.0);
        if clip.w <= 1e-6 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        if !(0.0..=1.0).contains(&ndc.z) {
            return None;
        }
        Some(Vec3::new(
            (ndc.x * 0.5 + 0.5) * size as f32,
            (0.5 - ndc.y * 0.5) * size as f32,
            ndc.z,
        ))
    };
    let texels: Vec<Option<Vec3>> = mesh.positions.iter().map(|&p| to_texel(p)).collect();
    for triangle in mesh.indices.chunks_exact(3) {
        let corner = |i: usize| texels.get(triangle[i] as usize).copied().flatten();
        let (Some(a), Some(b), Some(c)) = (corner(0), corner(1), corner(2)) else {
            continue;
        };
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if area.abs() < 1e-12 {
            continue;
        }
        let (x0, x1) = (a.x.min(b.x).min(c.x), a.x.max(b.x).max(c.x));
        let (y0, y1) = (a.y.min(b.y).min(c.y), a.y.max(b.y).max(c.y));
        let clamp = |v: f32| (v.max(0.0) as usize).min(size);
        for y in clamp(y0.floor())..clamp(y1.ceil() + 1.0) {
            for x in clamp(x0.floor())..clamp(x1.ceil() + 1.0) {
                // Texel centres, both windings (shadows take back faces
                // too).
                let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
                let w0 = ((b.x - px) * (c.y - py) - (b.y - py) * (c.x - px)) / area;
                let w1 = ((c.x - px) * (a.y - py) - (c.y - py) * (a.x - px)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = w0 * a.z + w1 * b.z + w2 * c.z;
                let texel = &mut depth[y * size + x];
                if z < *texel {
                    *texel = z;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;
    use std::sync::Arc;

    /// A sphere above a plane, lit from above: the plane's texels under
    /// the sphere are nearer (the sphere's depth), the rest the plane's.
    #[test]
    fn a_sphere_over_a_plane_shadows_what_is_under_it() {
        let text = "[light]\nposition = [0.0, 6.0, 0.1]\n[[objects]]\nmesh = { kind = \"sphere\", radius = 0.5 }\nposition = [0.0, 1.0, 0.0]\n[[objects]]\nmesh = { kind = \"plane\", size = 4.0 }\n";
        let scene = super::super::Scene::parse(Arc::new(crate::diagnostic::SourceFile::new(
            "s.toml", text,
        )))
        .unwrap();
        let meshes: Vec<Mesh> = scene
            .objects
            .iter()
            .map(|o| o.mesh.build(Path::new(".")).unwrap())
            .collect();
        let state = scene.frame(0, 1.0);
        let map = render(&state, &meshes.iter().collect::<Vec<_>>());
        let at = |p: Vec3| {
            let clip = state.light_clip_from_world * p.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            let (x, y) = (
                ((ndc.x * 0.5 + 0.5) * SIZE as f32) as usize,
                ((0.5 - ndc.y * 0.5) * SIZE as f32) as usize,
            );
            (map.depth[y * SIZE as usize + x], (ndc.z * 65535.0) as u16)
        };
        // Under the sphere: the stored depth is the sphere's, nearer than
        // the plane point's own.
        let (stored, own) = at(Vec3::new(0.0, 0.0, 0.0));
        assert!(stored + 50 < own, "{stored} {own}");
        // Away from it: the plane itself.
        let (stored, own) = at(Vec3::new(1.5, 0.0, 1.5));
        assert!(stored.abs_diff(own) < 50, "{stored} {own}");
    }
}
