//! Which inputs a cached value goes stale with every frame: the uniform
//! and storage members named for the time, the camera or a light. The
//! candidates' ranking and notes and the varyings' per-frame facts both
//! read the shader's names this way.

use naga::{Expression, TypeInner};

/// The per-frame inputs a cached value goes stale with, and the words in
/// the names of the uniform and storage members it loads that say so:
/// `time` (time, elapsed), `camera` (camera, cam, eye, view: positions and
/// matrices), `light` (light, sun).
pub(super) const PER_FRAME_INPUTS: [(&str, &[&str]); 3] = [
    ("time", &["time", "elapsed"]),
    ("camera", &["camera", "cam", "eye", "view"]),
    ("light", &["light", "sun"]),
];

/// Words of a member's name that say it places or orients something
/// (a camera's position, a light's direction, a view matrix), so that a
/// member of a buffer named for a camera or a light moves with it.
const PLACES: [&str; 15] = [
    "position",
    "pos",
    "proj",
    "projection",
    "matrix",
    "from",
    "to",
    "inverse",
    "origin",
    "direction",
    "dir",
    "forward",
    "transform",
    "world",
    "clip",
];

/// The slots of [`PER_FRAME_INPUTS`] a buffer member (`buffer.member`, or
/// a whole `buffer`) goes stale with: a word of the member's name is one
/// of the slot's (`view_proj`, `sun_direction`, `elapsed_time`), or the
/// buffer's own name is (the last word of a decorated name: naga_oil's
/// `mesh_view_bindings_view`) and the member places something
/// (`view.world_position`, not `view.width` or `view.viewport`). Whole
/// words, a plural as its singular: `viewport` and `lifetime` say nothing.
pub(super) fn per_frame_slots(name: &str) -> Vec<usize> {
    let (buffer, member) = match name.split_once('.') {
        Some((buffer, member)) => (buffer, Some(member)),
        None => (name, None),
    };
    let member_words = member.map(crate::proc::name_words).unwrap_or_default();
    let buffer_word = crate::proc::name_words(buffer).pop();
    let places = member.is_none() || member_words.iter().any(|w| PLACES.contains(&w.as_str()));
    PER_FRAME_INPUTS
        .iter()
        .enumerate()
        .filter(|(_, (_, words))| {
            let says = |word: &String| words.contains(&word.as_str());
            member_words.iter().any(says) || (places && buffer_word.as_ref().is_some_and(says))
        })
        .map(|(slot, _)| slot)
        .collect()
}

/// The `buffer.member` (or `buffer`) of a uniform or storage buffer that
/// `expr` reads: a member access of one, or a load of a whole one.
pub(super) fn loaded_buffer_member(
    module: &naga::Module,
    exprs: &[&Expression],
    expr: &Expression,
) -> Option<String> {
    let global_name = |expr: &Expression| match *expr {
        Expression::GlobalVariable(g) => {
            let variable = &module.global_variables[g];
            matches!(
                variable.space,
                naga::AddressSpace::Uniform | naga::AddressSpace::Storage { .. }
            )
            .then(|| (variable.name.clone().unwrap_or_default(), variable.ty))
        }
        _ => None,
    };
    match *expr {
        Expression::AccessIndex { base, index } => {
            let (name, ty) = global_name(exprs[base.index()])?;
            let member = match module.types[ty].inner {
                TypeInner::Struct { ref members, .. } => members
                    .get(index as usize)
                    .and_then(|m| m.name.clone())
                    .unwrap_or_default(),
                _ => String::new(),
            };
            Some(format!("{name}.{member}"))
        }
        Expression::Load { pointer } => global_name(exprs[pointer.index()]).map(|(name, _)| name),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::{per_frame_slots, PER_FRAME_INPUTS};

    fn inputs(name: &str) -> Vec<&'static str> {
        per_frame_slots(name)
            .into_iter()
            .map(|slot| PER_FRAME_INPUTS[slot].0)
            .collect()
    }

    #[test]
    fn per_frame_inputs_by_whole_words_of_the_member_or_its_buffer() {
        assert_eq!(inputs("camera.view_proj"), ["camera"]);
        assert_eq!(inputs("globals.sunDirection"), ["light"]);
        assert_eq!(inputs("globals.elapsed_time"), ["time"]);
        // Bevy's view buffer, decorated by naga_oil: its matrices and
        // position move with the camera, its size does not.
        assert_eq!(inputs("mesh_view_bindings_view.world_position"), ["camera"]);
        assert_eq!(inputs("mesh_view_bindings_view.inverse_view"), ["camera"]);
        assert!(inputs("mesh_view_bindings_view.width").is_empty());
        assert!(inputs("params.viewport").is_empty());
        assert!(inputs("particle.lifetime").is_empty());
        assert_eq!(
            inputs("mesh_view_bindings_lights.directional_lights[0].direction_to_light"),
            ["light"]
        );
        assert_eq!(inputs("lights"), ["light"]);
    }
}
