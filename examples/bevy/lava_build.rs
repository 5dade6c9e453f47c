//! How the game's materials' variants are built: the build script runs
//! it, and the plugin's tests profile the lava shader it composes (the
//! same packages, defs and vertex stage), so that what `shadecache
//! profile` measures is of the shader the game draws.

use shadecache::build::Build;
use shadecache::front::compose::ShaderDef;
use shadecache::rewrite::{DepthConvention, Options, Variant};

/// The node the variant caches, from `shadecache analyze` on the material.
pub const NODE: &str = "nfe927310";

/// The material composed with Bevy's own WESL packages: `bevy_pbr::` and
/// `bevy_render::` are the `src/` folders of the crates this game builds
/// against (found in its dependency graph), and the vertex stage is Bevy's
/// own mesh vertex shader, as for any material without one of its own;
/// rewritten into the one-pass variant of [`NODE`].
pub fn lava_build() -> Build {
    bevy_material(Build::new(), "assets/lava.wesl")
        // The crust: six octaves of object-space noise, the same every
        // frame. The analysis ranks the lit colour first, which reads the
        // time (the glow): cached, the glow would stand still between
        // refreshes, so the build names the crust.
        .node(NODE)
        .variant(Variant::OnePass)
        .options(Options {
            // Bevy renders with reversed Z.
            depth: DepthConvention::Reversed,
            color_format: shadecache::plan::TextureFormat::Rgba8UnormSrgb,
            // Bevy binds four groups of its own (view, binding arrays,
            // mesh, material); the cache takes a fifth, which every
            // Vulkan, Metal and D3D12 device has.
            max_bind_groups: 8,
            ..Options::default()
        })
}

/// Every material of the game: the lava ([`lava_build`]) and the stone,
/// whose one-pass variant caches the node the analysis ranks first (no id
/// is named: its colour reads nothing that changes from frame to frame).
pub fn game_build() -> Build {
    bevy_material(lava_build(), "assets/stone.wesl").variant(Variant::OnePass)
}

/// Adds a Bevy material's fragment shader to `build`, composed as Bevy
/// composes it: with Bevy's WESL packages, Bevy's mesh vertex stage and
/// what Bevy's mesh pipeline defines for a mesh with positions, normals
/// and UVs on a view without MSAA or prepasses, on a device with storage
/// buffers.
fn bevy_material(build: Build, shader: &str) -> Build {
    let mut build = build
        .shader(shader)
        .crate_package("bevy_pbr")
        .crate_package("bevy_render")
        .crate_vertex_shader("bevy_pbr", "render/mesh.wesl");
    for (name, value) in [
        ("MATERIAL_BIND_GROUP", ShaderDef::UInt(3)),
        ("MAX_DIRECTIONAL_LIGHTS", ShaderDef::UInt(10)),
        ("MAX_CASCADES_PER_LIGHT", ShaderDef::UInt(4)),
        ("VERTEX_POSITIONS", ShaderDef::Bool(true)),
        ("VERTEX_NORMALS", ShaderDef::Bool(true)),
        ("VERTEX_UVS", ShaderDef::Bool(true)),
        ("VERTEX_UVS_A", ShaderDef::Bool(true)),
        ("VERTEX_OUTPUT_INSTANCE_INDEX", ShaderDef::Bool(true)),
    ] {
        build = build.def(name, value);
    }
    build
}
