//! A cached material's values edited while the game runs (a colour
//! changed on hover, a slider moved): Bevy draws the new values at once,
//! while the cache would show the old ones where it reuses, for up to
//! Δn frames. The frame an asset of a cached material's type is modified,
//! each view's caches of that material start afresh, as at a cut, and
//! reuse resumes from the new values.
//!
//! By type, not by asset: an edit of one `StandardMaterial` resets every
//! cache of `StandardMaterial`. A game that borrows a material mutably
//! every frame (`Assets::get_mut` marks it modified whether or not it
//! changes it) resets its caches every frame, so caches nothing.

use std::any::TypeId;

use bevy::asset::AssetEvent;
use bevy::pbr::Material;
use bevy::platform::collections::HashSet;
use bevy::prelude::*;
use bevy::render::extract_resource::ExtractResource;
use bevy::render::RenderApp;

/// The cached material types with an asset modified this frame, extracted
/// with the frame (in which Bevy's render world prepares the new values).
#[derive(Resource, Clone, Default, ExtractResource)]
#[extract_app(RenderApp)]
pub(crate) struct EditedMaterials(HashSet<TypeId>);

impl EditedMaterials {
    /// Whether an asset of the material type `material` was modified this
    /// frame.
    pub fn contains(&self, material: TypeId) -> bool {
        self.0.contains(&material)
    }
}

/// Notes a modified asset of `M` (after Bevy's asset events of the frame
/// are sent).
pub(crate) fn watch<M: Material>(
    mut events: MessageReader<AssetEvent<M>>,
    mut edited: ResMut<EditedMaterials>,
) {
    let modified = events
        .read()
        .any(|event| matches!(event, AssetEvent::Modified { .. }));
    if modified {
        edited.0.insert(TypeId::of::<M>());
    }
}

/// An edit is one frame's: cleared as the next begins.
pub(crate) fn clear(mut edited: ResMut<EditedMaterials>) {
    if !edited.0.is_empty() {
        edited.0.clear();
    }
}
