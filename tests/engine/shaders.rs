//! Every WGSL kernel the renderer builds is composed from the shader library, parsed and validated by naga, so a
//! broken kernel fails CI instead of a user's first frame; and every struct Rust uploads has exactly the size and
//! field offsets of the WGSL struct that reads it.

use raykin::render::passes;

#[test]
fn all_wgsl_kernels_validate() {
    for (name, source) in passes::all_kernels() {
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

/// Every compute kernel reaches the driver specialised (`gpu::specialize`): a kernel that fell back to WGSL and
/// constants would still render, only with the compile time of every branch its constants switch off, so the
/// fallback is caught here. The path tracer compiled for a scene of the core BSDF and triangle lights loses the
/// layered BSDF and the environment's sampling, which its default constants keep.
#[test]
fn every_compute_kernel_specialises() {
    use raykin::gpu::specialize;
    for (name, source) in passes::all_kernels() {
        let parsed =
            specialize::parse(&source).unwrap_or_else(|| panic!("{name}.wgsl does not parse"));
        let module = naga::front::wgsl::parse_str(&source).unwrap();
        for entry in module
            .entry_points
            .iter()
            .filter(|e| e.stage == naga::ShaderStage::Compute)
        {
            assert!(
                specialize::specialize(&parsed, &entry.name, &[]).is_some(),
                "{name}.wgsl `{}` does not specialise",
                entry.name
            );
        }
    }
    let trace = passes::all_kernels()
        .into_iter()
        .find(|(name, _)| *name == "trace")
        .unwrap()
        .1;
    let parsed = specialize::parse(&trace).unwrap();
    let functions = |constants: &[(&str, f64)]| -> Vec<String> {
        let module = specialize::specialize(&parsed, "trace_pixels", constants).unwrap();
        module
            .functions
            .iter()
            .filter_map(|(_, f)| f.name.clone())
            .collect()
    };
    let general = functions(&[]);
    let cornell = functions(&[
        ("MATERIAL_LOBES", 0.0),
        ("PATH_AOVS", 0.0),
        ("PATH_HIT_AOV", 0.0),
        (
            "NEXT_EVENT_LIGHT_KINDS",
            f64::from(1u32 << raykin::render::layout::LIGHT_TRIANGLE),
        ),
    ]);
    for gone in ["layered_eval", "environment_sample_li", "sun_sample_li"] {
        assert!(
            general.iter().any(|f| f == gone),
            "the general kernel calls {gone}"
        );
        assert!(
            !cornell.iter().any(|f| f == gone),
            "the Cornell box's kernel still calls {gone}"
        );
    }
    assert!(cornell.iter().any(|f| f == "triangle_light_sample_li"));
}

/// On CPU adapters compute kernels read their parameters from storage buffers (`gpu::params_in_storage`):
/// lavapipe specialises a kernel on the values of uniforms that decide branches or loop counts and compiles it
/// again (tens of seconds) for each new image size, depth or camera. They read the scene from textures
/// (`gpu::scene_in_textures`). That form of every compute kernel validates, reads no uniform, and reads the
/// scene from textures only.
#[test]
fn compute_kernels_validate_in_their_cpu_adapter_form() {
    let mut compute = 0;
    let mut with_scene = 0;
    for (name, source) in passes::all_kernels() {
        let source = raykin::gpu::scene_in_textures(&raykin::gpu::params_in_storage(&source));
        let module = naga::front::wgsl::parse_str(&source)
            .unwrap_or_else(|e| panic!("{name}.wgsl: {}", e.emit_to_string(&source)));
        if !module
            .entry_points
            .iter()
            .any(|e| e.stage == naga::ShaderStage::Compute)
        {
            continue;
        }
        compute += 1;
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .unwrap_or_else(|e| {
            panic!(
                "{name}.wgsl with parameters in storage does not validate: {}",
                e.emit_to_string(&source)
            )
        });
        for (_, global) in module.global_variables.iter() {
            assert!(
                global.space != naga::AddressSpace::Uniform,
                "{name}.wgsl: `{}` is still a uniform",
                global.name.as_deref().unwrap_or("?")
            );
            if global.binding.as_ref().is_some_and(|b| b.group == 0)
                && source.contains("// ---- scene/bindings.wgsl ----")
            {
                assert_eq!(
                    global.space,
                    naga::AddressSpace::Handle,
                    "{name}.wgsl: scene binding `{}` is not a texture",
                    global.name.as_deref().unwrap_or("?")
                );
            }
        }
        if source.contains("// ---- scene/bindings.wgsl ----") {
            assert!(
                source.contains("var tlas_nodes: texture_storage_2d<rgba32uint, read>"),
                "{name}.wgsl"
            );
            with_scene += 1;
        }
    }
    assert!(compute >= 13, "only {compute} compute kernels found");
    assert!(with_scene >= 5, "only {with_scene} kernels read the scene");
}

/// Size and member offsets (by name) of each named struct of a WGSL module.
struct WgslLayouts {
    module: naga::Module,
    layouter: naga::proc::Layouter,
}

impl WgslLayouts {
    fn of(kernel: &raykin::render::shaders::ShaderModule) -> Self {
        let source = raykin::render::shaders::compose(kernel);
        let module = naga::front::wgsl::parse_str(&source).expect("parses");
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).expect("layout");
        Self { module, layouter }
    }

    fn size(&self, name: &str) -> usize {
        self.layouter[self.handle(name)].size as usize
    }

    fn offset(&self, name: &str, member: &str) -> usize {
        match &self.module.types[self.handle(name)].inner {
            naga::TypeInner::Struct { members, .. } => {
                members
                    .iter()
                    .find(|m| m.name.as_deref() == Some(member))
                    .unwrap_or_else(|| panic!("WGSL struct {name} has no member {member}"))
                    .offset as usize
            }
            _ => panic!("{name} is not a struct"),
        }
    }

    fn handle(&self, name: &str) -> naga::Handle<naga::Type> {
        self.module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no WGSL type {name}"))
            .0
    }
}

/// Asserts that the WGSL struct `$wgsl` has the size of the Rust type and each listed field at the Rust
/// field's offset (Rust field name = WGSL member name unless given as `rust => wgsl`).
macro_rules! same_layout {
    ($layouts:expr, $wgsl:literal, $rust:ty, [$($field:ident $(=> $member:literal)?),* $(,)?]) => {{
        let l = &$layouts;
        assert_eq!(l.size($wgsl), std::mem::size_of::<$rust>(), "size of {}", $wgsl);
        $(
            let member = same_layout!(@name $field $($member)?);
            assert_eq!(
                l.offset($wgsl, member),
                std::mem::offset_of!($rust, $field),
                "offset of {}.{}",
                $wgsl,
                member
            );
        )*
    }};
    (@name $field:ident $member:literal) => { $member };
    (@name $field:ident) => { stringify!($field) };
}

#[test]
fn scene_structs_match_wgsl() {
    use raykin::render::layout::*;
    let l = WgslLayouts::of(&passes::trace::KERNEL);
    same_layout!(l, "BvhNode", raykin::bvh::GpuBvhNode, []);
    same_layout!(
        l,
        "Instance",
        GpuInstance,
        [
            world_from_object,
            object_from_world,
            mesh,
            first_light,
            light_count
        ]
    );
    same_layout!(
        l,
        "Mesh",
        GpuMesh,
        [
            blas_root,
            triangle_offset,
            position_offset,
            normal_offset,
            tangent_offset,
            uv0_offset,
            uv1_offset,
            color_offset
        ]
    );
    same_layout!(
        l,
        "Material",
        GpuMaterial,
        [
            base_color,
            emissive,
            metallic,
            roughness,
            alpha_cutoff,
            normal_scale,
            flags,
            base_color_texture,
            metallic_roughness_texture,
            normal_texture,
            emissive_texture,
            specular_f0,
            transmission,
            specular_color_texture,
            clearcoat,
            clearcoat_roughness_texture,
            sheen_color,
            sheen_roughness,
            clearcoat_normal_texture,
            clearcoat_normal_scale,
            sheen_roughness_texture
        ]
    );
    same_layout!(
        l,
        "TextureInfo",
        GpuTexture,
        [offset, width, height, flags, uv_u, uv_v]
    );
    same_layout!(
        l,
        "Light",
        GpuLight,
        [
            kind, index_a, index_b, flags, position, range, direction, cos_outer, radiance,
            cos_inner
        ]
    );
    same_layout!(
        l,
        "LightTreeNode",
        GpuLightTreeNode,
        [
            lo,
            phi,
            hi,
            cos_theta_o,
            w,
            cos_theta_e,
            child_or_light,
            flags
        ]
    );
    same_layout!(
        l,
        "Frame",
        GpuFrame,
        [
            world_from_camera,
            tan_half_fov,
            lens_radius,
            focus_distance,
            light_count,
            width,
            height,
            sample_base,
            spp,
            max_depth,
            seed,
            rr_depth,
            flags,
            infinite_light_first,
            infinite_light_count,
            tree_light_count
        ]
    );
}

#[test]
fn pass_parameters_match_wgsl() {
    use passes::denoise::DenoisePassParams;
    use passes::display::DisplayParams;
    use passes::tonemap::TonemapParams;
    same_layout!(
        WgslLayouts::of(&passes::tonemap::KERNEL),
        "Params",
        TonemapParams,
        [width, height, tonemapper, view, exposure_scale, depth_scale]
    );
    same_layout!(
        WgslLayouts::of(&passes::denoise::KERNEL),
        "Params",
        DenoisePassParams,
        [
            width,
            height,
            step,
            last,
            sigma_luminance,
            sigma_normal,
            sigma_depth
        ]
    );
    same_layout!(
        WgslLayouts::of(&passes::display::KERNEL),
        "DisplayParams",
        DisplayParams,
        [origin, size, image_width, image_height, srgb_target]
    );
}

#[test]
fn gpu_deform_structs_match_wgsl() {
    use passes::deform::DeformParams;
    use passes::refit::RefitMeshGpu;
    use raykin::gpu_deform::inputs::DeformMeshGpu;
    let deform = WgslLayouts::of(&passes::deform::KERNEL);
    same_layout!(deform, "DeformParams", DeformParams, [mesh_count, groups_x]);
    same_layout!(
        deform,
        "DeformMesh",
        DeformMeshGpu,
        [
            vertex_count,
            first_group,
            rest_position,
            rest_normal,
            rest_tangent,
            influences,
            influence_sets,
            morph_targets,
            morph_deltas,
            morph_stride,
            morph_normal,
            morph_tangent,
            out_position,
            out_normal,
            out_tangent,
            joint_base,
            joint_count,
            weight_base
        ]
    );
    let refit = WgslLayouts::of(&passes::refit::KERNEL);
    same_layout!(
        refit,
        "RefitMesh",
        RefitMeshGpu,
        [
            blas_root,
            triangle_offset,
            position_offset,
            node_count,
            order_offset,
            level_offset,
            levels,
            wide_root,
            wide_count,
            source_offset
        ]
    );
    same_layout!(refit, "BvhNode", raykin::bvh::GpuBvhNode, []);
}

#[test]
fn realtime_structs_match_wgsl() {
    use passes::denoiser_planes::DenoiserPlanesParams;
    use passes::gradient::FilterStep;
    use passes::handover::HandoverParams;
    use raykin::render::layout::*;
    let gbuffer = WgslLayouts::of(&passes::gbuffer::KERNEL);
    same_layout!(
        gbuffer,
        "RealtimeFrame",
        GpuRealtimeFrame,
        [
            camera_from_world,
            prev_camera_from_world,
            prev_camera_origin,
            prev_tan_half_fov,
            flags,
            history_cap,
            strata_width,
            strata_height,
            restir_candidates,
            restir_neighbours,
            restir_radius,
            restir_max_confidence,
            depth_tolerance,
            normal_tolerance
        ]
    );
    same_layout!(
        gbuffer,
        "MotionInstance",
        GpuMotionInstance,
        [prev_world_from_object, object]
    );
    same_layout!(
        gbuffer,
        "GSurface",
        GpuSurface,
        [
            position, depth, object, triangle, bary, normal, geometric, bsdf, motion, prev_depth,
            material
        ]
    );
    same_layout!(
        WgslLayouts::of(&passes::temporal::KERNEL),
        "RealtimeSample",
        GpuRealtimeSample,
        [radiance, valid, unscattered]
    );
    same_layout!(
        WgslLayouts::of(&passes::handover::KERNEL),
        "Params",
        HandoverParams,
        [width, height, weight]
    );
    same_layout!(
        WgslLayouts::of(&passes::denoiser_planes::PACK_KERNEL),
        "Params",
        DenoiserPlanesParams,
        [width, height, max_radiance]
    );
    same_layout!(
        WgslLayouts::of(&passes::denoiser_planes::UNPACK_KERNEL),
        "Params",
        DenoiserPlanesParams,
        [width, height, max_radiance]
    );
    same_layout!(
        WgslLayouts::of(&passes::gradient::KERNEL),
        "FilterStep",
        FilterStep,
        [step]
    );
}
