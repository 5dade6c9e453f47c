//! A small builder for writing new functions in naga IR: each expression
//! is appended and emitted at once, so the function reads top to bottom as
//! its WGSL would.

use naga::{Block, Expression, Function, Handle, Span, Statement};

/// Builds one function body.
#[derive(Debug)]
pub struct Builder {
    pub function: Function,
    /// The block statements are added to.
    pub block: Block,
}

impl Builder {
    pub fn new(function: Function) -> Self {
        Builder {
            function,
            block: Block::new(),
        }
    }

    /// Appends an expression, emitting it when it needs emitting.
    pub fn expr(&mut self, expr: Expression) -> Handle<Expression> {
        let emit = !expr.needs_pre_emit();
        let handle = self.function.expressions.append(expr, Span::UNDEFINED);
        if emit {
            self.block.push(
                Statement::Emit(naga::Range::new_from_bounds(handle, handle)),
                Span::UNDEFINED,
            );
        }
        handle
    }

    /// Names an expression, so the WGSL shows it as a `let` of that name.
    pub fn name(&mut self, expr: Handle<Expression>, name: &str) {
        self.function.named_expressions.insert(expr, name.into());
    }

    pub fn argument(&mut self, index: u32) -> Handle<Expression> {
        self.expr(Expression::FunctionArgument(index))
    }

    pub fn literal_f32(&mut self, value: f32) -> Handle<Expression> {
        self.expr(Expression::Literal(naga::Literal::F32(value)))
    }

    pub fn member(&mut self, base: Handle<Expression>, index: u32) -> Handle<Expression> {
        self.expr(Expression::AccessIndex { base, index })
    }

    /// Calls `function`, returning its result.
    pub fn call(
        &mut self,
        function: Handle<naga::Function>,
        arguments: Vec<Handle<Expression>>,
    ) -> Handle<Expression> {
        let result = self
            .function
            .expressions
            .append(Expression::CallResult(function), Span::UNDEFINED);
        self.block.push(
            Statement::Call {
                function,
                arguments,
                result: Some(result),
            },
            Span::UNDEFINED,
        );
        result
    }

    pub fn push(&mut self, statement: Statement) {
        self.block.push(statement, Span::UNDEFINED);
    }

    /// Runs `build` on a fresh block and returns it, leaving the current
    /// block as it was.
    pub fn nested(&mut self, build: impl FnOnce(&mut Self)) -> Block {
        let outer = std::mem::take(&mut self.block);
        build(self);
        std::mem::replace(&mut self.block, outer)
    }

    pub fn finish(mut self) -> Function {
        self.function.body = self.block;
        self.function
    }
}

/// The scalar type `scalar`, added to `module` if it is not there.
pub fn scalar_type(module: &mut naga::Module, scalar: naga::Scalar) -> Handle<naga::Type> {
    module.types.insert(
        naga::Type {
            name: None,
            inner: naga::TypeInner::Scalar(scalar),
        },
        Span::UNDEFINED,
    )
}

/// The vector type of `size` × `scalar`, added to `module` if it is not
/// there.
pub fn vector_type(
    module: &mut naga::Module,
    size: naga::VectorSize,
    scalar: naga::Scalar,
) -> Handle<naga::Type> {
    module.types.insert(
        naga::Type {
            name: None,
            inner: naga::TypeInner::Vector { size, scalar },
        },
        Span::UNDEFINED,
    )
}

/// `vec4<f32>`: clip positions, payloads, flows.
pub fn vec4_type(module: &mut naga::Module) -> Handle<naga::Type> {
    vector_type(module, naga::VectorSize::Quad, naga::Scalar::F32)
}

/// A vertex or fragment entry point `name` running `function`, with
/// nothing of the compute, mesh and ray stages.
pub fn entry_point(
    name: impl Into<String>,
    stage: naga::ShaderStage,
    function: naga::Function,
) -> naga::EntryPoint {
    naga::EntryPoint {
        name: name.into(),
        stage,
        early_depth_test: None,
        workgroup_size: [0; 3],
        workgroup_size_overrides: None,
        function,
        mesh_info: None,
        task_payload: None,
        incoming_ray_payload: None,
    }
}

/// `@location(location)` with no interpolation given: a fragment output,
/// or a flat or default-interpolated input.
pub fn location(location: u32) -> naga::Binding {
    naga::Binding::Location {
        location,
        interpolation: None,
        sampling: None,
        blend_src: None,
        per_primitive: false,
    }
}

/// `@location(location)` interpolated perspective-correctly at the pixel
/// centre: the clip positions at other times, as the rasteriser
/// interpolates the position itself.
pub fn perspective_location(location: u32) -> naga::Binding {
    naga::Binding::Location {
        location,
        interpolation: Some(naga::Interpolation::Perspective),
        sampling: Some(naga::Sampling::Center),
        blend_src: None,
        per_primitive: false,
    }
}
