//! Kernels specialised before the driver sees them. The engine's kernels carry the features a scene may lack
//! behind pipeline-overridable constants (`MATERIAL_LOBES`, `PATH_AOVS`, `NEXT_EVENT_LIGHT_KINDS`, ...), and
//! wgpu hands the driver every branch those constants switch off: naga substitutes the values but keeps the
//! `if`s, so the driver inlines and optimises the dead code before it finds it dead. On lavapipe that work is
//! most of a run's start-up (the path tracer's pipeline: half a second; the layered BSDF alone, switched off for a
//! scene without sheen or clearcoat, took a sixth of it: docs/BENCHMARKS.md).
//!
//! Here the WGSL is parsed once per module; per pipeline the constants are substituted (naga's
//! `process_overrides`), every `if` whose condition the constants decide is replaced by the branch taken,
//! statements after a `return`, `break` or `continue` are dropped, and whatever is then unreachable goes (naga's
//! `compact`). A condition is decided when it folds from literals, constants, local variables whose stores so far
//! it knows (naga lowers `&&` and `||` to one), and the results of functions that return at once an expression of
//! their arguments and constants (`scene_uses_texture(CORE_TEXTURE_EMISSIVE)`, `next_event_samples(LIGHT_SUN)`).
//! Only statements whose execution the constants rule out are removed, so the kernel computes what the WGSL
//! says (the path tracer's pipeline on lavapipe: 0.09 s, from 0.5 s, images byte-identical). A module that does
//! not parse or validate goes to wgpu as WGSL, which reports the error as before.

use naga::{
    Arena, BinaryOperator, Block, Expression, Function, Handle, Literal, LocalVariable, Module,
    ShaderStage, Statement, UnaryOperator,
};
use std::cell::RefCell;
use std::collections::HashMap;

/// A kernel's WGSL, parsed and validated once.
pub struct ParsedModule {
    module: Module,
    info: naga::valid::ModuleInfo,
}

/// `source` parsed and validated, or `None` where it does not parse or validate (wgpu then reports why).
pub fn parse(source: &str) -> Option<ParsedModule> {
    let module = naga::front::wgsl::parse_str(source).ok()?;
    let info = validator().validate(&module).ok()?;
    Some(ParsedModule { module, info })
}

/// The module of compute entry point `entry` with `constants` substituted and the branches they rule out
/// removed; `None` where naga cannot substitute them (an unknown name) or the result does not validate.
pub fn specialize(parsed: &ParsedModule, entry: &str, constants: &[(&str, f64)]) -> Option<Module> {
    let mut values = naga::back::PipelineConstants::default();
    for (name, value) in constants {
        values.insert((*name).to_owned(), *value);
    }
    let (module, _) = naga::back::pipeline_constants::process_overrides(
        &parsed.module,
        &parsed.info,
        Some((ShaderStage::Compute, entry)),
        &values,
    )
    .ok()?;
    let mut module = module.into_owned();
    remove_dead_branches(&mut module);
    naga::compact::compact(&mut module, naga::compact::KeepUnused::No);
    validator().validate(&module).ok()?;
    Some(module)
}

fn validator() -> naga::valid::Validator {
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
}

/// Removes, in every function and entry point, the branches the module's constants rule out. Functions are
/// visited in arena order, callees first (naga's WGSL front end orders them so), so that a call's result can be
/// folded from its callee's already simplified body.
fn remove_dead_branches(module: &mut Module) {
    let handles: Vec<Handle<Function>> = module.functions.iter().map(|(h, _)| h).collect();
    for handle in handles {
        let mut body = std::mem::take(&mut module.functions[handle].body);
        prune_function(module, &module.functions[handle], &mut body);
        let function = &mut module.functions[handle];
        function.body = body;
        forget_names(function);
    }
    for index in 0..module.entry_points.len() {
        let mut body = std::mem::take(&mut module.entry_points[index].function.body);
        prune_function(module, &module.entry_points[index].function, &mut body);
        let function = &mut module.entry_points[index].function;
        function.body = body;
        forget_names(function);
    }
}

