//! `shadecache play` as a user runs it: the original, a fixed cache and
//! the host crate's governor, on lavapipe. The ratios are of one run (each
//! frame draws all three in turn), and the bounds leave room for a shared
//! two-core machine.

use std::path::Path;

use serde_json::Value;

use crate::util::*;

/// `shadecache play SHADER --scene SCENE ARGS...` into a new folder; its
/// play.json.
fn play(shader: &str, scene: &str, args: &[&str]) -> Value {
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("play");
    let mut all = vec!["play", shader, "--scene", scene, "--quiet", "--out"];
    let dir_text = dir.display().to_string();
    all.push(&dir_text);
    all.extend(args);
    let output = shadecache(&all);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = std::fs::read_to_string(dir.join("play.json")).unwrap();
    let page = std::fs::read_to_string(dir.join("play.html")).unwrap();
    assert!(page.contains("<svg") && page.contains("governor"), "{page}");
    assert!(
        stdout(&output).contains("original") && stdout(&output).contains("governor"),
        "{}",
        stdout(&output)
    );
    let mut played: Value = serde_json::from_str(&text).unwrap();
    // What the page shows, for the tests to check beside the JSON.
    played["html_marks_the_switch"] = Value::Bool(page.contains("cache off at "));
    played
}

fn number(value: &Value, key: &str) -> f64 {
    value[key]
        .as_f64()
        .unwrap_or_else(|| panic!("`{key}` in {value}"))
}

/// Mean time of the governed frames from `frame` on.
fn auto_mean_from(played: &Value, frame: u64) -> f64 {
    let times: Vec<f64> = played["auto_frames"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["frame"].as_u64().unwrap() >= frame)
        .map(|f| f["ms"].as_f64().unwrap())
        .collect();
    times.iter().sum::<f64>() / times.len().max(1) as f64
}

/// A cache that costs more than it saves (three-pass recomputing every
/// pixel every frame, Δn = 1) is switched off once the governor has
/// enough original frames to be sure, and from then on the governed
/// frames cost what the original's do, within 10%: the re-probes' bursts
/// cost about 2%, and on lavapipe the same original pipeline drawn at
/// another place in the frame's order differs by up to 6%
/// (docs/governor.md).
#[test]
fn governor_turns_a_losing_cache_off() {
    if no_gpu() {
        return;
    }
    let played = play(
        "corpus/noise_marble.wgsl",
        "corpus/scenes/marble_sphere.toml",
        &[
            "--size",
            "128x128",
            "--frames",
            "600",
            "--variant",
            "three-pass",
            "--refresh-period",
            "1",
        ],
    );
    let fixed = number(&played, "original_ms") / number(&played, "fixed_ms");
    assert!(
        fixed < 0.9,
        "the fixed cache at {fixed:.2}×: it should lose"
    );
    let decisions = played["decisions"].as_array().unwrap();
    assert_eq!(decisions.len(), 1, "{decisions:?}");
    assert_eq!(decisions[0]["on"], false);
    let off = decisions[0]["frame"].as_u64().unwrap();
    assert!(off <= 400, "off at frame {off}");
    let after = auto_mean_from(&played, off);
    let original = number(&played, "original_ms");
    assert!(
        after <= original * 1.10,
        "governed {after:.3} ms after the switch against {original:.3} ms"
    );
    assert_eq!(played["auto_on_at_end"], false);
    assert!(
        played["html_marks_the_switch"].as_bool().unwrap(),
        "the page marks no switch"
    );
}

/// A cache that pays (the environment map's 25 taps, two-pass) is kept,
/// and the governor's original frames, the measurement, cost little of its
/// gain: at least 90% of what the fixed cache saves.
#[test]
fn governor_keeps_a_winning_cache() {
    if no_gpu() {
        return;
    }
    let played = play(
        "corpus/envmap_gauss.wgsl",
        "corpus/scenes/envmap_sphere.toml",
        &[
            "--size",
            "128x128",
            "--frames",
            "400",
            "--variant",
            "two-pass",
        ],
    );
    let (original, fixed, auto) = (
        number(&played, "original_ms"),
        number(&played, "fixed_ms"),
        number(&played, "auto_ms"),
    );
    assert!(
        fixed < original * 0.8,
        "{fixed:.3} ms against {original:.3}"
    );
    assert_eq!(played["decisions"].as_array().unwrap().len(), 0, "{played}");
    let kept = (original - auto) / (original - fixed);
    assert!(kept >= 0.9, "the governor kept {kept:.3} of the gain");
}

