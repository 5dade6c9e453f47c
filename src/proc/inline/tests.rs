use super::*;

const HELPERS: &str = r#"
fn first_above(v: vec4<f32>, t: f32) -> f32 {
    for (var i = 0; i < 4; i++) {
        if v[i] > t {
            return v[i];
        }
    }
    return -1.0;
}

fn shade(x: f32) -> f32 {
    if x < 0.0 {
        return 0.0;
    }
    let y = x * x;
    return y + 1.0;
}

fn accumulate(x: f32) -> f32 {
    var total = 1.0;
    total += x;
    return total;
}

fn scale(p: ptr<function, f32>, by: f32) {
    *p = *p * by;
}

@fragment
fn fs(@location(0) v: vec4<f32>) -> @location(0) vec4<f32> {
    var acc = 0.0;
    for (var k = 0; k < 2; k++) {
        acc += accumulate(v.x + f32(k));
    }
    var s = shade(v.y);
    scale(&s, 2.0);
    return vec4<f32>(first_above(v, 0.5), s, acc, 1.0);
}
"#;

fn inline_all(source: &str) -> (naga::Module, Inlined) {
    let mut module = naga::front::wgsl::parse_str(source).unwrap();
    let root = module.entry_points[0].function.clone();
    let inlined = inline(&mut module, &root, &mut |_| true).unwrap();
    module.entry_points[0].function = inlined.function.clone();
    (module, inlined)
}

fn validate(module: &naga::Module) -> naga::valid::ModuleInfo {
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(module)
    .expect("the inlined module validates")
}

fn calls_in(function: &Function) -> usize {
    let mut calls = 0;
    super::super::each_statement(&function.body, &mut |s| {
        calls += usize::from(matches!(s, Statement::Call { .. }));
    });
    calls
}

#[test]
fn early_returns_in_branches_and_loops_inline_to_valid_ir() {
    let (module, inlined) = inline_all(HELPERS);
    validate(&module);
    assert_eq!(calls_in(&module.entry_points[0].function), 0);
    assert_eq!(inlined.calls.len(), 4);
    // The WGSL back end writes it, and it parses again.
    let info = validate(&module);
    let text =
        naga::back::wgsl::write_string(&module, &info, naga::back::wgsl::WriterFlags::empty())
            .unwrap();
    assert!(naga::front::wgsl::parse_str(&text).is_ok(), "{text}");
    // A return inside the helper's loop breaks out of it under the flag.
    assert!(text.contains("returned"), "{text}");
}

#[test]
fn a_call_in_a_loop_resets_the_helpers_locals_each_time() {
    let (module, inlined) = inline_all(HELPERS);
    let function = &module.entry_points[0].function;
    let accumulate = inlined
        .calls
        .iter()
        .position(|c| module.functions[c.function].name.as_deref() == Some("accumulate"))
        .unwrap();
    // `total`'s initializer is a store inside the caller's loop, not an
    // initializer that runs once.
    let total = function
        .local_variables
        .iter()
        .find(|(_, l)| l.name.as_deref() == Some("total"))
        .map(|(h, l)| (h, l.init))
        .unwrap();
    assert_eq!(total.1, None);
    let mut stored_in_loop = false;
    for (statement, _) in function.body.span_iter() {
        if let Statement::Loop { body, .. } = statement {
            super::super::each_statement(body, &mut |s| {
                if let Statement::Store { pointer, value } = *s {
                    stored_in_loop |= function.expressions[pointer]
                        == Expression::LocalVariable(total.0)
                        && matches!(
                            function.expressions[value],
                            Expression::Literal(naga::Literal::F32(v)) if v == 1.0
                        );
                }
            });
        }
    }
    assert!(stored_in_loop);
    // The call's result is a load, standing for the caller's
    // `CallResult`.
    let original = naga::front::wgsl::parse_str(HELPERS).unwrap();
    let root = &original.entry_points[0].function;
    let (call_result, _) = root
        .expressions
        .iter()
        .find(|(_, e)| matches!(e, Expression::CallResult(f) if *f == inlined.calls[accumulate].function))
        .unwrap();
    let load = inlined.find(None, call_result).unwrap();
    assert!(matches!(
        function.expressions[load],
        Expression::Load { .. }
    ));
}

#[test]
fn origins_name_each_call_sites_copy() {
    let (module, inlined) = inline_all(HELPERS);
    let function = &module.entry_points[0].function;
    assert_eq!(inlined.origins.len(), function.expressions.len());
    let shade = module
        .functions
        .iter()
        .find(|(_, f)| f.name.as_deref() == Some("shade"))
        .unwrap();
    // `x * x` in `shade` has one copy, found by its origin.
    let (square, _) = shade
        .1
        .expressions
        .iter()
        .find(|(_, e)| {
            matches!(
                e,
                Expression::Binary {
                    op: naga::BinaryOperator::Multiply,
                    ..
                }
            )
        })
        .unwrap();
    let call = inlined
        .calls
        .iter()
        .position(|c| c.function == shade.0)
        .unwrap();
    let copy = inlined.find(Some(call), square).unwrap();
    assert!(matches!(
        function.expressions[copy],
        Expression::Binary { .. }
    ));
    assert_eq!(inlined.path(call), vec![inlined.calls[call].ordinal]);
}

#[test]
fn only_the_selected_path_is_inlined() {
    let mut module = naga::front::wgsl::parse_str(HELPERS).unwrap();
    let root = module.entry_points[0].function.clone();
    // The second call in statement order: `shade(v.y)`.
    let inlined = inline(&mut module, &root, &mut |path| path == [1]).unwrap();
    assert_eq!(inlined.calls.len(), 1);
    assert_eq!(calls_in(&inlined.function), 3);
    module.entry_points[0].function = inlined.function;
    validate(&module);
}