/// Drops the names of `let` values: `compact` keeps every named expression, and one in a removed branch may
/// name the result of a call whose callee is gone. The names only label the driver's code.
fn forget_names(function: &mut Function) {
    function.named_expressions.clear();
}

/// Prunes `body` of `function` (taken out of it): local variables start at their initial values (WGSL's zero
/// where there is none).
fn prune_function(module: &Module, function: &Function, body: &mut Block) {
    let folder = Folder::new(module, function, body);
    let mut known = HashMap::new();
    for (handle, local) in function.local_variables.iter() {
        let value = match local.init {
            Some(init) => folder.fold(init),
            None => zero_value(&module.types[local.ty].inner),
        };
        if let Some(value) = value {
            known.insert(handle, value);
        }
    }
    prune_block(body, &folder, &mut known);
}

/// Local variables' values where the statements so far decide them (a forward pass over straight-line code).
type KnownLocals = HashMap<Handle<LocalVariable>, Value>;

/// Replaces each `if` the folder decides by the statements of the branch taken (their expressions' scope
/// widens, which no valid use can notice) and drops what follows a statement that leaves the block. `known`
/// holds the local variables' values on entry and is left with those on exit. Naga lowers `a && b` and `a || b`
/// to a local variable stored in branches and loaded by the `if` that tests it, so the folder follows stores of
/// values it knows into the loads emitted after them.
fn prune_block(block: &mut Block, folder: &Folder, known: &mut KnownLocals) {
    let mut out = Block::with_capacity(block.len());
    for (statement, span) in std::mem::take(block).span_into_iter() {
        match statement {
            Statement::Emit(ref range) => {
                for expression in range.clone() {
                    if let Expression::Load { pointer } = folder.expressions[expression]
                        && let Expression::LocalVariable(local) = folder.expressions[pointer]
                        && let Some(value) = known.get(&local)
                    {
                        folder.loads.borrow_mut().insert(expression, *value);
                    }
                }
                out.push(statement, span);
            }
            Statement::Store { pointer, value } => {
                if let Some(local) = folder.root_local(pointer) {
                    let whole = matches!(folder.expressions[pointer], Expression::LocalVariable(_));
                    match folder.fold(value).filter(|_| whole) {
                        Some(v) => known.insert(local, v),
                        None => known.remove(&local),
                    };
                }
                out.push(statement, span);
            }
            Statement::If {
                condition,
                mut accept,
                mut reject,
            } => match folder.fold(condition) {
                Some(Value::Bool(taken)) => {
                    let mut branch = if taken { accept } else { reject };
                    prune_block(&mut branch, folder, known);
                    out.append(&mut branch);
                }
                _ => {
                    let mut after_reject = known.clone();
                    prune_block(&mut accept, folder, known);
                    prune_block(&mut reject, folder, &mut after_reject);
                    known.retain(|local, value| after_reject.get(local) == Some(value));
                    out.push(
                        Statement::If {
                            condition,
                            accept,
                            reject,
                        },
                        span,
                    );
                }
            },
            Statement::Block(mut inner) => {
                prune_block(&mut inner, folder, known);
                out.push(Statement::Block(inner), span);
            }
            Statement::Switch {
                selector,
                mut cases,
            } => {
                // Cases may fall through into each other: each starts from what no case changes.
                for case in &cases {
                    forget_stored(&case.body, folder, known);
                }
                for case in &mut cases {
                    prune_block(&mut case.body, folder, &mut known.clone());
                }
                out.push(Statement::Switch { selector, cases }, span);
            }
            Statement::Loop {
                mut body,
                mut continuing,
                break_if,
            } => {
                // Later iterations see the loop's own stores: the body starts from what the loop never changes.
                forget_stored(&body, folder, known);
                forget_stored(&continuing, folder, known);
                prune_block(&mut body, folder, &mut known.clone());
                prune_block(&mut continuing, folder, &mut known.clone());
                out.push(
                    Statement::Loop {
                        body,
                        continuing,
                        break_if,
                    },
                    span,
                );
            }
            other => {
                forget_written(&other, folder, known);
                out.push(other, span);
            }
        }
        if out.last().is_some_and(leaves_block) {
            break;
        }
    }
    *block = out;
}

