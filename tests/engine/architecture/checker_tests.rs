//! The checker itself on synthetic crates: it must catch what it claims to (circles through `crate::`,
//! `super::`, re-exports and macro arguments; cross-pass names; wgpu in bvh/; render/ from scene/) and not
//! be fooled by comments, strings or a pass's own submodules.

use super::import_graph::ImportGraph;
use super::module_tree::{ModuleTree, Target};
use super::{
    bvh_wgpu_violations, cross_pass_violations, cycle_violations, scene_render_violations,
};
use std::path::PathBuf;

fn tree(files: &[(&str, &str)]) -> ModuleTree {
    let sources: Vec<(PathBuf, String)> = files
        .iter()
        .map(|(path, text)| (PathBuf::from(path), text.to_string()))
        .collect();
    ModuleTree::from_sources(&sources).unwrap_or_else(|e| panic!("{e}"))
}

fn edges(tree: &ModuleTree, parent: &[&str]) -> Vec<(String, String)> {
    let parent: Vec<String> = parent.iter().map(|s| s.to_string()).collect();
    ImportGraph::among_children(tree, &parent)
        .edges
        .into_keys()
        .collect()
}

fn edge(from: &str, to: &str) -> (String, String) {
    (from.into(), to.into())
}

#[test]
fn a_two_module_circle_is_reported_with_its_files_and_lines() {
    let t = tree(&[
        ("lib.rs", "mod a;\nmod b;\n"),
        ("a/mod.rs", "mod inner;\n"),
        ("a/inner.rs", "\nuse crate::b::B;\npub struct A;\n"),
        (
            "b.rs",
            "pub struct B;\npub fn f() -> crate::a::inner::A {\n    todo!()\n}\n",
        ),
    ]);
    let violations = cycle_violations(&t, &[]);
    assert_eq!(violations.len(), 1, "{violations:?}");
    let report = &violations[0];
    assert!(report.contains("a -> b -> a"), "{report}");
    assert!(report.contains("a/inner.rs:2"), "{report}");
    assert!(report.contains("b.rs:2"), "{report}");
}

#[test]
fn a_three_module_circle_is_walked_in_order() {
    let t = tree(&[
        ("lib.rs", "mod a; mod b; mod c;"),
        ("a.rs", "use crate::b::x;"),
        ("b.rs", "pub fn x() { crate::c::y() }"),
        ("c.rs", "pub fn y() { let _ = crate::a::Z; }"),
    ]);
    let violations = cycle_violations(&t, &[]);
    assert_eq!(violations.len(), 1, "{violations:?}");
    assert!(violations[0].contains("a -> b -> c -> a"), "{violations:?}");
}

#[test]
fn super_paths_and_reexports_resolve_to_the_sibling_that_defines_the_item() {
    let t = tree(&[
        ("lib.rs", "pub mod render;"),
        (
            "render/mod.rs",
            "mod settings;\nmod tracer;\nmod denoise;\npub use settings::Settings;\nuse denoise::Denoiser;\n",
        ),
        (
            "render/settings.rs",
            "pub struct Settings(super::tracer::Bind);",
        ),
        ("render/tracer.rs", "use super::Settings;\npub struct Bind;"),
        // A private `use` in the parent is reachable from its children too.
        (
            "render/denoise.rs",
            "pub struct Denoiser;\nfn f(_: super::Denoiser) {}",
        ),
    ]);
    assert_eq!(
        edges(&t, &["render"]),
        [edge("settings", "tracer"), edge("tracer", "settings")]
    );
    let violations = cycle_violations(&t, &[]);
    assert!(
        violations.len() == 1 && violations[0].contains("render::settings -> render::tracer"),
        "{violations:?}"
    );
    assert!(
        cycle_violations(&t, &[&["render::settings", "render::tracer"]]).is_empty(),
        "a known circle is accepted"
    );
}

#[test]
fn a_known_cycle_that_is_gone_must_be_deleted() {
    let t = tree(&[
        ("lib.rs", "mod a; mod b;"),
        ("a.rs", "use crate::b::B;"),
        ("b.rs", ""),
    ]);
    let violations = cycle_violations(&t, &[&["a", "b"]]);
    assert!(
        violations.len() == 1 && violations[0].contains("delete its line"),
        "{violations:?}"
    );
}

#[test]
fn macro_arguments_count_and_comments_and_strings_do_not() {
    let t = tree(&[
        ("lib.rs", "mod a; mod b; mod c;"),
        (
            "a.rs",
            "fn f() { tracing::warn!(\"{}\", crate::b::N); assert_eq!(crate::c::f(), ()); }",
        ),
        (
            "b.rs",
            "// crate::a::X\n/// [`crate::a::X`]\npub const N: u32 = 1;\nconst S: &str = \"crate::a::X\";\nconst R: &str = r#\"crate::a::X\"#;\n",
        ),
        ("c.rs", "pub fn f() {}"),
    ]);
    assert_eq!(edges(&t, &[]), [edge("a", "b"), edge("a", "c")]);
}

