//! The bounds a scene's values keep, checked when the scene is read.
//!
//! serde checks a scene's shape (keys, types); this checks what its values
//! can mean: every number finite (TOML spells `nan` and `inf`), a camera
//! that can look at something (a field of view strictly between 0° and
//! 180°, an eye away from its target and not straight above or below it),
//! sizes above zero, and counts small enough that a run ends in time and
//! memory (frames, warm-up, mesh subdivisions). Each error points at the
//! value in the file. `docs/scene-toml.md` states the same bounds.

use std::ops::Range;
use std::sync::Arc;

use glam::Vec3;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

use super::{Far, MeshSource, Scene};
use crate::diagnostic::{Diagnostic, Error, SourceFile};

/// The most frames a run measures, and the most warm-up frames before
/// them: at a few milliseconds a frame on a software rasteriser, ten
/// thousand is a minute per configuration.
pub const MAX_FRAMES: u32 = 10_000;

/// The latest frame of its motion a scene can start at: an hour at 60 Hz,
/// where a frame's f32 time still steps exactly enough (2⁻¹¹ s at 3600 s).
pub const MAX_START_FRAME: u32 = 216_000;

/// The most quads a procedural mesh has (rings × segments, or
/// subdivisions²): 2 million triangles, about 100 MB of vertices and
/// indices. A finer mesh only costs memory and time.
pub const MAX_QUADS: u64 = 1 << 20;

/// The largest frame side, in pixels.
pub const MAX_SIZE: u32 = 8192;

/// Checks `scene`, read from `file`, against the bounds above.
pub(super) fn check(scene: &Scene, file: &Arc<SourceFile>) -> Result<(), Error> {
    // serde has read the text, so it parses; its spans place the labels.
    let document = DeTable::parse(&file.text).ok();
    let spans = Spans(document.as_ref());
    let fail = |message: String, path: &[&str]| -> Result<(), Error> {
        let diagnostic = Diagnostic::error(message);
        Err(Error::in_file(
            file.clone(),
            match spans.span(path) {
                Some(span) => diagnostic.with_label(span, "here"),
                None => diagnostic,
            },
        ))
    };

    if let Some(document) = &document {
        if let Some((span, text)) = non_finite(document.get_ref()) {
            return Err(Error::in_file(
                file.clone(),
                Diagnostic::error(format!(
                    "`{text}` is not a finite number: a scene's numbers must be finite (and within f32)"
                ))
                .with_label(span, "here"),
            ));
        }
    }

    if scene.objects.is_empty() {
        return fail(
            "the scene has no objects: add at least one [[objects]] with a mesh".into(),
            &[],
        );
    }
    if spans.len(&["size"]).is_some_and(|n| n != 2) {
        return fail(
            "`size` is [width, height]: two numbers of pixels".into(),
            &["size"],
        );
    }
    if scene.size.iter().any(|&side| side == 0 || side > MAX_SIZE) {
        return fail(
            format!(
                "size {:?} is not between 1 and {MAX_SIZE} pixels a side",
                scene.size
            ),
            &["size"],
        );
    }
    if scene.frames == 0 || scene.frames > MAX_FRAMES {
        return fail(
            format!(
                "frames = {} is not between 1 and {MAX_FRAMES}",
                scene.frames
            ),
            &["frames"],
        );
    }
    if scene.warmup > MAX_FRAMES {
        return fail(
            format!("warmup = {} is above {MAX_FRAMES}", scene.warmup),
            &["warmup"],
        );
    }
    if scene.start_frame > MAX_START_FRAME {
        return fail(
            format!(
                "start_frame = {} is above {MAX_START_FRAME}",
                scene.start_frame
            ),
            &["start_frame"],
        );
    }
    if scene.seconds_per_frame < 0.0 {
        return fail(
            "seconds_per_frame cannot be negative".into(),
            &["seconds_per_frame"],
        );
    }
    camera(scene, &fail)?;
    objects(scene, &fail)
}