/// Forgets the local variables `block` stores to (anywhere in it, nested blocks included), or everything where
/// it holds a statement that may write memory otherwise.
fn forget_stored(block: &Block, folder: &Folder, known: &mut KnownLocals) {
    for_each_statement(block, &mut |statement| {
        forget_written(statement, folder, known)
    });
}

/// Forgets what `statement` itself may write: the local variable a `Store` writes into, those whose pointers a
/// `Call` passes (a callee can write a local variable only through one), everything for any other statement
/// that may write memory.
fn forget_written(statement: &Statement, folder: &Folder, known: &mut KnownLocals) {
    match statement {
        Statement::Store { pointer, .. } => {
            if let Some(local) = folder.root_local(*pointer) {
                known.remove(&local);
            }
        }
        Statement::Call { arguments, .. } => {
            for argument in arguments {
                if let Some(local) = folder.root_local(*argument) {
                    known.remove(&local);
                }
            }
        }
        statement if !writes_no_memory(statement) => known.clear(),
        _ => {}
    }
}

/// Whether `statement` writes no memory itself (a `Store` or a `Call` may; control flow holds statements that
/// may, and `for_each_statement` visits those).
fn writes_no_memory(statement: &Statement) -> bool {
    matches!(
        statement,
        Statement::Emit(_)
            | Statement::Block(_)
            | Statement::If { .. }
            | Statement::Switch { .. }
            | Statement::Loop { .. }
            | Statement::Return { .. }
            | Statement::Break
            | Statement::Continue
            | Statement::Kill
            | Statement::ControlBarrier(_)
            | Statement::MemoryBarrier(_)
    )
}

/// Calls `visit` with every statement of `block`, those nested in blocks, branches, cases and loops included.
fn for_each_statement(block: &Block, visit: &mut impl FnMut(&Statement)) {
    for statement in block.iter() {
        visit(statement);
        match statement {
            Statement::Block(inner) => for_each_statement(inner, visit),
            Statement::If { accept, reject, .. } => {
                for_each_statement(accept, visit);
                for_each_statement(reject, visit);
            }
            Statement::Switch { cases, .. } => {
                for case in cases {
                    for_each_statement(&case.body, visit);
                }
            }
            Statement::Loop {
                body, continuing, ..
            } => {
                for_each_statement(body, visit);
                for_each_statement(continuing, visit);
            }
            _ => {}
        }
    }
}

/// Whether nothing after `statement` in its block can run.
fn leaves_block(statement: &Statement) -> bool {
    matches!(
        statement,
        Statement::Return { .. } | Statement::Break | Statement::Continue | Statement::Kill
    )
}

/// WGSL's initial value of a local variable of this type, where the folder tracks the type.
fn zero_value(ty: &naga::TypeInner) -> Option<Value> {
    match *ty {
        naga::TypeInner::Scalar(naga::Scalar {
            kind: naga::ScalarKind::Bool,
            ..
        }) => Some(Value::Bool(false)),
        naga::TypeInner::Scalar(naga::Scalar::U32) => Some(Value::U32(0)),
        naga::TypeInner::Scalar(naga::Scalar::I32) => Some(Value::I32(0)),
        _ => None,
    }
}

/// A scalar the folder knows at compile time.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Value {
    Bool(bool),
    U32(u32),
    I32(i32),
}

/// The call statements of a function by their result expressions: callee and arguments.
type Calls = HashMap<Handle<Expression>, (Handle<Function>, Vec<Handle<Expression>>)>;

