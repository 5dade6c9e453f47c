//! A cached material's values edited while the game runs (a colour
//! changed on hover, a slider moved): Bevy draws the new values at once,
//! while the cache would show the old ones where it reuses, for up to
//! Δn frames. The frame a material asset is modified, each view's cache
//! that draws a mesh binding it starts afresh, as at a cut, and reuse
//! resumes from the new values.
//!
//! By asset: an edit of a `StandardMaterial` no cached mesh binds (a
//! hovered prop Bevy draws) leaves the caches of `StandardMaterial` as
//! they are. A cache holds all its meshes' pixels in one, so an edit of
//! one of its meshes' materials resets the whole of it. A game that
//! borrows a material mutably every frame (`Assets::get_mut` marks it
//! modified whether or not it changes it) resets the caches drawing it
//! every frame, so caches nothing of them.
//!
//! A mesh given another asset (a material swapped on selection) is the
//! same change by another road: the view's cache keeps the asset each of
//! its meshes bound when last drawn and starts afresh when one binds
//! another (`ViewCache::materials_changed`).

use bevy::asset::{AssetEvent, UntypedAssetId};
use bevy::pbr::Material;
use bevy::platform::collections::HashSet;
use bevy::prelude::*;
use bevy::render::extract_resource::ExtractResource;
use bevy::render::RenderApp;

/// The cached materials' assets modified this frame, extracted with the
/// frame (in which Bevy's render world prepares the new values).
#[derive(Resource, Clone, Default, ExtractResource)]
#[extract_app(RenderApp)]
pub(crate) struct EditedMaterials(HashSet<UntypedAssetId>);

impl EditedMaterials {
    /// Whether the material asset `asset` was modified this frame.
    pub fn contains(&self, asset: UntypedAssetId) -> bool {
        self.0.contains(&asset)
    }
}

/// Notes a modified asset of `M` (after Bevy's asset events of the frame
/// are sent).
pub(crate) fn watch<M: Material>(
    mut events: MessageReader<AssetEvent<M>>,
    mut edited: ResMut<EditedMaterials>,
) {
    for event in events.read() {
        if let AssetEvent::Modified { id } = event {
            edited.0.insert(id.untyped());
        }
    }
}

/// An edit is one frame's: cleared as the next begins.
pub(crate) fn clear(mut edited: ResMut<EditedMaterials>) {
    if !edited.0.is_empty() {
        edited.0.clear();
    }
}