/// Each object's bounds: a positive scale, a mesh within bounds, a skin
/// that checks.
fn objects(
    scene: &Scene,
    fail: &impl Fn(String, &[&str]) -> Result<(), Error>,
) -> Result<(), Error> {
    for (index, object) in scene.objects.iter().enumerate() {
        let at = index.to_string();
        if scene.objects[index].scale <= 0.0 {
            return fail(
                format!(
                    "object {index}'s scale is {}: it must be above 0",
                    object.scale
                ),
                &["objects", &at, "scale"],
            );
        }
        if let Some(message) = mesh(&object.mesh) {
            return fail(
                format!("object {index}'s mesh: {message}"),
                &["objects", &at, "mesh"],
            );
        }
        if let Some(Err(message)) = object.skin.as_ref().map(|skin| skin.check()) {
            return fail(
                format!("object {index}'s skin: {message}"),
                &["objects", &at, "skin"],
            );
        }
    }
    Ok(())
}

/// The camera's bounds.
fn camera(
    scene: &Scene,
    fail: &impl Fn(String, &[&str]) -> Result<(), Error>,
) -> Result<(), Error> {
    let camera = &scene.camera;
    let far_ok = match camera.far {
        Far::Distance(far) => far > camera.near,
        Far::Infinity => true,
    };
    if !(camera.near > 0.0 && far_ok) {
        return fail(
            "the camera needs 0 < near < far (far may be \"infinity\")".into(),
            &["camera", "near"],
        );
    }
    if !(camera.fov_degrees > 0.0 && camera.fov_degrees < 180.0) {
        return fail(
            format!(
                "fov_degrees = {}: a field of view is strictly between 0 and 180 degrees",
                camera.fov_degrees
            ),
            &["camera", "fov_degrees"],
        );
    }
    sight(
        camera.eye,
        camera.target,
        "the camera",
        &["camera", "eye"],
        fail,
    )?;
    let mut last = None;
    for (index, cut) in camera.cuts.iter().enumerate() {
        let at = index.to_string();
        let path = ["camera", "cuts", &at, "frame"];
        if last.is_some_and(|last| cut.frame <= last) {
            return fail(
                format!(
                    "[[camera.cuts]] are in frame order, each after the one before: frame {} follows frame {}",
                    cut.frame,
                    last.unwrap_or_default()
                ),
                &path,
            );
        }
        last = Some(cut.frame);
        let (eye, target) = (
            cut.eye.unwrap_or(camera.eye),
            cut.target.unwrap_or(camera.target),
        );
        let what = format!("the shot cut to at frame {}", cut.frame);
        sight(eye, target, &what, &["camera", "cuts", &at], fail)?;
    }
    if camera.zoom_per_frame <= 0.0 {
        return fail(
            "the camera's zoom_per_frame must be above 0 (1 keeps the field of view)".into(),
            &["camera", "zoom_per_frame"],
        );
    }
    Ok(())
}

/// Checks that an eye at `eye` looking at `target` sees something.
fn sight(
    eye: [f32; 3],
    target: [f32; 3],
    what: &str,
    path: &[&str],
    fail: &impl Fn(String, &[&str]) -> Result<(), Error>,
) -> Result<(), Error> {
    let (eye, target) = (Vec3::from(eye), Vec3::from(target));
    let sight = target - eye;
    if sight.length() <= 1e-6 * eye.length().max(1.0) {
        return fail(
            format!("{what}'s eye is at its target: it looks nowhere"),
            path,
        );
    }
    // The view's up is +y; orbits turn about the target's y axis and pans
    // keep the offset, so a line of sight along y stays along it.
    if sight.normalize().cross(Vec3::Y).length() < 1e-7 {
        return fail(
            format!("{what} looks straight up or down: its up direction (+y) is along the line of sight, so the view is undefined; move the eye off the target's vertical"),
            path,
        );
    }
    Ok(())
}