/// Calls nested deeper than this are not followed (the engine's deepest fold is two).
const MOST_NESTED_CALLS: u32 = 8;

/// Folds expressions of one function: literals, constants, arguments where the caller knows them, and calls to
/// functions that return at once.
struct Folder<'a> {
    module: &'a Module,
    expressions: &'a Arena<Expression>,
    /// The call statement that produces each `CallResult`: callee and arguments.
    calls: Calls,
    /// The values of the function's arguments, where a caller knows them.
    arguments: Vec<Option<Value>>,
    /// The values of loads of local variables, as known where they were emitted (filled in by `prune_block`).
    loads: RefCell<HashMap<Handle<Expression>, Value>>,
    depth: u32,
}

impl<'a> Folder<'a> {
    fn new(module: &'a Module, function: &'a Function, body: &Block) -> Self {
        Self {
            module,
            expressions: &function.expressions,
            calls: collect_calls(body),
            arguments: vec![None; function.arguments.len()],
            loads: RefCell::default(),
            depth: 0,
        }
    }

    /// The local variable a pointer expression points into, if any.
    fn root_local(&self, pointer: Handle<Expression>) -> Option<Handle<LocalVariable>> {
        match self.expressions[pointer] {
            Expression::LocalVariable(local) => Some(local),
            Expression::Access { base, .. } | Expression::AccessIndex { base, .. } => {
                self.root_local(base)
            }
            _ => None,
        }
    }

    fn fold(&self, expression: Handle<Expression>) -> Option<Value> {
        match self.expressions[expression] {
            Expression::Literal(literal) => literal_value(literal),
            Expression::Constant(constant) => {
                match self.module.global_expressions[self.module.constants[constant].init] {
                    Expression::Literal(literal) => literal_value(literal),
                    _ => None,
                }
            }
            Expression::FunctionArgument(index) => {
                self.arguments.get(index as usize).copied().flatten()
            }
            Expression::Unary { op, expr } => match (op, self.fold(expr)?) {
                (UnaryOperator::LogicalNot, Value::Bool(b)) => Some(Value::Bool(!b)),
                (UnaryOperator::BitwiseNot, Value::U32(v)) => Some(Value::U32(!v)),
                (UnaryOperator::BitwiseNot, Value::I32(v)) => Some(Value::I32(!v)),
                (UnaryOperator::Negate, Value::I32(v)) => Some(Value::I32(v.wrapping_neg())),
                _ => None,
            },
            Expression::Binary { op, left, right } => self.fold_binary(op, left, right),
            Expression::Select {
                condition,
                accept,
                reject,
            } => match self.fold(condition)? {
                Value::Bool(true) => self.fold(accept),
                Value::Bool(false) => self.fold(reject),
                _ => None,
            },
            Expression::CallResult(_) => self.fold_call(expression),
            Expression::Load { .. } => self.loads.borrow().get(&expression).copied(),
            _ => None,
        }
    }