/// A cache near 1× (three-pass at Δn = 32 on the marble at 128²: 0.90×
/// to 1.00× on one lavapipe machine, 0.77× on another) has a speed-up
/// interval near or across 1×: in 1000 frames the governor switches at
/// most twice, never twice within its minimum dwell of 120 frames. How
/// near 1× the cache lands is the machine's, not asserted here (no test
/// asserts a timing); the governor's own tests play a cache at exactly 1×
/// under noise.
#[test]
fn governor_does_not_flap_on_noise() {
    if no_gpu() {
        return;
    }
    let played = play(
        "corpus/noise_marble.wgsl",
        "corpus/scenes/marble_sphere.toml",
        &[
            "--size",
            "128x128",
            "--frames",
            "1000",
            "--variant",
            "three-pass",
            "--refresh-period",
            "32",
        ],
    );
    let fixed = number(&played, "original_ms") / number(&played, "fixed_ms");
    let frames: Vec<u64> = played["decisions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["frame"].as_u64().unwrap())
        .collect();
    assert!(frames.len() <= 2, "fixed cache at {fixed:.2}×: {frames:?}");
    assert!(
        frames.windows(2).all(|w| w[1] - w[0] >= 120),
        "fixed cache at {fixed:.2}×: {frames:?}"
    );
}

/// The payload's weight drops halfway (the blur's 64 taps become 1 at
/// frame 500): the cache pays before and loses after, and the governor
/// keeps it on until the change and turns it off within 400 frames of it
/// (its pairs come one in 16 frames, and the window's median turns after
/// half of its 24 pairs are new).
#[test]
fn governor_follows_a_scene_that_changes_weight() {
    if no_gpu() {
        return;
    }
    let played = play(
        "corpus/texture_loop.wgsl",
        "corpus/scenes/blur_gets_light.toml",
        &["--frames", "1000", "--variant", "two-pass"],
    );
    let decisions = played["decisions"].as_array().unwrap();
    assert!(!decisions.is_empty(), "{played}");
    let first = &decisions[0];
    assert_eq!(first["on"], false, "{decisions:?}");
    let off = first["frame"].as_u64().unwrap();
    assert!(
        (500..900).contains(&off),
        "off at frame {off}: {decisions:?}"
    );
    assert!(number(first, "speedup") < 1.0, "{first}");
    // Before the change the cache was on and paid.
    let before: Vec<&Value> = played["auto_frames"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| (100..500).contains(&f["frame"].as_u64().unwrap()))
        .collect();
    let cached = before.iter().filter(|f| f["drew"] != "original").count();
    assert!(
        cached * 10 >= before.len() * 9,
        "{cached} of {} cached",
        before.len()
    );
}

/// Given several variants, the governor tries each at the start (warmed
/// up, measured against the original, its first warm frame watched) and
/// draws the fastest of those within the budget; the fixed way draws the
/// first.
#[test]
fn governor_draws_the_fastest_of_several_variants() {
    if no_gpu() {
        return;
    }
    let played = play(
        "corpus/noise_marble.wgsl",
        "corpus/scenes/marble_sphere.toml",
        &[
            "--size",
            "128x128",
            "--frames",
            "400",
            "--variant",
            "three-pass,one-pass,two-pass",
            "--min-psnr",
            "20",
        ],
    );
    assert_eq!(
        played["auto_variants"],
        serde_json::json!(["three-pass", "one-pass", "two-pass"])
    );
    assert!(played["fixed_variant"]
        .as_str()
        .unwrap()
        .starts_with("three-pass"));
    let trials = played["trials"].as_array().unwrap();
    assert_eq!(trials.len(), 1, "{played}");
    let turns = trials[0].as_array().unwrap();
    let tried: Vec<u64> = turns
        .iter()
        .map(|t| t["variant"].as_u64().unwrap())
        .collect();
    assert_eq!(tried, [0, 1, 2]);
    assert!(turns.iter().all(|t| number(t, "psnr") >= 20.0), "{turns:?}");
    let fastest = turns
        .iter()
        .max_by(|a, b| number(a, "speedup").total_cmp(&number(b, "speedup")))
        .unwrap()["variant"]
        .clone();
    let chosen = &played["decisions"][0];
    assert_eq!(chosen["cause"], "trial", "{chosen}");
    assert_eq!(chosen["variant"], fastest, "{chosen}");
    // The governed frames after the trial draw the chosen variant.
    let after = chosen["frame"].as_u64().unwrap() + 8;
    assert!(played["auto_frames"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["frame"].as_u64().unwrap() > after && f["drew"] != "original")
        .all(|f| f["variant"] == fastest));
}

/// A light that starts to move (frame 120, then 4° a frame) leaves the
/// cached lit colour behind it: the error watch sees the watched frames
/// fall below the budget of 36 dB and the governor halves Δn from 16,
/// each time for a watched frame below the budget, never before the light
/// moves, and keeps the cache on.
#[test]
fn governor_lowers_delta_n_when_the_error_watch_trips() {
    if no_gpu() {
        return;
    }
    let played = play(
        "corpus/noise_marble.wgsl",
        "corpus/scenes/light_starts_moving.toml",
        &[
            "--frames",
            "400",
            "--variant",
            "one-pass",
            "--refresh-period",
            "16",
            "--min-psnr",
            "36",
        ],
    );
    let decisions = played["decisions"].as_array().unwrap();
    let lowered: Vec<&Value> = decisions.iter().filter(|d| d["cause"] == "error").collect();
    assert!(!lowered.is_empty(), "{decisions:?}");
    let mut period = 16;
    for decision in &lowered {
        assert!(decision["frame"].as_u64().unwrap() > 120, "{decision}");
        assert!(number(decision, "psnr") < 36.0, "{decision}");
        assert_eq!(decision["on"], true, "{decision}");
        assert_eq!(
            decision["period"].as_u64().unwrap(),
            period / 2,
            "{decision}"
        );
        period /= 2;
    }
    assert_eq!(played["auto_period_at_end"].as_u64().unwrap(), period);
    let watches = played["watches"].as_array().unwrap();
    assert!(
        watches
            .iter()
            .filter(|w| w["frame"].as_u64().unwrap() < 120)
            .all(|w| number(w, "psnr") >= 36.0),
        "{watches:?}"
    );
    assert!(number(&played, "watch_frame_ms") > number(&played, "fixed_ms"));
}

/// On the same frames, the error watch's PSNR (a compute pass on the GPU,
/// over the pixels the cache's depth covers) is the profiler's (the frame
/// read back and compared with the reference's over the pixels the
/// classification marks), within 0.5 dB.
#[test]
fn error_watch_equals_the_profilers_error() {
    if no_gpu() {
        return;
    }
    let played = play(
        "corpus/noise_marble.wgsl",
        "corpus/scenes/marble_sphere.toml",
        &[
            "--size",
            "128x128",
            "--frames",
            "150",
            "--variant",
            "one-pass",
            "--refresh-period",
            "32",
            "--min-psnr",
            "20",
        ],
    );
    let watches = played["watches"].as_array().unwrap();
    assert!(watches.len() >= 2, "{played}");
    for watch in watches {
        let (gpu, profiler) = (number(watch, "psnr"), number(watch, "profiler_psnr"));
        assert!(
            (gpu - profiler).abs() < 0.5 && gpu < 100.0,
            "watch {gpu:.3} dB, profiler {profiler:.3} dB"
        );
    }
}

/// Of several variants, one the rewrite refuses (one-pass, where the
/// payload takes implicit derivatives under the miss branch) is left out
/// with its reason, and the others are played; asked for alone, it is an
/// error naming the reason, and nothing is written.
#[test]
fn play_leaves_out_a_refused_variant_and_plays_the_rest() {
    if no_gpu() {
        return;
    }
    let played = play(
        "corpus/pbr_material_flags.wgsl",
        "corpus/scenes/pbr_flags_sphere.toml",
        &[
            "--size",
            "64x64",
            "--frames",
            "20",
            "--variant",
            "one-pass,two-pass",
        ],
    );
    assert_eq!(played["auto_variants"], serde_json::json!(["two-pass"]));
    let refused = played["refused"].as_array().unwrap();
    assert_eq!(refused.len(), 1, "{refused:?}");
    assert!(
        refused[0].as_str().unwrap().contains("one-pass")
            && refused[0].as_str().unwrap().contains("derivatives"),
        "{refused:?}"
    );
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("play");
    let output = shadecache([
        "play".as_ref(),
        "corpus/pbr_material_flags.wgsl".as_ref(),
        "--scene".as_ref(),
        "corpus/scenes/pbr_flags_sphere.toml".as_ref(),
        "--variant".as_ref(),
        "one-pass".as_ref(),
        "--out".as_ref(),
        dir.as_os_str(),
    ] as [&std::ffi::OsStr; 8]);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("derivatives"),
        "{}",
        stderr(&output)
    );
    assert!(!dir.join("play.json").exists());
}

/// A variant `play` cannot draw is refused before anything runs, with the
/// reason, and a bad flag is a usage error.
#[test]
fn play_refuses_what_it_cannot_play() {
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("play");
    let output = shadecache([
        "play".as_ref(),
        "corpus/noise_marble.wgsl".as_ref(),
        "--variant".as_ref(),
        "all".as_ref(),
        "--out".as_ref(),
        dir.as_os_str(),
    ] as [&std::ffi::OsStr; 6]);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(stderr(&output).contains("name them"));
    assert!(!Path::new(&dir).join("play.json").exists());
    // An error budget that is no PSNR is a usage error, before anything
    // runs.
    let output = shadecache([
        "play".as_ref(),
        "corpus/noise_marble.wgsl".as_ref(),
        "--min-psnr".as_ref(),
        "0".as_ref(),
        "--out".as_ref(),
        dir.as_os_str(),
    ] as [&std::ffi::OsStr; 6]);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("PSNR in dB"),
        "{}",
        stderr(&output)
    );
    assert!(!Path::new(&dir).join("play.json").exists());
}
