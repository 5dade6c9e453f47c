//! How the game's materials' variants are built: the build script runs
//! it, and the plugin's tests profile the lava shader it composes (the
//! same packages, defs and vertex stage), so that what `shadecache
//! profile` measures is of the shader the game draws.

use std::path::Path;

use shadecache::build::{BevyMesh, Build};
use shadecache::front::compose::ShaderDef;
use shadecache::rewrite::{DepthConvention, Options, Variant};

/// The node the variant caches, from `shadecache analyze` on the material.
pub const NODE: &str = "nfe927310";

/// The material composed with Bevy's own WESL packages: `bevy_pbr::` and
/// `bevy_render::` are the `src/` folders of the crates this game builds
/// against (found in its dependency graph), and the vertex stage is Bevy's
/// own mesh vertex shader, as for any material without one of its own;
/// rewritten into the one-pass variant of [`NODE`]. `assets` is the
/// harness's folder of assets (relative to the crate in its build script).
pub fn lava_build(assets: &Path) -> Build {
    game_options(bevy_material(
        Build::new(),
        &assets.join("lava.wesl"),
        BevyMesh::default(),
    ))
    // The crust: six octaves of object-space noise, the same every
    // frame. The analysis ranks the lit colour first, which reads the
    // time (the glow): cached, the glow would stand still between
    // refreshes, so the build names the crust.
    .node(NODE)
    .variant(Variant::OnePass)
}

/// The options every variant of the game is rewritten with.
fn game_options(build: Build) -> Build {
    build.options(Options {
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

/// Every material of the game: the lava ([`lava_build`]), the lava again
/// for meshes with vertex colours (Bevy composes a material's shader per
/// mesh layout, and the plugin draws each mesh through the build composed
/// as Bevy's pipeline for it was), and the stone, whose one-pass variant
/// caches the node the analysis ranks first (no id is named: its colour
/// reads nothing that changes from frame to frame).
pub fn game_build(assets: &Path) -> Build {
    let coloured = BevyMesh {
        colors: true,
        ..BevyMesh::default()
    };
    let build = bevy_material(lava_build(assets), &assets.join("lava.wesl"), coloured)
        .name("lava_vertex_colors")
        .node(NODE)
        .variant(Variant::OnePass);
    let build = bevy_material(build, &assets.join("stone.wesl"), BevyMesh::default())
        .variant(Variant::OnePass);
    // Bevy's own `StandardMaterial`: bevy_pbr's `pbr.wesl`, bindless as
    // Bevy binds it wherever the device has binding arrays.
    let build = composed_as_bevy(
        build
            .crate_shader("bevy_pbr", "render/pbr.wesl")
            .name("standard_material"),
        BevyMesh::default(),
    )
    .def("BINDLESS", ShaderDef::Bool(true))
    .variant(Variant::TwoPass);
    // An `ExtendedMaterial<StandardMaterial, _>`: its extension's shader
    // (not bindless: the extension is not).
    bevy_material(build, &assets.join("rim.wesl"), BevyMesh::default()).variant(Variant::TwoPass)
}

/// Adds a Bevy material's fragment shader to `build`, composed as Bevy
/// composes it: with Bevy's WESL packages, Bevy's mesh vertex stage and
/// the defs Bevy's mesh pipeline sets for meshes with `mesh`'s attributes
/// in a forward opaque pass ([`Build::bevy_mesh`]; the plugin checks each
/// mesh's own against the plan's).
fn bevy_material(build: Build, shader: &Path, mesh: BevyMesh) -> Build {
    composed_as_bevy(build.shader(shader), mesh)
}

/// The last shader of `build` composed as Bevy composes a material's.
fn composed_as_bevy(build: Build, mesh: BevyMesh) -> Build {
    build
        .crate_package("bevy_pbr")
        .crate_package("bevy_render")
        .crate_vertex_shader("bevy_pbr", "render/mesh.wesl")
        .bevy_mesh(mesh)
}
