//! What `shadecache analyze` reports.

use std::path::Path;

use serde_json::Value;

use crate::util::{analyze_json, shadecache, stdout, temp_file};

fn candidate<'a>(analysis: &'a Value, text: &str) -> &'a Value {
    analysis["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["text"] == text)
        .unwrap_or_else(|| panic!("no candidate `{text}`"))
}

fn ratio(analysis: &Value, text: &str) -> f64 {
    candidate(analysis, text)["ratio"].as_f64().unwrap()
}

#[test]
fn noise_partial_octave_sums_rise_toward_the_full_sum() {
    let analysis = analyze_json(Path::new("corpus/noise_marble.wgsl"));
    let sums = [
        "abs(gradient_noise(p))",
        "o1 + (0.5 * abs(gradient_noise(p * 2.0)))",
        "s2 + (0.25 * abs(gradient_noise(p * 4.0)))",
        "s3 + (0.125 * abs(gradient_noise(p * 8.0)))",
        "s4 + (0.0625 * abs(gradient_noise(p * 16.0)))",
    ];
    let ratios: Vec<f64> = sums.iter().map(|text| ratio(&analysis, text)).collect();
    for pair in ratios.windows(2) {
        assert!(pair[1] > pair[0], "partial sums must rise: {ratios:?}");
    }
    // Each octave costs about the same, so the k-th partial sum holds about
    // k/5 of the noise; the full sum is most of the shader.
    assert!(ratios[4] > 0.9, "{ratios:?}");
    assert!((ratios[1] / ratios[0] - 2.0).abs() < 0.1, "{ratios:?}");
}

#[test]
fn json_has_the_documented_shape() {
    let analysis = analyze_json(Path::new("corpus/noise_marble.wgsl"));
    assert_eq!(analysis["shader"], "corpus/noise_marble.wgsl");
    assert_eq!(analysis["entry"], "fs_main");
    assert!(analysis["total_cost"].as_f64().unwrap() > 0.0);
    let first = &analysis["candidates"][0];
    for key in [
        "id",
        "span",
        "text",
        "type",
        "components",
        "cost",
        "ratio",
        "overlap",
    ] {
        assert!(!first[key].is_null(), "candidate lacks `{key}`: {first}");
    }
    assert!(first["span"]["start"].as_array().unwrap().len() == 2);
    assert!(first["span"]["end"].as_array().unwrap().len() == 2);
    let types = ["f32", "vec2<f32>", "vec3<f32>", "vec4<f32>"];
    for c in analysis["candidates"].as_array().unwrap() {
        let ty = c["type"].as_str().unwrap();
        let components = c["components"].as_u64().unwrap() as usize;
        assert_eq!(types[components - 1], ty);
    }
    // Candidates come highest P/T first; those that read per-frame inputs
    // as if 0.02 lower.
    let ratios: Vec<f64> = analysis["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let flagged = !c["depends_on"].as_array().unwrap().is_empty();
            c["ratio"].as_f64().unwrap() - if flagged { 0.02 } else { 0.0 }
        })
        .collect();
    assert!(ratios.windows(2).all(|w| w[0] >= w[1]));
    let rejected = analysis["rejected"].as_array().unwrap();
    assert!(rejected.iter().all(|r| r["reason"].is_string()));
}

#[test]
fn span_and_text_agree_with_the_source() {
    let path = Path::new("corpus/noise_marble.wgsl");
    let source = std::fs::read_to_string(crate::util::root().join(path)).unwrap();
    let analysis = analyze_json(path);
    let sum = candidate(&analysis, "s4 + (0.0625 * abs(gradient_noise(p * 16.0)))");
    let [line, col] = [0, 1].map(|i| sum["span"]["start"][i].as_u64().unwrap() as usize);
    let source_line = source.lines().nth(line - 1).unwrap();
    assert!(source_line[col - 1..].starts_with("s4 + (0.0625"));
    assert_eq!(sum["span"]["end"][0].as_u64().unwrap() as usize, line);
}

/// One shader that exercises every reason for rejection.
const REASONS: &str = r#"
struct Frame { tint: vec3<f32>, count: u32 }
@group(0) @binding(0) var<uniform> frame: Frame;

@fragment
fn fs(@location(0) uv: vec2<f32>) -> @location(0) vec4<f32> {
    let shade = frame.tint * 0.5;
    let cell = vec2<i32>(floor(uv * 8.0));
    var acc = 0.0;
    for (var i = 0u; i < frame.count; i++) {
        acc += sin(uv.x * f32(i));
    }
    let wave = cos(uv.y * 12.0);
    return vec4<f32>(shade * wave + vec3<f32>(acc) + vec3<f32>(f32(cell.x)), 1.0);
}
"#;