#[test]
fn inline_modules_resolve_super_from_where_they_are() {
    let t = tree(&[
        ("lib.rs", "mod a; mod b;"),
        // `super` inside `mod tests` is `a`, not the root: no edge; `super::super::b` is.
        (
            "a.rs",
            "fn g() {}\n#[cfg(test)]\nmod tests { use super::g; fn h() { super::super::b::f() } }",
        ),
        ("b.rs", "pub fn f() {}"),
    ]);
    assert_eq!(edges(&t, &[]), [edge("a", "b")]);
}

#[test]
fn passes_naming_each_other_are_caught_and_their_own_submodules_are_not() {
    let shared = [
        ("lib.rs", "pub mod render;"),
        ("render/mod.rs", "pub mod passes; pub mod gpu_util;"),
        ("render/gpu_util.rs", "pub fn layout() {}"),
        (
            "render/passes/mod.rs",
            "pub mod trace; pub mod tonemap; pub mod denoise;",
        ),
        ("render/passes/tonemap.rs", "pub struct Params;"),
        (
            "render/passes/denoise/mod.rs",
            "mod kernel; pub use kernel::K;",
        ),
        ("render/passes/denoise/kernel.rs", "pub struct K;"),
    ];
    let clean = tree(
        &[
            &shared[..],
            &[(
                "render/passes/trace/mod.rs",
                "mod stack;\nuse super::super::gpu_util::layout;\nuse stack::Stack;",
            )],
            &[("render/passes/trace/stack.rs", "pub struct Stack;")],
        ]
        .concat(),
    );
    assert_eq!(cross_pass_violations(&clean), Vec::<String>::new());

    let crossing = tree(
        &[
            &shared[..],
            &[(
                "render/passes/trace/mod.rs",
                "mod stack;\nuse super::tonemap::Params;",
            )],
            &[(
                "render/passes/trace/stack.rs",
                "fn f(_: crate::render::passes::denoise::K) {}",
            )],
        ]
        .concat(),
    );
    let violations = cross_pass_violations(&crossing);
    assert_eq!(violations.len(), 2, "{violations:?}");
    assert!(
        violations[0].contains("`trace` names pass `denoise`")
            && violations[0].contains("render/passes/trace/stack.rs:1"),
        "{violations:?}"
    );
    assert!(
        violations[1].contains("`trace` names pass `tonemap`")
            && violations[1].contains("render/passes/trace/mod.rs:2"),
        "{violations:?}"
    );

    let no_passes = tree(&[("lib.rs", "pub mod render;"), ("render/mod.rs", "")]);
    assert!(
        cross_pass_violations(&no_passes).is_empty(),
        "vacuous without passes"
    );
}

#[test]
fn wgpu_in_bvh_is_caught_directly_and_through_a_reexport() {
    let gpu = ("gpu/mod.rs", "pub use wgpu::DeviceType;");
    let direct = tree(&[
        ("lib.rs", "mod bvh; mod gpu;"),
        gpu,
        ("bvh/mod.rs", "use wgpu::Buffer;"),
    ]);
    let violations = bvh_wgpu_violations(&direct);
    assert!(
        violations.len() == 1 && violations[0].contains("bvh/mod.rs:1"),
        "{violations:?}"
    );
    let through = tree(&[
        ("lib.rs", "mod bvh; mod gpu;"),
        gpu,
        ("bvh/mod.rs", "mod wide;"),
        (
            "bvh/wide.rs",
            "fn f(_: crate::gpu::DeviceType) {}\nfn g(_: ::wgpu::Buffer) {}",
        ),
    ]);
    assert_eq!(bvh_wgpu_violations(&through).len(), 2);
    let clean = tree(&[
        ("lib.rs", "mod bvh; mod gpu;"),
        gpu,
        (
            "bvh/mod.rs",
            "// wgpu::Buffer is the GPU's\nuse glam::Vec3;",
        ),
    ]);
    assert!(bvh_wgpu_violations(&clean).is_empty());
}

#[test]
fn scene_naming_render_is_caught() {
    let t = tree(&[
        ("lib.rs", "mod scene; mod render;"),
        ("render/mod.rs", "pub struct Renderer;"),
        ("scene/mod.rs", "mod spawn;"),
        (
            "scene/spawn.rs",
            "fn f() { let _ = crate::render::Renderer; }",
        ),
    ]);
    let violations = scene_render_violations(&t);
    assert!(
        violations.len() == 1 && violations[0].contains("scene/spawn.rs:1"),
        "{violations:?}"
    );
}

#[test]
fn external_crates_resolve_as_external() {
    let t = tree(&[
        ("lib.rs", "mod a;"),
        ("a.rs", "use wgpu;\nfn f() { wgpu::Instance::new(); }"),
    ]);
    let targets: Vec<Target> = t.uses().into_iter().map(|u| u.target).collect();
    assert!(targets.contains(&Target::External(vec![
        "wgpu".into(),
        "Instance".into(),
        "new".into()
    ])));
    assert!(
        !targets
            .iter()
            .any(|t| matches!(t, Target::Internal(p) if p.first().is_some_and(|s| s == "wgpu")))
    );
}

#[test]
fn a_file_that_does_not_parse_is_named() {
    let sources = vec![(PathBuf::from("render/bad.rs"), "fn (".to_string())];
    let error = ModuleTree::from_sources(&sources)
        .err()
        .expect("a parse error");
    assert!(error.starts_with("render/bad.rs:1:"), "{error}");
}
