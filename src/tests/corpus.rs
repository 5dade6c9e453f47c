//! The corpus as the validators see it: naga and Tint accept every
//! shader, and Tint rejects a derivative in non-uniform control flow.

use super::util::{corpus, root, temp_file, tint_validate};

#[test]
fn corpus_is_valid_for_naga() {
    for path in corpus() {
        if let Err(err) = crate::front::load(&root().join(&path)) {
            panic!(
                "{} is not valid for naga:\n{}",
                path.display(),
                err.render()
            );
        }
    }
}

#[test]
fn corpus_is_valid_for_tint() {
    let files = corpus();
    for result in tint_validate(&files) {
        assert!(
            result.ok,
            "{} is rejected by Tint: {:#?}",
            result.file, result.messages
        );
    }
}

/// The Tint harness must catch what naga 30 lets through: a derivative in
/// non-uniform control flow of a fragment shader.
#[test]
fn tint_rejects_derivatives_in_non_uniform_control_flow() {
    let source = "@fragment\nfn fs(@location(0) uv: vec2<f32>) -> @location(0) vec4<f32> {\n    var c = 0.0;\n    if (uv.x > 0.5) {\n        c = dpdx(uv.y);\n    }\n    return vec4<f32>(c);\n}\n";
    let (_dir, path) = temp_file("non_uniform.wgsl", source.as_bytes());
    assert!(
        crate::front::load(&path).is_ok(),
        "naga 30 accepts this shader, which is why Tint is needed"
    );
    let result = tint_validate(&[path]).remove(0);
    assert!(!result.ok);
    let error = result
        .messages
        .iter()
        .find(|m| m.kind == "error")
        .expect("an error message");
    assert!(error.message.contains("uniform control flow"), "{error:?}");
    assert_eq!((error.line, error.column), (5, 13));
}
