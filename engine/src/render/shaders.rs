//! The WGSL shader library (`shaders/`, cut along pbrt-v4's interfaces) and its module table. WGSL has no
//! includes: a kernel names the library modules it needs, and [`compose`] writes those modules and everything
//! they need, each once, in dependency order, then the kernel. Tests validate exactly the composed strings with
//! naga, so what CI checks is what runs.
//!
//! The `constants` module is generated from [`super::layout::WGSL_CONSTANTS`], the one source of every constant
//! Rust and WGSL share.

/// One WGSL source and the library modules it uses.
#[derive(Clone, Copy, Debug)]
pub struct ShaderModule {
    /// The library path without `.wgsl` (`bsdf/gltf`), or a kernel's name.
    pub name: &'static str,
    pub source: &'static str,
    pub requires: &'static [&'static str],
}

macro_rules! library {
    ($($name:literal => [$($dep:literal),* $(,)?]),* $(,)?) => {
        &[$(ShaderModule {
            name: $name,
            source: include_str!(concat!("../../../shaders/", $name, ".wgsl")),
            requires: &[$($dep),*],
        }),*]
    };
}

/// The library, `shaders/<name>.wgsl`. `constants` is generated and not listed.
pub const LIBRARY: &[ShaderModule] = library! {
    "math" => [],
    "color" => [],
    "sampler" => [],
    "sampling" => ["math"],
    "octahedral" => ["constants", "math"],
    "view" => [],
    "camera" => ["view", "traversal/ray", "sampling"],
    "scene/types" => [],
    "scene/bindings" => ["scene/types"],
    "scene/vertex" => ["constants", "math", "octahedral", "scene/bindings"],
    "scene/texture" => ["constants", "scene/bindings"],
    "scene/alpha" => ["scene/vertex", "scene/texture"],
    "scene/interaction" => ["scene/vertex", "scene/texture", "color", "bsdf/gltf", "traversal/ray"],
    "traversal/ray" => ["scene/types"],
    "traversal/stats" => [],
    "traversal/primitive" => ["traversal/ray", "traversal/stats", "scene/alpha"],
    "traversal/bvh2" => ["traversal/primitive", "traversal/stats"],
    "traversal/cwbvh" => ["traversal/primitive", "traversal/stats"],
    "traversal/tlas" => ["traversal/bvh2", "traversal/cwbvh", "traversal/stats", "math"],
    "traversal/refill" => ["traversal/tlas"],
    "bsdf/bsdf" => [],
    "bsdf/microfacet" => ["math"],
    "bsdf/sheen_albedo" => [],
    "bsdf/sheen" => ["bsdf/sheen_albedo", "math"],
    "bsdf/gltf" => ["constants", "bsdf/bsdf", "bsdf/microfacet", "bsdf/sheen", "sampling", "color", "octahedral"],
    "lights/light" => [],
    "lights/light_tree" => ["constants", "scene/bindings", "lights/light"],
    "lights/light_sampler" => ["constants", "scene/bindings", "view", "lights/light_tree"],
    "lights/punctual" => ["constants", "lights/light", "scene/types", "traversal/ray"],
    "lights/area" => [
        "constants",
        "lights/light",
        "scene/vertex",
        "scene/texture",
        "color",
        "sampling",
        "math",
    ],
    "lights/environment" => ["constants", "lights/light", "scene/bindings", "math", "traversal/ray"],
    "lights/sun" => ["lights/light", "scene/types", "math", "sampling", "traversal/ray"],
    "lights/dispatch" => [
        "constants",
        "scene/bindings",
        "traversal/ray",
        "lights/area",
        "lights/punctual",
        "lights/environment",
        "lights/sun",
    ],
    "integrator/path" => [
        "traversal/tlas",
        "scene/interaction",
        "lights/light_sampler",
        "lights/dispatch",
        "sampler",
        "camera",
        "color",
        "math",
        "view",
    ],
    "realtime/frame" => ["constants", "view", "sampler"],
    "realtime/gbuffer" => ["constants", "bsdf/gltf"],
    "realtime/sample" => [],
    "realtime/motion" => ["constants", "math", "realtime/frame", "scene/vertex"],
    "restir/reservoir" => ["constants", "math"],
    "restir/target" => [
        "integrator/path",
        "lights/light_sampler",
        "lights/area",
        "bsdf/gltf",
        "traversal/tlas",
        "color",
        "math",
    ],
    "integrator/realtime" => [
        "integrator/path",
        "realtime/gbuffer",
        "realtime/motion",
        "restir/target",
        "octahedral",
        "camera",
        "sampler",
    ],
};

