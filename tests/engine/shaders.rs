//! Every WGSL module the renderer builds is parsed and validated by naga, so a broken kernel fails CI
//! instead of a user's first frame.

#[test]
fn all_wgsl_modules_validate() {
    for (name, source) in raykin::render::shaders::all_modules() {
        let module = naga::front::wgsl::parse_str(&source)
            .unwrap_or_else(|e| panic!("{name}.wgsl: {}", e.emit_to_string(&source)));
        let mut validator = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        );
        validator.validate(&module).unwrap_or_else(|e| {
            panic!(
                "{name}.wgsl does not validate: {}",
                e.emit_to_string(&source)
            )
        });
    }
}

/// Byte size of each named struct of a WGSL module.
fn wgsl_sizes(source: &str) -> impl Fn(&str) -> usize + use<> {
    let module = naga::front::wgsl::parse_str(source).expect("parses");
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("layout");
    move |name: &str| {
        let (handle, _) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("type {name}"));
        layouter[handle].size as usize
    }
}

/// The Rust structs uploaded to the GPU must have the sizes the WGSL structs read.
#[test]
fn gpu_struct_sizes_match_wgsl() {
    let size_of = wgsl_sizes(&raykin::render::shaders::path_trace_source());
    use raykin::render::layout::*;
    assert_eq!(
        size_of("BvhNode"),
        std::mem::size_of::<raykin::bvh::GpuBvhNode>()
    );
    assert_eq!(size_of("Instance"), std::mem::size_of::<GpuInstance>());
    assert_eq!(size_of("Mesh"), std::mem::size_of::<GpuMesh>());
    assert_eq!(size_of("Material"), std::mem::size_of::<GpuMaterial>());
    assert_eq!(size_of("TextureInfo"), std::mem::size_of::<GpuTexture>());
    assert_eq!(size_of("Emitter"), std::mem::size_of::<GpuEmitter>());
    assert_eq!(size_of("Frame"), std::mem::size_of::<GpuFrame>());
}

#[test]
fn gpu_deform_struct_sizes_match_wgsl() {
    use raykin::gpu_deform::{DeformParams, RefitMeshGpu, inputs::DeformMeshGpu};
    let deform = wgsl_sizes(raykin::render::shaders::DEFORM);
    assert_eq!(deform("DeformMesh"), std::mem::size_of::<DeformMeshGpu>());
    assert_eq!(deform("DeformParams"), std::mem::size_of::<DeformParams>());
    let refit = wgsl_sizes(raykin::render::shaders::REFIT);
    assert_eq!(refit("RefitMesh"), std::mem::size_of::<RefitMeshGpu>());
    assert_eq!(
        refit("BvhNode"),
        std::mem::size_of::<raykin::bvh::GpuBvhNode>()
    );
}
