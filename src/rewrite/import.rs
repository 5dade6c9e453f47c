//! Importing the toolchain's own WGSL (`shaders/`) into a user's module at
//! IR level: types, constants, global variables and functions are copied
//! with their handles remapped, and the imported resources are moved to the
//! bind group the rewrite chose.

use std::collections::HashMap;

use naga::{Block, Expression, Handle, Module, Statement};

use super::remap::{self, Mapper};

/// What an import added to the target module, by name.
#[derive(Debug, Default)]
pub struct Imported {
    pub functions: HashMap<String, Handle<naga::Function>>,
    pub globals: HashMap<String, Handle<naga::GlobalVariable>>,
    pub types: HashMap<String, Handle<naga::Type>>,
}

/// Copies everything of `source` except its entry points into `target`,
/// putting its resource bindings in `group`.
pub fn import(target: &mut Module, source: &Module, group: u32) -> Imported {
    let mut maps = ModuleMaps::default();
    let mut imported = Imported::default();

    // Types come in dependency order in a UniqueArena.
    for (handle, ty) in source.types.iter() {
        let inner = remap::type_inner(&ty.inner, &mut TypeOnly(&maps.types));
        let mapped = target.types.insert(
            naga::Type {
                name: ty.name.clone(),
                inner,
            },
            source.types.get_span(handle),
        );
        maps.types.insert(handle, mapped);
        if let Some(name) = &ty.name {
            imported.types.insert(name.clone(), mapped);
        }
    }

    // Constant expressions and constants, interleaved in source order: a
    // constant's initializer only refers to earlier expressions.
    for (handle, expr) in source.global_expressions.iter() {
        let mut mapper = GlobalMapper {
            maps: &mut maps,
            target_constants: &mut target.constants,
            source,
        };
        let copied = remap::expression(expr, &mut mapper);
        let mapped = target
            .global_expressions
            .append(copied, source.global_expressions.get_span(handle));
        maps.global_expressions.insert(handle, mapped);
    }

    for (handle, global) in source.global_variables.iter() {
        let ty = maps.types[&global.ty];
        let init = global.init.map(|h| maps.global_expressions[&h]);
        let binding = global.binding.as_ref().map(|b| naga::ResourceBinding {
            group,
            binding: b.binding,
        });
        let mapped = target.global_variables.append(
            naga::GlobalVariable {
                name: global.name.clone(),
                space: global.space,
                binding,
                ty,
                init,
                memory_decorations: global.memory_decorations,
            },
            source.global_variables.get_span(handle),
        );
        maps.globals.insert(handle, mapped);
        if let Some(name) = &global.name {
            imported.globals.insert(name.clone(), mapped);
        }
    }

    // Functions in arena order: a function only calls earlier ones.
    for (handle, function) in source.functions.iter() {
        let copied = copy_function(function, &mut maps, &mut target.constants, source);
        let mapped = target
            .functions
            .append(copied, source.functions.get_span(handle));
        maps.functions.insert(handle, mapped);
        if let Some(name) = &function.name {
            imported.functions.insert(name.clone(), mapped);
        }
    }
    imported
}

#[derive(Default)]
struct ModuleMaps {
    types: HashMap<Handle<naga::Type>, Handle<naga::Type>>,
    constants: HashMap<Handle<naga::Constant>, Handle<naga::Constant>>,
    global_expressions: HashMap<Handle<Expression>, Handle<Expression>>,
    globals: HashMap<Handle<naga::GlobalVariable>, Handle<naga::GlobalVariable>>,
    functions: HashMap<Handle<naga::Function>, Handle<naga::Function>>,
}

/// Maps types only (type definitions refer to nothing else but overrides,
/// which the toolchain's own WGSL does not use).
struct TypeOnly<'a>(&'a HashMap<Handle<naga::Type>, Handle<naga::Type>>);

impl Mapper for TypeOnly<'_> {
    fn expression(&mut self, h: Handle<Expression>) -> Handle<Expression> {
        h
    }
    fn ty(&mut self, h: Handle<naga::Type>) -> Handle<naga::Type> {
        self.0[&h]
    }
    fn constant(&mut self, h: Handle<naga::Constant>) -> Handle<naga::Constant> {
        h
    }
    fn override_(&mut self, h: Handle<naga::Override>) -> Handle<naga::Override> {
        h
    }
    fn global(&mut self, h: Handle<naga::GlobalVariable>) -> Handle<naga::GlobalVariable> {
        h
    }
    fn local(&mut self, h: Handle<naga::LocalVariable>) -> Handle<naga::LocalVariable> {
        h
    }
    fn function(&mut self, h: Handle<naga::Function>) -> Handle<naga::Function> {
        h
    }
}

/// Maps handles of the source module's global scope, copying constants on
/// first use.
struct GlobalMapper<'a> {
    maps: &'a mut ModuleMaps,
    target_constants: &'a mut naga::Arena<naga::Constant>,
    source: &'a Module,
}

