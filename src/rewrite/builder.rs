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
