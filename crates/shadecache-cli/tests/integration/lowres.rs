//! `shadecache rewrite --variant lowres` refuses what lowres cannot take:
//! a reconstruction it does not read with, knobs out of their range.

use crate::util::{root, shadecache, stderr};

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

/// s must be 2 or 4, σ within what f32 squares, a in [1e-6, 1]: a clear
/// error, nothing written.
#[test]
fn lowres_bad_knobs_are_errors() {
    let shader = root().join("corpus/noise_marble.wgsl");
    for (flag, value, says) in [
        ("--upsample-factor", "3", "s is 2 or 4"),
        ("--sigma-normal", "0", "positive"),
        ("--sigma-depth=-1", "", "positive"),
        (
            "--sensitivity",
            "1.5",
            "the sensitivity must lie in [1e-6, 1]",
        ),
        (
            "--sigma-normal",
            "1e-45",
            "the weights' widths lie from 1e-6 to 1e6",
        ),
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

/// `--paper` writes the paper's path into both lowres's plans, forward and
/// deferred, and into the flags of their upsampling pass's
/// `cache_upsample` call: the geometry-blind gradient filter (256), hole
/// filling (512), σz of the depth range (1024) and material ids (2048)
/// over spatio-temporal (4).
#[test]
fn paper_is_written_into_both_lowres_plans() {
    let shader = root().join("corpus/noise_marble.wgsl");
    let out = tempfile::tempdir().unwrap();
    let output = shadecache([
        "rewrite".as_ref(),
        shader.as_os_str(),
        "--variant".as_ref(),
        "lowres,deferred-lowres".as_ref(),
        "--node".as_ref(),
        "nb0c12cc4".as_ref(),
        "--paper".as_ref(),
        "--out".as_ref(),
        out.path().as_os_str(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    for (variant, upsampling_pass) in [("lowres", "pass2"), ("deferred-lowres", "pass4")] {
        let dir = out.path().join(variant);
        let plan: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("plan.json")).unwrap()).unwrap();
        let upsampling = &plan["upsampling"];
        assert_eq!(
            upsampling["gradient_filter"], "paper",
            "{variant}: {upsampling}"
        );
        assert_eq!(upsampling["fill_holes"], true, "{variant}: {upsampling}");
        assert_eq!(
            upsampling["depth_tolerance"], "of-range",
            "{variant}: {upsampling}"
        );
        assert_eq!(upsampling["material_ids"], true, "{variant}: {upsampling}");
        let wgsl = std::fs::read_to_string(dir.join(format!("{upsampling_pass}.wgsl"))).unwrap();
        assert!(wgsl.contains("cache_upsample(3844u"), "{variant}: {wgsl}");
    }
}