    fn fold_binary(
        &self,
        op: BinaryOperator,
        left: Handle<Expression>,
        right: Handle<Expression>,
    ) -> Option<Value> {
        use BinaryOperator as B;
        let (l, r) = (self.fold(left), self.fold(right));
        // Either side decides `&&` and `||` (naga's expressions have no side effects).
        match op {
            B::LogicalAnd if l == Some(Value::Bool(false)) || r == Some(Value::Bool(false)) => {
                return Some(Value::Bool(false));
            }
            B::LogicalOr if l == Some(Value::Bool(true)) || r == Some(Value::Bool(true)) => {
                return Some(Value::Bool(true));
            }
            _ => {}
        }
        let (l, r) = (l?, r?);
        Some(match (op, l, r) {
            (B::LogicalAnd, Value::Bool(a), Value::Bool(b)) => Value::Bool(a && b),
            (B::LogicalOr, Value::Bool(a), Value::Bool(b)) => Value::Bool(a || b),
            (B::Equal, a, b) => Value::Bool(a == b),
            (B::NotEqual, a, b) => Value::Bool(a != b),
            (B::Less, Value::U32(a), Value::U32(b)) => Value::Bool(a < b),
            (B::LessEqual, Value::U32(a), Value::U32(b)) => Value::Bool(a <= b),
            (B::Greater, Value::U32(a), Value::U32(b)) => Value::Bool(a > b),
            (B::GreaterEqual, Value::U32(a), Value::U32(b)) => Value::Bool(a >= b),
            (B::Less, Value::I32(a), Value::I32(b)) => Value::Bool(a < b),
            (B::LessEqual, Value::I32(a), Value::I32(b)) => Value::Bool(a <= b),
            (B::Greater, Value::I32(a), Value::I32(b)) => Value::Bool(a > b),
            (B::GreaterEqual, Value::I32(a), Value::I32(b)) => Value::Bool(a >= b),
            (B::And, Value::U32(a), Value::U32(b)) => Value::U32(a & b),
            (B::InclusiveOr, Value::U32(a), Value::U32(b)) => Value::U32(a | b),
            (B::ExclusiveOr, Value::U32(a), Value::U32(b)) => Value::U32(a ^ b),
            (B::And, Value::Bool(a), Value::Bool(b)) => Value::Bool(a & b),
            (B::InclusiveOr, Value::Bool(a), Value::Bool(b)) => Value::Bool(a | b),
            // WGSL takes a shift's amount modulo the bit width at run time, as wrapping shifts do.
            (B::ShiftLeft, Value::U32(a), Value::U32(b)) => Value::U32(a.wrapping_shl(b)),
            (B::ShiftRight, Value::U32(a), Value::U32(b)) => Value::U32(a.wrapping_shr(b)),
            (B::Add, Value::U32(a), Value::U32(b)) => Value::U32(a.wrapping_add(b)),
            (B::Subtract, Value::U32(a), Value::U32(b)) => Value::U32(a.wrapping_sub(b)),
            (B::Multiply, Value::U32(a), Value::U32(b)) => Value::U32(a.wrapping_mul(b)),
            _ => return None,
        })
    }

    /// The value a call returns, where its callee returns at once an expression this folds.
    fn fold_call(&self, result: Handle<Expression>) -> Option<Value> {
        if self.depth >= MOST_NESTED_CALLS {
            return None;
        }
        let (callee, arguments) = self.calls.get(&result)?;
        let function = &self.module.functions[*callee];
        let (value, calls) = immediate_return(&function.body)?;
        let inner = Folder {
            module: self.module,
            expressions: &function.expressions,
            calls,
            arguments: arguments.iter().map(|a| self.fold(*a)).collect(),
            loads: RefCell::default(),
            depth: self.depth + 1,
        };
        inner.fold(value)
    }
}

/// The expression a function returns before any other statement (but the evaluation of expressions and calls),
/// with the calls before it (the only ones its value can depend on).
fn immediate_return(body: &Block) -> Option<(Handle<Expression>, Calls)> {
    let mut calls = Calls::new();
    for statement in body.iter() {
        match statement {
            Statement::Emit(_) => {}
            Statement::Call {
                function,
                arguments,
                result,
            } => {
                if let Some(result) = result {
                    calls.insert(*result, (*function, arguments.clone()));
                }
            }
            Statement::Return { value } => return value.map(|value| (value, calls)),
            _ => return None,
        }
    }
    None
}

/// Every call statement in `block` with a result, by its result expression.
fn collect_calls(block: &Block) -> Calls {
    let mut calls = Calls::new();
    for_each_statement(block, &mut |statement| {
        if let Statement::Call {
            function,
            arguments,
            result: Some(result),
        } = statement
        {
            calls.insert(*result, (*function, arguments.clone()));
        }
    });
    calls
}

