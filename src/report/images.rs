//! The report's pictures: maps of the cache's decisions (hits green,
//! misses red — orange when off-screen — refreshes blue, as in seed 002
//! fig. 5) and the reference, variant and difference images of the best
//! result.

use std::path::{Path, PathBuf};

/// What the report shows besides its numbers: the last measured frames,
/// and the GPU timer scopes of the last frame.
#[derive(Debug)]
pub struct Pictures {
    /// The reference's last measured frame, RGBA8.
    pub reference: Vec<u8>,
    /// Colour and classes of each result, in `Report::results` order.
    pub results: Vec<Picture>,
    /// Every pass of every run in the last frame, for a Chrome trace.
    pub trace: Vec<wgpu_profiler::GpuTimerQueryResult>,
    /// The recommended configuration's rewrite, as it was measured (the
    /// analysis bounded by the scene's uniform values), to write out.
    pub chosen: Option<crate::rewrite::Rewritten>,
}

/// A result's last measured colour and classes (RGBA8).
pub type Picture = (Vec<u8>, Vec<u8>);

use super::Report;

/// The difference of two RGBA8 pictures, ×4 so that small errors show.
pub fn amplified_difference(a: &[u8], b: &[u8]) -> Vec<u8> {
    a.iter()
        .zip(b)
        .map(|(a, b)| a.abs_diff(*b).saturating_mul(4))
        .collect()
}

/// Writes an RGBA8 picture of `size` to `path` as a PNG, opaque (the
/// frames' alpha says nothing a viewer should show).
pub fn save_opaque(path: PathBuf, rgba: &[u8], size: [u32; 2]) -> Result<PathBuf, String> {
    let opaque: Vec<u8> = rgba
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    image::save_buffer(
        &path,
        &opaque,
        size[0],
        size[1],
        image::ExtendedColorType::Rgba8,
    )
    .map_err(|e| format!("cannot write `{}`: {e}", path.display()))?;
    Ok(path)
}

/// Creates `dir` (and its parents) for pictures.
pub fn create_dir(dir: &Path) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create `{}`: {e}", dir.display()))
}

/// Writes a reference, a result and their difference (×4) as the PNGs
/// `names` in `dir`; returns their paths.
pub fn save_comparison(
    dir: &Path,
    names: [&str; 3],
    (reference, result): (&[u8], &[u8]),
    size: [u32; 2],
) -> Result<Vec<PathBuf>, String> {
    let difference = amplified_difference(reference, result);
    names
        .into_iter()
        .zip([reference, result, &difference])
        .map(|(name, rgba)| save_opaque(dir.join(name), rgba, size))
        .collect()
}

/// Writes `maps/<rank>-<node>-<variant>-dn<Δn>-k<k>.png` for every result,
/// and `reference.png`, `best.png` and `difference.png` (×4 amplified)
/// into `dir/images/`. Returns the files written.
pub fn write_images(
    dir: &Path,
    report: &Report,
    pictures: &Pictures,
) -> Result<Vec<PathBuf>, String> {
    let [width, height] = report.size;
    let maps = dir.join("maps");
    let images = dir.join("images");
    create_dir(&maps)?;
    create_dir(&images)?;
    let save = |path: PathBuf, rgba: &[u8]| save_opaque(path, rgba, [width, height]);
    let mut written = Vec::new();
    for (rank, (row, (_, classes))) in report.results.iter().zip(&pictures.results).enumerate() {
        if classes.is_empty() {
            continue;
        }
        let name = map_name(rank, row);
        written.push(save(maps.join(name), classes)?);
    }
    if !pictures.reference.is_empty() {
        match pictures
            .results
            .first()
            .filter(|(color, _)| !color.is_empty())
        {
            Some((color, _)) => written.extend(save_comparison(
                &images,
                ["reference.png", "best.png", "difference.png"],
                (&pictures.reference, color),
                [width, height],
            )?),
            None => written.push(save(images.join("reference.png"), &pictures.reference)?),
        }
    }
    Ok(written)
}

/// The file name of a result's map.
pub fn map_name(rank: usize, row: &super::ResultRow) -> String {
    format!(
        "{:02}-{}-{}-dn{}-k{}-{}.png",
        rank + 1,
        row.node,
        row.variant,
        row.refresh_period,
        row.refresh_quad,
        row.reconstruction.as_str()
    )
}
