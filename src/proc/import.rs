//! Importing one module into another at IR level: types, constants, global
//! variables and functions are copied with their handles remapped.
//!
//! - [`import`]: the toolchain's own WGSL (`shaders/`) into a user's module,
//!   its resources moved to the bind group the rewrite chose;
//! - [`import_vertex_stage`]: a separate vertex module (`--vertex FILE`)
//!   into a fragment-only one, its resources the same as the fragment
//!   module's where they share a binding.

use std::collections::HashMap;

use naga::{Block, Expression, Handle, Module};

use crate::proc::remap::{self, Mapper};

/// What an import added to the target module, by name.
#[derive(Debug, Default)]
pub struct Imported {
    pub functions: HashMap<String, Handle<naga::Function>>,
    pub globals: HashMap<String, Handle<naga::GlobalVariable>>,
    pub types: HashMap<String, Handle<naga::Type>>,
}

/// Copies everything of `source` except its entry points into `target`,
/// putting its resource bindings in `group`, `first_binding` after their
/// own numbers.
pub fn import(
    target: &mut Module,
    source: &Module,
    group: u32,
    first_binding: u32,
) -> Result<Imported, String> {
    let mut maps = ModuleMaps {
        keep_spans: true,
        ..ModuleMaps::default()
    };
    copy_module(
        target,
        source,
        &mut maps,
        Placing::Group(group, first_binding),
    )
}

/// Copies the vertex entry point `entry` of `source`, with everything it
/// needs, into `target` (a fragment-only module), and returns its index
/// among `target`'s entry points. A resource at a (group, binding) `target`
/// also declares is the same resource and must have the same type and
/// address space. Spans are dropped: they point into the other file.
pub fn import_vertex_stage(
    target: &mut Module,
    source: &Module,
    entry: usize,
) -> Result<usize, String> {
    if !source.overrides.is_empty() {
        return Err("the vertex module declares pipeline overrides, which cannot be merged into the fragment module yet".into());
    }
    let entry = &source.entry_points[entry];
    if target.entry_points.iter().any(|ep| ep.name == entry.name) {
        return Err(format!(
            "both modules have an entry point named `{}`",
            entry.name
        ));
    }
    let mut maps = ModuleMaps::default();
    copy_module(target, source, &mut maps, Placing::Merge)?;
    let function = copy_function(&entry.function, &mut maps, &mut target.constants, source);
    target.entry_points.push(naga::EntryPoint {
        function,
        ..entry.clone()
    });
    Ok(target.entry_points.len() - 1)
}

/// Whether two types of one arena lay out alike, whatever their names: a
/// vertex module and a fragment module declare the same uniform struct,
/// composed modules under decorated names.
fn same_layout(
    types: &naga::UniqueArena<naga::Type>,
    a: Handle<naga::Type>,
    b: Handle<naga::Type>,
) -> bool {
    use naga::TypeInner as T;
    if a == b {
        return true;
    }
    match (&types[a].inner, &types[b].inner) {
        (
            T::Struct {
                members: ma,
                span: sa,
            },
            T::Struct {
                members: mb,
                span: sb,
            },
        ) => {
            sa == sb
                && ma.len() == mb.len()
                && ma
                    .iter()
                    .zip(mb)
                    .all(|(x, y)| x.offset == y.offset && same_layout(types, x.ty, y.ty))
        }
        (
            T::Array {
                base: ba,
                size: za,
                stride: ta,
            },
            T::Array {
                base: bb,
                size: zb,
                stride: tb,
            },
        ) => za == zb && ta == tb && same_layout(types, *ba, *bb),
        (x, y) => x == y,
    }
}

/// Where the copied resources go.
enum Placing {
    /// Every binding into this group, at its own binding number plus the
    /// second.
    Group(u32, u32),
    /// At their own group and binding, shared with the target's resource
    /// there.
    Merge,
}

