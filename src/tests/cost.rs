//! The cost model on shaders made to have a known answer.

use crate::analysis::{analyze, Analysis, Options};
use crate::diagnostic::SourceFile;
use crate::front;

fn analysis_of(source: &str) -> Analysis {
    let shader = front::parse(SourceFile::new("test.wgsl", source))
        .unwrap_or_else(|err| panic!("{}", err.render()));
    analyze(&shader, &Options::default()).unwrap_or_else(|err| panic!("{}", err.render()))
}

fn cost_of(analysis: &Analysis, text: &str) -> f64 {
    analysis
        .candidates
        .iter()
        .find(|c| c.node.text == text)
        .unwrap_or_else(|| panic!("no candidate `{text}`"))
        .cost
}

#[test]
fn a_payload_that_is_all_the_work_has_ratio_one() {
    let analysis = analysis_of(
        "@fragment\nfn fs(@location(0) uv: vec2<f32>) -> @location(0) vec4<f32> {\n    let v = sin(uv.x * 7.0) * cos(uv.y * 5.0) + sqrt(abs(uv.x - uv.y));\n    return vec4<f32>(v);\n}\n",
    );
    let top = &analysis.candidates[0];
    assert!((top.ratio - 1.0).abs() < 1e-9, "{top:?}");
    assert_eq!(top.cost, analysis.total_cost);
    // Caching the whole value leaves nothing shared with the rest.
    assert_eq!(cost_of(&analysis, "vec4<f32>(v)"), analysis.total_cost);
}

fn loop_shader(bound: &str) -> String {
    format!(
        "@fragment\nfn fs(@location(0) x: f32) -> @location(0) vec4<f32> {{\n    var acc = 0.0;\n    for (var i = 0; i < {bound}; i++) {{\n        acc += sin(x * f32(i));\n    }}\n    let total = acc * 0.5;\n    return vec4<f32>(total);\n}}\n"
    )
}

#[test]
fn a_loop_with_constant_bound_costs_n_times_its_body() {
    let cost = |n: u32| cost_of(&analysis_of(&loop_shader(&n.to_string())), "acc * 0.5");
    let (c4, c16, c64) = (cost(4), cost(16), cost(64));
    // cost(n) = n × body + fixed: the differences isolate the body.
    let body = (c16 - c4) / 12.0;
    assert!(
        body > 5.0,
        "the body (a sine, a multiply, a conversion, an add) costs something: {body}"
    );
    assert!(((c64 - c16) / 48.0 - body).abs() < 1e-9, "linear in n");
    let fixed = c4 - 4.0 * body;
    assert!(
        fixed.abs() < body,
        "almost all of the cost is the loop: fixed {fixed}, body {body}"
    );
}

#[test]
fn loop_trip_counts_are_inferred_from_constant_bounds() {
    let trips = |header: &str| {
        let source = format!(
            "const N: i32 = 6;\n@fragment\nfn fs(@location(0) x: f32, @location(1) @interpolate(flat) n: i32) -> @location(0) vec4<f32> {{\n    var acc = 0.0;\n    {header} {{\n        acc += x;\n    }}\n    return vec4<f32>(acc);\n}}\n"
        );
        let shader = front::parse(SourceFile::new("loop.wgsl", source)).unwrap();
        let function = &shader.module.entry_points[0].function;
        let layout = crate::proc::layout(&shader.module, function, 8.0);
        assert_eq!(layout.loops.len(), 1);
        layout.loops[0].trips
    };
    assert_eq!(trips("for (var i = 0; i < 10; i++)"), Some(10));
    assert_eq!(trips("for (var i = 0; i <= 10; i++)"), Some(11));
    assert_eq!(trips("for (var i = 2; i < 10; i += 3)"), Some(3));
    assert_eq!(trips("for (var i = 10; i > 0; i--)"), Some(10));
    assert_eq!(trips("for (var i = 0; i < N; i++)"), Some(6));
    assert_eq!(trips("for (var i = 5; i < 3; i++)"), Some(0));
    // Bounds only known at run time: the default.
    assert_eq!(trips("for (var i = 0; i < n; i++)"), None);
    // The counter written in the body: unknown.
    assert_eq!(
        trips("for (var i = 0; i < 10; i++) { i += 1; }\n    if (true)"),
        None
    );
}

#[test]
fn a_loop_with_unknown_bound_uses_the_default_trip_count() {
    let source = "@fragment\nfn fs(@location(0) x: f32, @location(1) @interpolate(flat) n: i32) -> @location(0) vec4<f32> {\n    var acc = 0.0;\n    for (var i = 0; i < n; i++) {\n        acc += sin(x * f32(i));\n    }\n    let total = acc * 0.5;\n    return vec4<f32>(total);\n}\n";
    let unknown = cost_of(&analysis_of(source), "acc * 0.5");
    let default_trips = crate::cost::Weights::default().default_loop_trips as u32;
    let known = cost_of(
        &analysis_of(&loop_shader(&default_trips.to_string())),
        "acc * 0.5",
    );
    assert!((unknown - known).abs() <= 2.0, "{unknown} vs {known}");
}

#[test]
fn a_helper_call_costs_its_body() {
    let inlined = analysis_of(
        "@fragment\nfn fs(@location(0) x: f32) -> @location(0) vec4<f32> {\n    let v = sin(x) * exp(x) + pow(x, 2.5);\n    return vec4<f32>(v);\n}\n",
    );
    let called = analysis_of(
        "fn shade(x: f32) -> f32 {\n    return sin(x) * exp(x) + pow(x, 2.5);\n}\nfn wrap(x: f32) -> f32 {\n    return shade(x);\n}\n@fragment\nfn fs(@location(0) x: f32) -> @location(0) vec4<f32> {\n    let v = wrap(x);\n    return vec4<f32>(v);\n}\n",
    );
    assert_eq!(
        cost_of(&inlined, "sin(x) * exp(x) + pow(x, 2.5)"),
        cost_of(&called, "wrap(x)")
    );
    assert_eq!(inlined.total_cost, called.total_cost);
}

#[test]
fn overlap_counts_what_the_rest_also_needs() {
    // `n` is needed by the payload and by the rest: it is paid twice in a
    // multi-pass variant (seed 002, fig. 7).
    let analysis = analysis_of(
        "@fragment\nfn fs(@location(0) x: vec3<f32>) -> @location(0) vec4<f32> {\n    let n = normalize(x);\n    let payload = sin(n * 9.0);\n    let rest = n * 0.5;\n    return vec4<f32>(payload + rest, 1.0);\n}\n",
    );
    let payload = analysis
        .candidates
        .iter()
        .find(|c| c.node.text == "sin(n * 9.0)")
        .unwrap();
    let n = cost_of(&analysis, "normalize(x)");
    assert_eq!(payload.overlap, n);
    assert!(payload.cost > n);
}
