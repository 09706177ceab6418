// Alpha-mask cut-outs, tested during traversal so that masked-out texels are never hit.

// Whether some material of the scene is alpha-masked (engine/src/render/material_lobes.rs `MaterialNeeds`):
// without one the test compiles away, which on lavapipe would otherwise run at every candidate hit of every
// traversal (its `if`s mask SIMD lanes, they never skip code). Kernels that do not set it test.
override ALPHA_MASKS: bool = true;

// False when the hit point's base-colour alpha is below the material's cutoff.
fn alpha_passes(mesh: Mesh, tri: vec4<u32>, bary: vec2<f32>) -> bool {
    if !ALPHA_MASKS { return true; }
    let m = read_material(tri.w);
    if (m.flags & MATERIAL_ALPHA_MASK) == 0u { return true; }
    let w = vec3<f32>(1.0 - bary.x - bary.y, bary.x, bary.y);
    var alpha = m.base_color.a;
    if scene_uses_texture(CORE_TEXTURE_BASE_COLOR) && m.base_color_texture != NONE {
        let set_offset = select(mesh.uv0_offset, mesh.uv1_offset, (m.base_color_texture >> 24u) == 1u);
        if set_offset != NONE {
            alpha *= sample_texture(m.base_color_texture, interpolate_uv(set_offset, tri, w)).a;
        }
    }
    if mesh.color_offset != NONE {
        alpha *= vertex_color(mesh, tri, w).a;
    }
    return alpha >= m.alpha_cutoff;
}
