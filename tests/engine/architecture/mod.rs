//! The "Architecture invariant" lines of docs/ARCHITECTURE.md, checked on the source: no import cycle among
//! the engine's modules (at every level of the module tree), `bvh/` names no wgpu, `scene/` never names
//! `render/`, render passes never name each other, and in `game/` only `main.rs` calls into the bench.
//! `scripts/import-graph.sh` prints the graphs these checks read.

mod checker_tests;
mod import_graph;
mod module_tree;

use crate::common::repo_root;
use import_graph::{ImportGraph, list_sites};
use module_tree::{ModulePath, ModuleTree, Target};
use std::collections::BTreeSet;
use std::path::Path;

/// Import circles known today, each to be removed: each line is one circle's modules. Delete a line once its circle is gone (the test then fails until it is deleted, so the list never
/// hides a circle that came back).
const KNOWN_CYCLES: &[&[&str]] = &[];

/// The crate whose source is `src` (e.g. `engine/src`, from the repository root), files named from there.
fn crate_tree(src: &str) -> ModuleTree {
    ModuleTree::load(&repo_root().join(src), Path::new(src)).unwrap_or_else(|e| panic!("{e}"))
}

/// The graph among the children of every module that has children, root first.
fn all_graphs(tree: &ModuleTree) -> Vec<ImportGraph> {
    let parents: BTreeSet<&ModulePath> = tree
        .modules()
        .filter(|m| !tree.children(m).is_empty())
        .collect();
    parents
        .into_iter()
        .map(|p| ImportGraph::among_children(tree, p))
        .collect()
}

/// Every import circle not in `known`, explained, and every `known` entry no longer found.
fn cycle_violations(tree: &ModuleTree, known: &[&[&str]]) -> Vec<String> {
    let known: Vec<BTreeSet<String>> = known
        .iter()
        .map(|c| c.iter().map(|m| m.to_string()).collect())
        .collect();
    let mut found = Vec::new();
    let mut violations = Vec::new();
    for graph in all_graphs(tree) {
        for cycle in graph.cycles() {
            let qualified: BTreeSet<String> = cycle.iter().map(|m| graph.qualified(m)).collect();
            if !known.contains(&qualified) {
                violations.push(format!(
                    "import cycle {qualified:?}: {}",
                    graph.explain(&cycle)
                ));
            }
            found.push(qualified);
        }
    }
    for stale in known.iter().filter(|k| !found.contains(k)) {
        violations.push(format!(
            "the known cycle {stale:?} is gone (or changed): delete its line in KNOWN_CYCLES"
        ));
    }
    violations
}

/// Every place where a module inside `within` names something `forbidden` accepts.
fn forbidden_uses(
    tree: &ModuleTree,
    within: impl Fn(&[String]) -> bool,
    forbidden: impl Fn(&Target) -> bool,
    rule: &str,
) -> Vec<String> {
    tree.uses()
        .into_iter()
        .filter(|u| within(&u.from) && forbidden(&u.target))
        .map(|u| format!("{}: {rule}: names {}", u.site, u.target))
        .collect()
}

fn under(prefix: &'static [&'static str]) -> impl Fn(&[String]) -> bool {
    move |module| module.len() >= prefix.len() && module.iter().zip(prefix).all(|(a, b)| a == b)
}

fn names_internal(prefix: &'static [&'static str]) -> impl Fn(&Target) -> bool {
    move |target| matches!(target, Target::Internal(path) if under(prefix)(path))
}

fn names_external(krate: &'static str) -> impl Fn(&Target) -> bool {
    move |target| matches!(target, Target::External(path) if path.first().is_some_and(|c| c == krate))
}

/// `bvh/` is the CPU side: it never names wgpu (directly or through a re-export).
fn bvh_wgpu_violations(tree: &ModuleTree) -> Vec<String> {
    forbidden_uses(
        tree,
        under(&["bvh"]),
        names_external("wgpu"),
        "bvh/ imports no wgpu",
    )
}

/// The data model never depends on the renderer.
fn scene_render_violations(tree: &ModuleTree) -> Vec<String> {
    forbidden_uses(
        tree,
        under(&["scene"]),
        names_internal(&["render"]),
        "scene/ never imports render/",
    )
}

/// Each child of `render::passes` is one GPU pass: none names another (shared code lives outside `passes`).
/// Vacuous while `render/passes/` does not exist.
fn cross_pass_violations(tree: &ModuleTree) -> Vec<String> {
    let graph = ImportGraph::among_children(tree, &["render".into(), "passes".into()]);
    graph
        .edges
        .iter()
        .map(|((from, to), sites)| {
            format!(
                "pass `{from}` names pass `{to}` (passes never call each other): {}",
                list_sites(sites)
            )
        })
        .collect()
}

fn assert_none(violations: Vec<String>) {
    assert!(
        violations.is_empty(),
        "{} architecture violation(s):\n{}",
        violations.len(),
        violations.join("\n")
    );
}

#[test]
fn engine_modules_import_no_cycle() {
    let tree = crate_tree("engine/src");
    // The graphs, for a reviewer (`--nocapture`, or scripts/import-graph.sh).
    for graph in all_graphs(&tree) {
        let parent = if graph.parent.is_empty() {
            "the engine's top-level modules".to_string()
        } else {
            format!("the children of {}", graph.parent.join("::"))
        };
        println!("imports among {parent}:\n{}", graph.listing());
    }
    assert_none(cycle_violations(&tree, KNOWN_CYCLES));
}

#[test]
fn bvh_imports_no_wgpu() {
    assert_none(bvh_wgpu_violations(&crate_tree("engine/src")));
}

#[test]
fn scene_never_imports_render() {
    assert_none(scene_render_violations(&crate_tree("engine/src")));
}

#[test]
fn render_passes_never_name_each_other() {
    assert_none(cross_pass_violations(&crate_tree("engine/src")));
}

/// In `game/`, the bench is one module tree the CLI calls: only `main.rs` names it.
#[test]
fn only_main_calls_into_the_bench() {
    let tree = crate_tree("game/src");
    assert_none(forbidden_uses(
        &tree,
        |module| !module.is_empty() && !under(&["bench"])(module),
        names_internal(&["bench"]),
        "only main.rs names bench/",
    ));
    assert_none(cycle_violations(&tree, &[]));
}
