//! A material's shader that changes while the game runs (Bevy's hot
//! reload, or a shader asset the game edits).
//!
//! The variant was rewritten from the shader by the build script, and
//! compiled into the game; Bevy composes the changed shader at once. The
//! two would draw different materials, so from the change on the material
//! is Bevy's: its caches are dropped, its meshes handed back to Bevy's
//! opaque pass, and the change is said once. Building the game again
//! rewrites the variant from the new shader. Only the material's own
//! fragment shader (its `Material::fragment_shader` asset) is watched, not
//! the modules it imports.

use std::any::TypeId;

use bevy::asset::AssetEvent;
use bevy::pbr::Material;
use bevy::platform::collections::HashSet;
use bevy::prelude::*;
use bevy::render::extract_resource::ExtractResource;
use bevy::render::RenderApp;
use bevy::shader::{Shader, ShaderRef};

use crate::CacheStats;

/// The cached materials whose shader changed since the game started: the
/// main world sees the change, and the render world (which stops drawing
/// them through their variants) reads the set as it was extracted with
/// the frame, so that every render system of a frame agrees on it (read
/// from the main world while it runs, one system saw the change and an
/// earlier one of the same frame did not: a frame drew the meshes
/// through neither).
#[derive(Resource, Clone, Default, ExtractResource)]
#[extract_app(RenderApp)]
pub(crate) struct ReloadedMaterials(HashSet<TypeId>);

impl ReloadedMaterials {
    /// Whether the material asset type `material` changed its shader.
    pub fn contains(&self, material: TypeId) -> bool {
        self.0.contains(&material)
    }
}

/// Watches `M`'s fragment shader for a change after it loaded.
pub(crate) fn watch<M: Material>(
    mut events: MessageReader<AssetEvent<Shader>>,
    server: Res<AssetServer>,
    mut reloaded: ResMut<ReloadedMaterials>,
    stats: Res<CacheStats>,
) {
    let watched = M::fragment_shader();
    for event in events.read() {
        let AssetEvent::Modified { id } = *event else {
            continue;
        };
        let ours = match &watched {
            ShaderRef::Path(path) => server.get_path(id).is_some_and(|p| p == *path),
            ShaderRef::Handle(handle) => handle.id() == id,
            ShaderRef::Default => false,
        };
        if ours && !reloaded.contains(TypeId::of::<M>()) {
            reloaded.0.insert(TypeId::of::<M>());
            stats.error(format!(
                "the shader of {} changed while the game runs (a hot reload), and its variant was rewritten from the one the game was built with: Bevy draws its meshes until the game is built again",
                bevy::utils::prelude::ShortName::of::<M>()
            ));
        }
    }
}
