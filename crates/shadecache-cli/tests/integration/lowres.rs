//! The lowres variant: the payload shaded at 1/s × 1/s of the pixels on
//! a jittered lattice and rebuilt at full resolution (seed 001).

use shadecache::profile::Options;
use shadecache::rewrite::{CacheFormat, Reconstruction, Variant};

use crate::profile::{marble_scene, options, run};
use crate::util::{root, shadecache, stderr};

/// Lowres alone, with `reconstructions`, rgba32float, after `warmup`
/// frames.
fn lowres(reconstructions: &[Reconstruction], warmup: u32, frames: u32) -> Options {
    let mut opts = options(&[32], &[4]);
    opts.variants = vec![Variant::Lowres];
    opts.lowres_reconstructions = reconstructions.to_vec();
    opts.cache_formats = vec![CacheFormat::Rgba32float];
    opts.warmup = Some(warmup);
    opts.frames = Some(frames);
    opts
}

/// A static scene: after s² = 16 frames every pixel has been shaded on
/// its own once, and the spatio-temporal reconstruction shows that away
/// from the silhouette (PSNR above 40 dB, under 0.2% of the pixels off by
/// more than the error threshold). This runs the whole variant through
/// the host crate, as an application does: the samples at 32×32 with the
/// projection jittered onto each frame's lattice, the upsampling, the
/// history. Not yet exact: at the silhouette the bilinear history lookup
/// straddles the edge and misses, and those pixels are upsampled anew each
/// frame (a nearest history fetch there is the next step).
#[test]
fn static_scene_lowres_converges_away_from_silhouettes() {
    let Some((_, report, _)) = run(
        &marble_scene("", ""),
        lowres(&[Reconstruction::SpatioTemporal], 17, 3),
    ) else {
        return;
    };
    assert_eq!(report.results.len(), 1);
    let row = &report.results[0];
    assert_eq!(row.refresh_period, 16);
    assert!(
        row.psnr > 40.0 && row.above_threshold < 0.002,
        "largest difference {} after 16 frames (PSNR {} dB, {} of pixels wrong)",
        row.max_abs_error,
        row.psnr,
        row.above_threshold
    );
}

/// Before the lattice has covered the window, only a sixteenth of the
/// pixels are shaded: the spatial upsampling interpolates the rest, so
/// the frame is not yet the reference (the convergence above is the
/// history's doing, not an artefact of a full-resolution shading).
#[test]
fn lowres_first_frame_is_upsampled_not_shaded() {
    let Some((_, report, _)) = run(
        &marble_scene("", ""),
        lowres(&[Reconstruction::Spatial], 0, 1),
    ) else {
        return;
    };
    let row = &report.results[0];
    assert!(row.max_abs_error > 4.0 / 255.0, "{}", row.max_abs_error);
    assert!(row.psnr > 20.0, "{}", row.psnr);
}

/// s must be 2 or 4, σ positive: a clear error, nothing written.
#[test]
fn lowres_bad_knobs_are_errors() {
    let shader = root().join("corpus/noise_marble.wgsl");
    for (flag, value, says) in [
        ("--upsample-factor", "3", "s is 2 or 4"),
        ("--sigma-normal", "0", "positive"),
        ("--sigma-depth=-1", "", "positive"),
        ("--sensitivity", "1.5", "(0, 1]"),
    ] {
        let out = tempfile::tempdir().unwrap();
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "rewrite".as_ref(),
            shader.as_os_str(),
            "--variant".as_ref(),
            "lowres".as_ref(),
            "--all-nodes".as_ref(),
            flag.as_ref(),
        ];
        if !value.is_empty() {
            args.push(value.as_ref());
        }
        args.extend(["--out".as_ref(), out.path().as_os_str()]);
        let output = shadecache(args);
        assert!(!output.status.success(), "{flag} {value}");
        assert!(
            stderr(&output).contains(says),
            "{flag} {value}: {}",
            stderr(&output)
        );
        assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 0);
    }
}

/// A cache variant refuses an upsampling reconstruction, and lowres a
/// cache one, each with its reason.
#[test]
fn lowres_and_cache_reconstructions_do_not_mix() {
    let shader = root().join("corpus/noise_marble.wgsl");
    for (variant, reconstruction, says) in [
        ("two-pass", "spatio-temporal", "upsamples lowres's samples"),
        (
            "lowres",
            "bilinear-packed",
            "rebuilds the payload from its samples",
        ),
    ] {
        let out = tempfile::tempdir().unwrap();
        let output = shadecache([
            "rewrite".as_ref(),
            shader.as_os_str(),
            "--variant".as_ref(),
            variant.as_ref(),
            "--node".as_ref(),
            "nb0c12cc4".as_ref(),
            "--reconstruction".as_ref(),
            reconstruction.as_ref(),
            "--out".as_ref(),
            out.path().as_os_str(),
        ]);
        assert!(!output.status.success());
        assert!(stderr(&output).contains(says), "{}", stderr(&output));
    }
}