fn copy_module(
    target: &mut Module,
    source: &Module,
    maps: &mut ModuleMaps,
    placing: Placing,
) -> Result<Imported, String> {
    let mut imported = Imported::default();

    // Types come in dependency order in a UniqueArena.
    for (handle, ty) in source.types.iter() {
        let inner = remap::type_inner(&ty.inner, &mut TypeOnly(&maps.types));
        let mapped = target.types.insert(
            naga::Type {
                name: ty.name.clone(),
                inner,
            },
            maps.span(source.types.get_span(handle)),
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
            maps: &mut *maps,
            target_constants: &mut target.constants,
            source,
        };
        let copied = remap::expression(expr, &mut mapper);
        let span = mapper.maps.span(source.global_expressions.get_span(handle));
        let mapped = target.global_expressions.append(copied, span);
        maps.global_expressions.insert(handle, mapped);
    }

    for (handle, global) in source.global_variables.iter() {
        let ty = maps.types[&global.ty];
        let init = global.init.map(|h| maps.global_expressions[&h]);
        let binding = match (&placing, &global.binding) {
            (Placing::Group(group, first), Some(b)) => Some(naga::ResourceBinding {
                group: *group,
                binding: first + b.binding,
            }),
            (Placing::Merge, Some(b)) => {
                let shared = target
                    .global_variables
                    .iter()
                    .find(|(_, g)| g.binding.as_ref() == Some(b));
                if let Some((existing, g)) = shared {
                    if !same_layout(&target.types, g.ty, ty) || g.space != global.space {
                        return Err(format!(
                            "group {} binding {} is `{}` in the vertex module and `{}` in the fragment module, of different types",
                            b.group,
                            b.binding,
                            global.name.as_deref().unwrap_or("?"),
                            g.name.as_deref().unwrap_or("?")
                        ));
                    }
                    maps.globals.insert(handle, existing);
                    continue;
                }
                Some(*b)
            }
            (_, None) => None,
        };
        let mapped = target.global_variables.append(
            naga::GlobalVariable {
                name: global.name.clone(),
                space: global.space,
                binding,
                ty,
                init,
                memory_decorations: global.memory_decorations,
            },
            maps.span(source.global_variables.get_span(handle)),
        );
        maps.globals.insert(handle, mapped);
        if let Some(name) = &global.name {
            imported.globals.insert(name.clone(), mapped);
        }
    }

    // Functions in arena order: a function only calls earlier ones.
    for (handle, function) in source.functions.iter() {
        let copied = copy_function(function, maps, &mut target.constants, source);
        let span = maps.span(source.functions.get_span(handle));
        let mapped = target.functions.append(copied, span);
        maps.functions.insert(handle, mapped);
        if let Some(name) = &function.name {
            imported.functions.insert(name.clone(), mapped);
        }
    }
    Ok(imported)
}

#[derive(Default)]
struct ModuleMaps {
    /// Whether the copies keep the source's spans (they point into the
    /// source's file).
    keep_spans: bool,
    types: HashMap<Handle<naga::Type>, Handle<naga::Type>>,
    constants: HashMap<Handle<naga::Constant>, Handle<naga::Constant>>,
    global_expressions: HashMap<Handle<Expression>, Handle<Expression>>,
    globals: HashMap<Handle<naga::GlobalVariable>, Handle<naga::GlobalVariable>>,
    functions: HashMap<Handle<naga::Function>, Handle<naga::Function>>,
}

impl ModuleMaps {
    fn span(&self, span: naga::Span) -> naga::Span {
        if self.keep_spans {
            span
        } else {
            naga::Span::UNDEFINED
        }
    }
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
            self.maps.span(self.source.constants.get_span(h)),
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
    let keep = maps.keep_spans;
    let span = |s: naga::Span| if keep { s } else { naga::Span::UNDEFINED };
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
            span(function.local_variables.get_span(handle)),
        );
        mapper.locals.push(mapped);
    }
    // Expressions refer only to earlier ones, so one pass in order maps all.
    for (handle, expr) in function.expressions.iter() {
        let copied = remap::expression(expr, &mut mapper);
        let mapped = out
            .expressions
            .append(copied, span(function.expressions.get_span(handle)));
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
    let keep_spans = m.global.maps.keep_spans;
    remap::block(block, m, keep_spans, &mut |_, _, _| false)
}
