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
use std::sync::{Arc, Mutex};

use bevy::asset::AssetEvent;
use bevy::pbr::Material;
use bevy::platform::collections::HashSet;
use bevy::prelude::*;
use bevy::shader::{Shader, ShaderRef};

use crate::CacheStats;

/// The cached materials whose shader changed since the game started,
/// shared by the main world (which sees the change) and the render world
/// (which stops drawing them through their variants).
#[derive(Resource, Clone, Default)]
pub(crate) struct ReloadedMaterials(Arc<Mutex<HashSet<TypeId>>>);

impl ReloadedMaterials {
    /// Whether the material asset type `material` changed its shader.
    pub fn contains(&self, material: TypeId) -> bool {
        self.0
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .contains(&material)
    }

    /// Notes that `material`'s shader changed; whether it was news.
    fn insert(&self, material: TypeId) -> bool {
        self.0
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .insert(material)
    }
}

/// Watches `M`'s fragment shader for a change after it loaded.
pub(crate) fn watch<M: Material>(
    mut events: MessageReader<AssetEvent<Shader>>,
    server: Res<AssetServer>,
    reloaded: Res<ReloadedMaterials>,
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
        if ours && reloaded.insert(TypeId::of::<M>()) {
            stats.error(format!(
                "the shader of {} changed while the game runs (a hot reload), and its variant was rewritten from the one the game was built with: Bevy draws its meshes until the game is built again",
                bevy::utils::prelude::ShortName::of::<M>()
            ));
        }
    }
}