/// What is wrong with a procedural mesh's sizes, if anything.
fn mesh(source: &MeshSource) -> Option<String> {
    let positive = |name: &str, value: f32| {
        (value <= 0.0).then(|| format!("`{name}` is {value}: it must be above 0"))
    };
    let quads = |what: &str, a: u32, b: u32| {
        let quads = u64::from(a) * u64::from(b);
        (quads > MAX_QUADS).then(|| {
            format!(
                "{what} make {quads} quads, more than the {MAX_QUADS} a procedural mesh may have"
            )
        })
    };
    match *source {
        MeshSource::Sphere {
            radius,
            rings,
            segments,
        } => positive("radius", radius).or_else(|| quads("rings × segments", rings, segments)),
        MeshSource::Torus {
            radius,
            tube,
            rings,
            segments,
        } => positive("radius", radius)
            .or_else(|| positive("tube", tube))
            .or_else(|| quads("rings × segments", rings, segments)),
        MeshSource::Plane { size, subdivisions }
        | MeshSource::Terrain {
            size, subdivisions, ..
        } => positive("size", size).or_else(|| quads("subdivisions²", subdivisions, subdivisions)),
        MeshSource::Cube { size } => positive("size", size),
        MeshSource::Cylinder {
            radius,
            length,
            rings,
            segments,
        } => positive("radius", radius)
            .or_else(|| positive("length", length))
            .or_else(|| quads("rings × segments", rings, segments)),
        MeshSource::Fullscreen | MeshSource::Obj { .. } | MeshSource::Gltf { .. } => None,
    }
}

/// Where the value at `path` sits in the TOML `text` (see
/// [`Scene::span`]).
pub(super) fn span_in(text: &str, path: &[&str]) -> Option<Range<usize>> {
    let document = DeTable::parse(text).ok()?;
    Spans(Some(&document)).span(path)
}

/// The first float of the document that is not finite as an f32, with its
/// span and its text.
fn non_finite(table: &DeTable) -> Option<(Range<usize>, String)> {
    table.values().find_map(non_finite_value)
}

fn non_finite_value(value: &Spanned<DeValue>) -> Option<(Range<usize>, String)> {
    match value.get_ref() {
        DeValue::Float(float) => {
            let text = float.as_str();
            let parsed: f64 = text.replace('_', "").parse().unwrap_or(f64::NAN);
            (!(parsed.is_finite() && parsed.abs() <= f64::from(f32::MAX)))
                .then(|| (value.span(), text.to_string()))
        }
        DeValue::Array(array) => array.iter().find_map(non_finite_value),
        DeValue::Table(table) => non_finite(table),
        _ => None,
    }
}

/// Where a key's value sits in the scene's text.
struct Spans<'a, 'i>(Option<&'a Spanned<DeTable<'i>>>);

impl Spans<'_, '_> {
    /// The value at `path`: table keys, and indices (decimal) into
    /// arrays, `["objects", "1", "mesh"]`. The whole file for `[]`.
    fn value(&self, path: &[&str]) -> Option<Span<'_>> {
        let mut at = Span::Table(self.0?.get_ref(), self.0?.span());
        for step in path {
            at = match at {
                Span::Table(table, _) => {
                    let value = table.get(*step)?;
                    Span::Value(value)
                }
                Span::Value(value) => match value.get_ref() {
                    DeValue::Table(table) => Span::Value(table.get(*step)?),
                    DeValue::Array(array) => Span::Value(array.get(step.parse::<usize>().ok()?)?),
                    _ => return None,
                },
            };
        }
        Some(at)
    }

    fn span(&self, path: &[&str]) -> Option<Range<usize>> {
        self.value(path).map(|at| match at {
            Span::Table(_, span) => span.start..span.start,
            Span::Value(value) => value.span(),
        })
    }

    /// How many elements the array at `path` has.
    fn len(&self, path: &[&str]) -> Option<usize> {
        match self.value(path)? {
            Span::Value(value) => value.get_ref().as_array().map(|a| a.len()),
            Span::Table(..) => None,
        }
    }
}

enum Span<'a> {
    Table(&'a DeTable<'a>, Range<usize>),
    Value(&'a Spanned<DeValue<'a>>),
}