#[test]
fn rejected_nodes_carry_their_reason() {
    let (_dir, path) = temp_file("reasons.wgsl", REASONS.as_bytes());
    let analysis = analyze_json(&path);
    let reason = |text: &str| -> String {
        analysis["rejected"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["text"] == text)
            .unwrap_or_else(|| panic!("`{text}` is not rejected: {analysis:#}"))["reason"]
            .as_str()
            .unwrap()
            .to_string()
    };
    assert_eq!(reason("frame.tint * 0.5"), "uniform-only");
    assert_eq!(reason("vec2<i32>(floor(uv * 8.0))"), "not-storable");
    assert_eq!(reason("sin(uv.x * f32(i))"), "in-loop");
    assert_eq!(reason("uv.y"), "trivial");
    assert_eq!(reason("12.0"), "trivial");
    // Still candidates: per-pixel float computations outside loops, and the
    // loop's total read after the loop.
    candidate(&analysis, "cos(uv.y * 12.0)");
    candidate(&analysis, "shade * wave + vec3<f32>(acc)");
}

#[test]
fn text_output_shows_candidates_as_notes_in_the_source() {
    let output = shadecache(["analyze", "corpus/noise_marble.wgsl"]);
    assert!(output.status.success());
    let text = stdout(&output);
    assert!(text.starts_with("note: #1 candidate n"), "{text}");
    assert!(text.contains("┌─ corpus/noise_marble.wgsl:"), "{text}");
    assert!(text.contains("abs(gradient_noise(p))"));
    assert!(text.contains("candidates,"));
    assert!(
        !text.contains("rejected n"),
        "rejected are shown only with --all"
    );

    let all = stdout(&shadecache([
        "analyze",
        "corpus/noise_marble.wgsl",
        "--all",
    ]));
    assert!(all.contains("(uniform-only)"), "{all}");
    assert!(all.contains("(trivial)"));
}

#[test]
fn entry_selects_among_several_fragment_entry_points() {
    let source = "@fragment fn first(@location(0) x: f32) -> @location(0) vec4<f32> { return vec4<f32>(sin(x)); }\n@fragment fn second(@location(0) x: f32) -> @location(0) vec4<f32> { return vec4<f32>(cos(x)); }\n";
    let (_dir, path) = temp_file("two.wgsl", source.as_bytes());
    let output = shadecache([
        "analyze".as_ref(),
        path.as_os_str(),
        "--entry".as_ref(),
        "second".as_ref(),
        "--format".as_ref(),
        "json".as_ref(),
    ] as [&std::ffi::OsStr; 6]);
    assert!(output.status.success());
    let analysis: Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(analysis["entry"], "second");
    let texts: Vec<&str> = analysis["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["text"].as_str().unwrap())
        .collect();
    assert!(texts.contains(&"cos(x)"), "{texts:?}");
    assert!(!texts.contains(&"sin(x)"), "{texts:?}");
}

/// Per-pixel values of a surface, a dither over the pixel's own screen
/// position, and values that read time and the camera.
const PAYLOAD_DEPENDENCES: &str = include_str!("../../../../tests/shaders/dependences.wgsl");

/// Values that read time or the camera go stale as they move: flagged in
/// `depends_on` (JSON and text) and ranked after object-space nodes of
/// similar P/T.
#[test]
fn time_dependent_payload_is_flagged() {
    let (_, analysis) = crate::util::analyzed("dependences.wgsl", PAYLOAD_DEPENDENCES);
    let pulse = crate::util::candidate(
        &analysis,
        "sin(world.x * 10.0 + frame.time) * cos(world.y * 7.0)",
    );
    assert_eq!(pulse.depends_on, ["time"]);
    let view = crate::util::candidate(&analysis, "length(frame.camera_position - world)");
    assert_eq!(view.depends_on, ["camera"]);
    let pattern = crate::util::candidate(&analysis, "sin(world.x * 10.0) * cos(world.y * 7.0)");
    assert!(pattern.depends_on.is_empty());
    // `pulse` costs a little more than `pattern` (one addition), yet
    // ranks after it.
    let rank = |text: &str| {
        analysis
            .candidates
            .iter()
            .position(|c| c.node.text == text)
            .unwrap()
    };
    assert!(pulse.ratio > pattern.ratio && pulse.ratio - pattern.ratio < 0.02);
    assert!(
        rank("sin(world.x * 10.0) * cos(world.y * 7.0)")
            < rank("sin(world.x * 10.0 + frame.time) * cos(world.y * 7.0)")
    );
    let (_dir, path) = temp_file("dependences.wgsl", PAYLOAD_DEPENDENCES.as_bytes());
    let json = analyze_json(&path);
    let flagged = json["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["text"] == "sin(world.x * 10.0 + frame.time) * cos(world.y * 7.0)")
        .unwrap();
    assert_eq!(flagged["depends_on"], serde_json::json!(["time"]));
    let text = stdout(&shadecache(["analyze".as_ref(), path.as_os_str()]));
    assert!(text.contains("it reads per-frame inputs (time)"), "{text}");
}
