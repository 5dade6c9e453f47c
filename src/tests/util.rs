//! What the library's tests share beyond the workspace's test support:
//! CPU silhouettes of a scene's objects, shaders analysed from text, the
//! marble scenes, a profile that must fail.

use std::path::Path;

pub use shadecache_test_support::{
    corpus, marble_scene, root, sphere_over_floor, temp_file, tint_validate,
};

use crate::scene::Scene;

/// Whether a pixel of `mask` lies within one pixel (8-neighbourhood) of
/// `i`.
pub fn near(mask: &[bool], w: usize, i: usize) -> bool {
    let h = mask.len() / w;
    let (x, y) = ((i % w) as i64, (i / w) as i64);
    (-1..=1).any(|dy| {
        (-1..=1).any(|dx| {
            let (nx, ny) = (x + dx, y + dy);
            nx >= 0
                && ny >= 0
                && nx < w as i64
                && ny < h as i64
                && mask[(ny as usize) * w + nx as usize]
        })
    })
}

/// Which pixels object `object` (all its instances) covers in frame
/// `frame`, rasterised on the CPU at pixel centres with the scene's own
/// matrices (`w × h`, row-major, y down).
pub fn silhouette(scene: &Scene, object: usize, frame: u32, w: usize, h: usize) -> Vec<bool> {
    let state = scene.frame(frame, w as f32 / h as f32);
    // A skinned object's outline is its pose's.
    let rest = scene.objects[object]
        .mesh
        .build(Path::new("."))
        .unwrap()
        .skinned(scene.objects[object].skin.as_ref());
    let mesh = scene.posed(object, &rest, &state).unwrap_or(rest);
    let instances: Vec<Vec<glam::Vec2>> = state.instances[object]
        .iter()
        .map(|instance| {
            let clip = state.clip_from_world * state.objects[object] * *instance;
            mesh.positions
                .iter()
                .map(|p| {
                    let c = clip * p.extend(1.0);
                    glam::Vec2::new(c.x / c.w, c.y / c.w)
                })
                .collect()
        })
        .collect();
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let p = glam::Vec2::new(x / w as f32 * 2.0 - 1.0, 1.0 - y / h as f32 * 2.0);
            instances.iter().any(|points| {
                mesh.indices.chunks(3).any(|t| {
                    let [a, b, c] = [
                        points[t[0] as usize],
                        points[t[1] as usize],
                        points[t[2] as usize],
                    ];
                    let side = |u: glam::Vec2, v: glam::Vec2| (v - u).perp_dot(p - u);
                    let (s0, s1, s2) = (side(a, b), side(b, c), side(c, a));
                    (s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0)
                })
            })
        })
        .collect()
}

/// The pixels of `mask` whose whole 8-neighbourhood is in `mask`: one
/// pixel in from its edge, where rasterisation rounding cannot matter.
pub fn interior(mask: &[bool], w: usize) -> Vec<bool> {
    let outside: Vec<bool> = mask.iter().map(|m| !m).collect();
    (0..mask.len()).map(|i| !near(&outside, w, i)).collect()
}

/// Parses, validates and analyses a shader given as text.
pub fn analyzed(name: &str, source: &str) -> (crate::front::Shader, crate::analysis::Analysis) {
    let shader = crate::front::parse(crate::diagnostic::SourceFile::new(name, source))
        .unwrap_or_else(|err| panic!("{name}: {err:?}"));
    let analysis = crate::analysis::analyze(&shader, &Default::default()).unwrap();
    (shader, analysis)
}

/// The candidate whose source text is `text`.
pub fn candidate<'a>(
    analysis: &'a crate::analysis::Analysis,
    text: &str,
) -> &'a crate::analysis::Candidate {
    analysis
        .candidates
        .iter()
        .find(|c| c.node.text == text)
        .unwrap_or_else(|| panic!("no candidate `{text}`"))
}

/// Where object `object` of `scene` moved between frames 0 and 1 at
/// `w`×`h`: the pixels it newly covers (its leading band, two pixels in
/// from the band's edges) and those it uncovers (one pixel in), from its
/// silhouettes.
pub fn moved_bands(scene: &Scene, object: usize, w: usize, h: usize) -> (Vec<usize>, Vec<usize>) {
    let (before, now) = (
        silhouette(scene, object, 0, w, h),
        silhouette(scene, object, 1, w, h),
    );
    let leading: Vec<bool> = (0..w * h).map(|i| now[i] && !before[i]).collect();
    let leading = interior(&interior(&leading, w), w);
    let trailing: Vec<bool> = (0..w * h).map(|i| before[i] && !now[i]).collect();
    let trailing = interior(&trailing, w);
    (
        (0..w * h).filter(|&i| leading[i]).collect(),
        (0..w * h).filter(|&i| trailing[i]).collect(),
    )
}

/// Whether pixel `i` of a classification map (RGBA8) is a hit.
pub fn is_hit(classes: &[u8], i: usize) -> bool {
    classes[i * 4..i * 4 + 3] == crate::measure::metrics::HIT
}

/// Profiles the shader at `shader` (relative to the root) on
/// `scene_text` with the default options, which must fail; the error as
/// the command prints it.
pub fn profile_error(shader: &str, scene_text: &str) -> String {
    let (_dir, path) = temp_file("scene.toml", scene_text.as_bytes());
    let shader =
        crate::front::load(&root().join(shader)).unwrap_or_else(|e| panic!("{}", e.render()));
    let scene = match Scene::load(&path) {
        Ok(scene) => scene,
        Err(err) => return err.render(),
    };
    let options = crate::profile::Options::default();
    match crate::profile::profile(&shader, &scene, &path, &options, &mut crate::profile::Quiet) {
        Ok(_) => panic!("the profile succeeded"),
        Err(err) => err.render(),
    }
}