/// The generated module of shared constants.
pub fn constants_source() -> String {
    let mut out = String::from(
        "// Generated from engine/src/render/layout.rs `WGSL_CONSTANTS`: do not edit in WGSL.\n",
    );
    for (name, value) in super::layout::WGSL_CONSTANTS {
        out.push_str(&format!("const {name}: u32 = {value}u;\n"));
    }
    out
}

/// A kernel's full source: the library modules it requires (transitively, each once, dependencies first), then
/// the kernel itself.
///
/// # Panics
/// When a module names a library module that does not exist (a programming error the naga test catches).
pub fn compose(kernel: &ShaderModule) -> String {
    let mut order: Vec<&str> = Vec::new();
    for name in kernel.requires {
        visit(name, &mut order, &mut Vec::new());
    }
    let mut out = String::new();
    for name in order {
        let text = if name == "constants" {
            constants_source()
        } else {
            let module = find(name);
            override_or(module.name, module.source)
        };
        out.push_str(&format!("// ---- {name}.wgsl ----\n{text}\n"));
    }
    out.push_str(&format!(
        "// ---- {}.wgsl ----\n{}",
        kernel.name,
        override_or(kernel.name, kernel.source)
    ));
    out
}

fn find(name: &str) -> &'static ShaderModule {
    LIBRARY
        .iter()
        .find(|m| m.name == name)
        .unwrap_or_else(|| panic!("shader library has no module `{name}`"))
}

/// Depth-first, post-order: a module after everything it requires. `path` catches require cycles.
fn visit<'a>(name: &'a str, order: &mut Vec<&'a str>, path: &mut Vec<&'a str>) {
    if order.contains(&name) {
        return;
    }
    assert!(
        !path.contains(&name),
        "shader modules require each other: {} -> {name}",
        path.join(" -> ")
    );
    if name != "constants" {
        path.push(name);
        for dep in find(name).requires {
            visit(dep, order, path);
        }
        path.pop();
    }
    order.push(name);
}

/// Kernel development: with `RAYKIN_SHADER_DIR` set, `<dir>/<name>.wgsl` (e.g. `bsdf/gltf.wgsl`, `trace.wgsl`)
/// replaces the built-in copy (edit a kernel and rerun without rebuilding; A/B variants in one GPU session).
/// Unset in normal use.
fn override_or(name: &str, built_in: &str) -> String {
    let Some(dir) = std::env::var_os("RAYKIN_SHADER_DIR") else {
        return built_in.to_string();
    };
    let path = std::path::Path::new(&dir).join(format!("{name}.wgsl"));
    match std::fs::read_to_string(&path) {
        Ok(text) => {
            tracing::warn!("shader {name}.wgsl read from {}", path.display());
            text
        }
        Err(_) => built_in.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_library_module_composes_once_after_its_requirements() {
        for module in LIBRARY {
            let kernel = ShaderModule {
                name: "probe",
                source: "",
                requires: std::slice::from_ref(&module.name),
            };
            let text = compose(&kernel);
            let headers: Vec<&str> = text.lines().filter(|l| l.starts_with("// ---- ")).collect();
            let mut seen = std::collections::HashSet::new();
            for h in &headers {
                assert!(seen.insert(*h), "{} composed twice for {}", h, module.name);
            }
            for dep in module.requires {
                let dep_at = headers
                    .iter()
                    .position(|h| h.contains(&format!(" {dep}.wgsl")));
                let at = headers
                    .iter()
                    .position(|h| h.contains(&format!(" {}.wgsl", module.name)));
                assert!(dep_at < at, "{dep} must come before {}", module.name);
            }
        }
    }

    #[test]
    fn constants_carry_the_rust_values() {
        let text = constants_source();
        assert!(text.contains(&format!("const NONE: u32 = {}u;", u32::MAX)));
        assert!(text.contains(&format!(
            "const TLAS_STACK_SIZE: u32 = {}u;",
            crate::bvh::MAX_TRAVERSAL_DEPTH
        )));
    }
}