fn literal_value(literal: Literal) -> Option<Value> {
    match literal {
        Literal::Bool(b) => Some(Value::Bool(b)),
        Literal::U32(v) => Some(Value::U32(v)),
        Literal::I32(v) => Some(Value::I32(v)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KERNEL: &str = r#"
override FEATURES: u32 = 3u;
override DEBUG: bool = true;
@group(0) @binding(0) var<storage, read_write> out: array<u32>;

fn uses(feature: u32) -> bool {
    return (FEATURES & (1u << feature)) != 0u;
}

fn expensive(x: u32) -> u32 {
    var v = x;
    for (var i = 0u; i < 8u; i++) { v = v * 1664525u + 1013904223u; }
    return v;
}

fn cheap(x: u32) -> u32 {
    if !uses(0u) { return x; }
    return x + 1u;
}

@compute @workgroup_size(1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    var v = id.x;
    if uses(1u) && v > 2u {
        v = expensive(v);
    }
    if DEBUG && uses(0u) { out[1] = 7u; }
    out[0] = cheap(v);
}
"#;

    fn names(module: &Module) -> Vec<String> {
        let mut names: Vec<String> = module
            .functions
            .iter()
            .filter_map(|(_, f)| f.name.clone())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn branches_the_constants_rule_out_are_removed() {
        let parsed = parse(KERNEL).expect("the test kernel parses");
        // Feature 1 off: `expensive` is never called, so it goes.
        let module = specialize(&parsed, "main", &[("FEATURES", 1.0)]).unwrap();
        assert!(!names(&module).contains(&"expensive".to_owned()));
        // Feature 1 on: the branch depends on `v` too and stays.
        let module = specialize(&parsed, "main", &[("FEATURES", 2.0)]).unwrap();
        assert!(names(&module).contains(&"expensive".to_owned()));
    }

    #[test]
    fn folds_calls_with_constant_arguments_and_unreachable_statements() {
        let parsed = parse(KERNEL).unwrap();
        let module = specialize(&parsed, "main", &[("FEATURES", 0.0), ("DEBUG", 1.0)]).unwrap();
        // `cheap` returns at once without feature 0; the store under `DEBUG && uses(0u)` is gone.
        let cheap = module
            .functions
            .iter()
            .find(|(_, f)| f.name.as_deref() == Some("cheap"))
            .map(|(_, f)| f)
            .unwrap();
        let returns = cheap
            .body
            .iter()
            .filter(|s| matches!(s, Statement::Return { .. }))
            .count();
        assert_eq!(returns, 1, "the statements after the first return are gone");
        let entry = &module.entry_points[0].function;
        let stores = count_stores(&entry.body, &entry.expressions);
        assert_eq!(stores, 1, "only out[0] is written");
        let module = specialize(&parsed, "main", &[("FEATURES", 1.0), ("DEBUG", 1.0)]).unwrap();
        let entry = &module.entry_points[0].function;
        assert_eq!(count_stores(&entry.body, &entry.expressions), 2);
    }

    /// Stores to the storage buffer (not to local variables).
    fn count_stores(block: &Block, expressions: &Arena<Expression>) -> usize {
        block
            .iter()
            .map(|s| match s {
                Statement::Store { pointer, .. } => match expressions[*pointer] {
                    Expression::AccessIndex { base, .. } => {
                        matches!(expressions[base], Expression::GlobalVariable(_)) as usize
                    }
                    _ => 0,
                },
                Statement::If { accept, reject, .. } => {
                    count_stores(accept, expressions) + count_stores(reject, expressions)
                }
                Statement::Block(b) => count_stores(b, expressions),
                Statement::Loop { body, .. } => count_stores(body, expressions),
                _ => 0,
            })
            .sum()
    }

    #[test]
    fn unknown_constants_and_bad_sources_fall_back() {
        assert!(parse("fn broken( {").is_none());
        let parsed = parse(KERNEL).unwrap();
        assert!(specialize(&parsed, "main", &[("NO_SUCH_CONSTANT", 1.0)]).is_none());
    }
}
