//! Whether Bevy composes a mesh's material as the variant was composed.
//!
//! Bevy composes a material's shader once per draw state: its mesh
//! pipeline sets defs for the mesh's vertex attributes (`VERTEX_COLORS`,
//! `VERTEX_TANGENTS`…), skinning, the view's prepasses, projection and
//! tonemapping, and the material's `specialize` adds its own. The variant
//! was composed once, by the build script, with the defs it was given;
//! its plan names the defs that change its code (`shader_defs`, each with
//! its value). A mesh is drawn through the variant only where Bevy's
//! pipeline for it was composed with the same values of those defs: else
//! the passes would draw another shader than Bevy's, and Bevy draws it.
//!
//! Bevy's defs for a pipeline are three lists: the specialised
//! descriptor's (vertex and fragment stages), the pipeline cache's
//! global ones (from the device's limits) and those Bevy's shader
//! libraries carry as assets (`MAX_DIRECTIONAL_LIGHTS`…). The first is
//! read per mesh; the second is made here as Bevy makes it; the third is
//! read from the main world's shader assets when they change.

use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::renderer::RenderDevice;
use bevy::render::Extract;
use bevy::shader::{Shader, ShaderDefVal};
use shadecache_host::plan::{ShaderDef, ShaderDefValue};

/// The defs Bevy's shader libraries carry (every shader asset's own
/// `shader_defs`), which Bevy's shader cache gives each composition that
/// imports them.
#[derive(Resource, Default)]
pub(crate) struct LibraryDefs(Vec<ShaderDefVal>);

/// Keeps [`LibraryDefs`] as the main world's shader assets are.
pub(crate) fn extract_library_defs(
    shaders: Extract<Res<Assets<Shader>>>,
    mut library: ResMut<LibraryDefs>,
) {
    if !shaders.is_changed() {
        return;
    }
    library.0 = shaders
        .iter()
        .flat_map(|(_, shader)| shader.shader_defs.iter().cloned())
        .collect();
}

/// The defs Bevy composed one pipeline with, by name.
pub(crate) struct BevyDefs(HashMap<String, ShaderDefValue>);

impl BevyDefs {
    /// From the specialised descriptor's `stages` defs, with the pipeline
    /// cache's global defs for `device` and the libraries' defs under them
    /// (the descriptor's win, as in Bevy's shader cache).
    pub fn new<'a>(
        stages: impl IntoIterator<Item = &'a ShaderDefVal>,
        device: &RenderDevice,
        library: &LibraryDefs,
    ) -> BevyDefs {
        let mut defs: HashMap<String, ShaderDefValue> = global_defs(device)
            .iter()
            .chain(&library.0)
            .map(entry)
            .collect();
        defs.extend(stages.into_iter().map(entry));
        BevyDefs(defs)
    }

    /// Bevy's value of `name` (unset where Bevy does not set it).
    fn value(&self, name: &str) -> ShaderDefValue {
        self.0.get(name).copied().unwrap_or(ShaderDefValue::Unset)
    }

    /// Each of the variant's `defs` whose value Bevy's differs from, in
    /// words (`VERTEX_COLORS: Bevy set, the variant unset`); empty where
    /// Bevy composes the material as the variant was.
    pub fn differences(&self, defs: &[ShaderDef]) -> Vec<String> {
        defs.iter()
            .filter_map(|def| {
                let bevys = self.value(&def.name);
                (bevys != def.value).then(|| {
                    format!(
                        "{}: Bevy {}, the variant {}",
                        def.name,
                        shown(bevys),
                        shown(def.value)
                    )
                })
            })
            .collect()
    }
}

/// A def of Bevy's as the plan writes it: `false` is unset, and a
/// number is its value.
fn entry(def: &ShaderDefVal) -> (String, ShaderDefValue) {
    let (name, value) = match def {
        ShaderDefVal::Bool(name, true) => (name, ShaderDefValue::Set),
        ShaderDefVal::Bool(name, false) => (name, ShaderDefValue::Unset),
        ShaderDefVal::Int(name, value) => (name, ShaderDefValue::Int(*value)),
        ShaderDefVal::UInt(name, value) => (name, ShaderDefValue::UInt(*value)),
    };
    (name.to_string(), value)
}

fn shown(value: ShaderDefValue) -> String {
    match value {
        ShaderDefValue::Unset => "unset".into(),
        ShaderDefValue::Set => "set".into(),
        ShaderDefValue::Int(v) => v.to_string(),
        ShaderDefValue::UInt(v) => format!("{v}u"),
    }
}

/// The defs Bevy 0.20's pipeline cache adds to every shader for the
/// device (`PipelineCache::new` in bevy_render: its list is private, so
/// it is made here the same way).
fn global_defs(device: &RenderDevice) -> Vec<ShaderDefVal> {
    let bindings = device.limits().max_storage_buffers_per_shader_stage;
    vec![
        ShaderDefVal::UInt("AVAILABLE_STORAGE_BUFFER_BINDINGS".into(), bindings),
        ShaderDefVal::Bool(
            "AVAILABLE_STORAGE_BUFFER_BINDINGS__GE_3".into(),
            bindings >= 3,
        ),
        ShaderDefVal::Bool(
            "AVAILABLE_STORAGE_BUFFER_BINDINGS__GE_6".into(),
            bindings >= 6,
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn def(name: &str, value: ShaderDefValue) -> ShaderDef {
        ShaderDef {
            name: name.into(),
            value,
        }
    }

    fn bevys(defs: &[ShaderDefVal]) -> BevyDefs {
        BevyDefs(defs.iter().map(entry).collect())
    }

    /// A def Bevy sets where the variant's composition did not (vertex
    /// colours), or the other way, or a number that differs, is a
    /// difference; defs the variant does not name, and `false` against
    /// unset, are not.
    #[test]
    fn differences_name_each_def_bevy_composes_otherwise() {
        let variant = [
            def("VERTEX_COLORS", ShaderDefValue::Unset),
            def("VERTEX_UVS_A", ShaderDefValue::Set),
            def("MATERIAL_BIND_GROUP", ShaderDefValue::UInt(3)),
            def("TONEMAP_IN_SHADER", ShaderDefValue::Unset),
        ];
        let same = bevys(&[
            "VERTEX_UVS_A".into(),
            ShaderDefVal::UInt("MATERIAL_BIND_GROUP".into(), 3),
            ShaderDefVal::Bool("TONEMAP_IN_SHADER".into(), false),
            "MESH_PIPELINE".into(),
        ]);
        assert!(same.differences(&variant).is_empty());
        let other = bevys(&[
            "VERTEX_COLORS".into(),
            ShaderDefVal::UInt("MATERIAL_BIND_GROUP".into(), 2),
        ]);
        assert_eq!(
            other.differences(&variant),
            [
                "VERTEX_COLORS: Bevy set, the variant unset",
                "VERTEX_UVS_A: Bevy unset, the variant set",
                "MATERIAL_BIND_GROUP: Bevy 2u, the variant 3u",
            ]
        );
    }
}