impl Mapper for GlobalMapper<'_> {
    fn expression(&mut self, h: Handle<Expression>) -> Handle<Expression> {
        self.maps.global_expressions[&h]
    }
    fn ty(&mut self, h: Handle<naga::Type>) -> Handle<naga::Type> {
        self.maps.types[&h]
    }
    fn constant(&mut self, h: Handle<naga::Constant>) -> Handle<naga::Constant> {
        if let Some(&mapped) = self.maps.constants.get(&h) {
            return mapped;
        }
        let constant = &self.source.constants[h];
        let mapped = self.target_constants.append(
            naga::Constant {
                name: constant.name.clone(),
                ty: self.maps.types[&constant.ty],
                init: self.maps.global_expressions[&constant.init],
            },
            self.source.constants.get_span(h),
        );
        self.maps.constants.insert(h, mapped);
        mapped
    }
    fn override_(&mut self, h: Handle<naga::Override>) -> Handle<naga::Override> {
        h
    }
    fn global(&mut self, h: Handle<naga::GlobalVariable>) -> Handle<naga::GlobalVariable> {
        self.maps.globals[&h]
    }
    fn local(&mut self, h: Handle<naga::LocalVariable>) -> Handle<naga::LocalVariable> {
        h
    }
    fn function(&mut self, h: Handle<naga::Function>) -> Handle<naga::Function> {
        self.maps.functions[&h]
    }
}

/// Maps a function's own handles one to one (expressions and locals are
/// copied whole and in order) and global handles through the module maps.
struct FunctionMapper<'a> {
    global: GlobalMapper<'a>,
    exprs: Vec<Handle<Expression>>,
    locals: Vec<Handle<naga::LocalVariable>>,
}

impl Mapper for FunctionMapper<'_> {
    fn expression(&mut self, h: Handle<Expression>) -> Handle<Expression> {
        self.exprs[h.index()]
    }
    fn ty(&mut self, h: Handle<naga::Type>) -> Handle<naga::Type> {
        self.global.ty(h)
    }
    fn constant(&mut self, h: Handle<naga::Constant>) -> Handle<naga::Constant> {
        self.global.constant(h)
    }
    fn override_(&mut self, h: Handle<naga::Override>) -> Handle<naga::Override> {
        h
    }
    fn global(&mut self, h: Handle<naga::GlobalVariable>) -> Handle<naga::GlobalVariable> {
        self.global.global(h)
    }
    fn local(&mut self, h: Handle<naga::LocalVariable>) -> Handle<naga::LocalVariable> {
        self.locals[h.index()]
    }
    fn function(&mut self, h: Handle<naga::Function>) -> Handle<naga::Function> {
        self.global.function(h)
    }
}

fn copy_function(
    function: &naga::Function,
    maps: &mut ModuleMaps,
    target_constants: &mut naga::Arena<naga::Constant>,
    source: &Module,
) -> naga::Function {
    let mut out = naga::Function {
        name: function.name.clone(),
        arguments: function
            .arguments
            .iter()
            .map(|arg| naga::FunctionArgument {
                name: arg.name.clone(),
                ty: maps.types[&arg.ty],
                binding: arg.binding.clone(),
            })
            .collect(),
        result: function.result.as_ref().map(|r| naga::FunctionResult {
            ty: maps.types[&r.ty],
            binding: r.binding.clone(),
        }),
        ..naga::Function::default()
    };
    let mut mapper = FunctionMapper {
        global: GlobalMapper {
            maps,
            target_constants,
            source,
        },
        exprs: Vec::new(),
        locals: Vec::new(),
    };
    // Locals first (expressions name them), their initializers once the
    // expressions they refer to exist.
    for (handle, local) in function.local_variables.iter() {
        let mapped = out.local_variables.append(
            naga::LocalVariable {
                name: local.name.clone(),
                ty: mapper.ty(local.ty),
                init: None,
            },
            function.local_variables.get_span(handle),
        );
        mapper.locals.push(mapped);
    }
    // Expressions refer only to earlier ones, so one pass in order maps all.
    for (handle, expr) in function.expressions.iter() {
        let copied = remap::expression(expr, &mut mapper);
        let mapped = out
            .expressions
            .append(copied, function.expressions.get_span(handle));
        mapper.exprs.push(mapped);
    }
    for (handle, local) in function.local_variables.iter() {
        if let Some(init) = local.init {
            let init = mapper.expression(init);
            let mapped = mapper.local(handle);
            out.local_variables.get_mut(mapped).init = Some(init);
        }
    }
    for (handle, name) in function.named_expressions.iter() {
        out.named_expressions
            .insert(mapper.expression(*handle), name.clone());
    }
    out.body = copy_block(&function.body, &mut mapper);
    out
}

fn copy_block(block: &Block, m: &mut FunctionMapper) -> Block {
    let mut out = Block::new();
    for (statement, &span) in block.span_iter() {
        let copied = match *statement {
            Statement::Emit(ref range) => match range.first_and_last() {
                Some((first, last)) => Statement::Emit(naga::Range::new_from_bounds(
                    m.expression(first),
                    m.expression(last),
                )),
                None => continue,
            },
            Statement::Block(ref inner) => Statement::Block(copy_block(inner, m)),
            Statement::If {
                condition,
                ref accept,
                ref reject,
            } => Statement::If {
                condition: m.expression(condition),
                accept: copy_block(accept, m),
                reject: copy_block(reject, m),
            },
            Statement::Switch {
                selector,
                ref cases,
            } => Statement::Switch {
                selector: m.expression(selector),
                cases: cases
                    .iter()
                    .map(|case| naga::SwitchCase {
                        value: case.value,
                        body: copy_block(&case.body, m),
                        fall_through: case.fall_through,
                    })
                    .collect(),
            },
            Statement::Loop {
                ref body,
                ref continuing,
                break_if,
            } => Statement::Loop {
                body: copy_block(body, m),
                continuing: copy_block(continuing, m),
                break_if: break_if.map(|h| m.expression(h)),
            },
            ref other => match remap::simple_statement(other, m) {
                Some(copied) => copied,
                None => continue,
            },
        };
        out.push(copied, span);
    }
    out
}
