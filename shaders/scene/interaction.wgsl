// A ray's hit resolved into what shading needs (pbrt-v4 `SurfaceInteraction`): the position, geometric and
// shading normals (normal map applied) facing the incoming ray, the material's BSDF parameters at the point
// (textures and vertex colours applied), coverage alpha and emission.

struct SurfaceInteraction {
    p: vec3<f32>,
    ng: vec3<f32>,      // geometric normal, facing the incoming ray
    n: vec3<f32>,       // shading normal, facing the incoming ray
    front: bool,        // hit the side the triangle's winding faces
    bsdf: BsdfParams,
    alpha: f32,
    emission: vec3<f32>,
    flags: u32,         // MATERIAL_* flags
    material: u32,
}

fn resolve_hit(hit: Hit, ray: Ray) -> SurfaceInteraction {
    let inst = read_instance(hit.instance);
    let mesh = read_mesh(inst.mesh);
    let tri = read_triangle(hit.triangle);
    let m = read_material(tri.w);
    let w = vec3<f32>(1.0 - hit.bary.x - hit.bary.y, hit.bary.x, hit.bary.y);
    let p0 = transform_point(inst.world_from_object, vertex_position(mesh, tri.x));
    let p1 = transform_point(inst.world_from_object, vertex_position(mesh, tri.y));
    let p2 = transform_point(inst.world_from_object, vertex_position(mesh, tri.z));
    var s: SurfaceInteraction;
    s.material = tri.w;
    // The hit point from world-space barycentrics is more precise than origin + t * dir.
    s.p = p0 * w.x + p1 * w.y + p2 * w.z;
    var ng = normalize(cross(p1 - p0, p2 - p0));
    s.front = dot(ng, ray.dir) < 0.0;
    if !s.front { ng = -ng; }
    s.ng = ng;

    var n = ng;
    if mesh.normal_offset != NONE {
        let a = read_pool_word(mesh.normal_offset + tri.x);
        let b = read_pool_word(mesh.normal_offset + tri.y);
        let c = read_pool_word(mesh.normal_offset + tri.z);
        if a != INVALID_OCT && b != INVALID_OCT && c != INVALID_OCT {
            let interpolated = transform_normal(inst.object_from_world, oct_decode(a) * w.x + oct_decode(b) * w.y + oct_decode(c) * w.z);
            if dot(interpolated, interpolated) > 1e-12 {
                n = normalize(interpolated);
                if !s.front { n = -n; }
            }
        }
    }

    var base = m.base_color;
    if scene_uses_texture(CORE_TEXTURE_BASE_COLOR) && m.base_color_texture != NONE {
        let t = sample_texture(m.base_color_texture, texture_uv(m.base_color_texture, mesh, tri, w));
        base *= vec4<f32>(srgb_to_linear(t.rgb), t.a);
    }
    if mesh.color_offset != NONE {
        base *= vertex_color(mesh, tri, w);
    }
    var metallic = m.metallic;
    var roughness = m.roughness;
    if scene_uses_texture(CORE_TEXTURE_METALLIC_ROUGHNESS) && m.metallic_roughness_texture != NONE {
        let t = sample_texture(m.metallic_roughness_texture, texture_uv(m.metallic_roughness_texture, mesh, tri, w));
        roughness *= t.g;
        metallic *= t.b;
    }
    // The clear coat has its own normal map; without one it follows the interpolated normal, not the base's map.
    let n_interpolated = n;
    if scene_uses_texture(CORE_TEXTURE_NORMAL) && m.normal_texture != NONE && mesh.tangent_offset != NONE {
        n = normal_mapped(n, m.normal_texture, m.normal_scale, inst, mesh, tri, w, s.front);
    }
    let v = -ray.dir;
    n = facing_viewer(n, v);
    s.n = n;

    var emission = m.emissive;
    if scene_uses_texture(CORE_TEXTURE_EMISSIVE) && m.emissive_texture != NONE && any(emission > vec3<f32>(0.0)) {
        emission *= srgb_to_linear(sample_texture(m.emissive_texture, texture_uv(m.emissive_texture, mesh, tri, w)).rgb);
    }
    s.emission = emission;
    // KHR_materials_unlit: the base colour is what the surface shows (the path ends there: integrator).
    if MATERIAL_LOBES != 0u && (m.flags & MATERIAL_UNLIT) != 0u { s.emission = base.rgb; }
    s.bsdf = core_bsdf(base.rgb, clamp(metallic, 0.0, 1.0), max(roughness * roughness, MIN_ALPHA));
    if MATERIAL_LOBES != 0u { s.bsdf = with_material_extensions(s.bsdf, m, mesh, tri, w, s.front); }
    if (MATERIAL_LOBES & LOBES_LAYERS) != 0u {
        var coat_n = n_interpolated;
        if (MATERIAL_LOBES & LOBES_LEVEL) >= LOBES_TEXTURED && m.clearcoat_normal_texture != NONE && mesh.tangent_offset != NONE {
            coat_n = normal_mapped(coat_n, m.clearcoat_normal_texture, m.clearcoat_normal_scale, inst, mesh, tri, w, s.front);
        }
        s.bsdf.layers = material_layers(m, mesh, tri, w, facing_viewer(coat_n, v) * basis(n));
    }
    s.alpha = base.a;
    s.flags = m.flags;
    return s;
}

// `n` with the tangent-space normal of `texture` applied (scaled by `scale`); unchanged without usable tangents.
fn normal_mapped(n: vec3<f32>, texture: u32, scale: f32, inst: Instance, mesh: Mesh, tri: vec4<u32>, w: vec3<f32>, front: bool) -> vec3<f32> {
    let ta = read_pool_word(mesh.tangent_offset + 2u * tri.x);
    let tb = read_pool_word(mesh.tangent_offset + 2u * tri.y);
    let tc = read_pool_word(mesh.tangent_offset + 2u * tri.z);
    if ta != INVALID_OCT && tb != INVALID_OCT && tc != INVALID_OCT {
        let sign = bitcast<f32>(read_pool_word(mesh.tangent_offset + 2u * tri.x + 1u));
        var t = transform_vector(inst.world_from_object, oct_decode(ta) * w.x + oct_decode(tb) * w.y + oct_decode(tc) * w.z);
        t = t - n * dot(n, t);
        if dot(t, t) > 1e-12 {
            t = normalize(t);
            // On back faces n was flipped; the bitangent must follow the surface's own orientation.
            let b = cross(select(-n, n, front), t) * sign;
            let tex = sample_texture(texture, texture_uv(texture, mesh, tri, w)).xyz * 2.0 - 1.0;
            let local = vec3<f32>(untransform_tangent_normal(texture, tex.xy) * scale, tex.z);
            let mapped = t * local.x + b * local.y + n * local.z;
            if dot(mapped, mapped) > 1e-12 { return normalize(mapped); }
        }
    }
    return n;
}

// A shading normal facing away from the viewer would make the BRDF vanish: bend it back just enough.
fn facing_viewer(n: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let nv = dot(n, v);
    if nv < 1e-3 { return normalize(n + (1e-3 - nv) * v); }
    return n;
}

// KHR_materials_clearcoat and _sheen (textures applied at the textured level); `coat_normal` in the local
// shading frame.
fn material_layers(m: Material, mesh: Mesh, tri: vec4<u32>, w: vec3<f32>, coat_normal: vec3<f32>) -> vec3<u32> {
    let textured = (MATERIAL_LOBES & LOBES_LEVEL) >= LOBES_TEXTURED;
    var coat = m.clearcoat;
    var coat_roughness = m.clearcoat_roughness;
    var sheen = m.sheen_color;
    var sheen_roughness = m.sheen_roughness;
    if textured && coat > 0.0 {
        if m.clearcoat_texture != NONE {
            coat *= sample_texture(m.clearcoat_texture, texture_uv(m.clearcoat_texture, mesh, tri, w)).r;
        }
        if m.clearcoat_roughness_texture != NONE {
            coat_roughness *= sample_texture(m.clearcoat_roughness_texture, texture_uv(m.clearcoat_roughness_texture, mesh, tri, w)).g;
        }
    }
    if textured && any(sheen > vec3<f32>(0.0)) {
        if m.sheen_color_texture != NONE {
            sheen *= srgb_to_linear(sample_texture(m.sheen_color_texture, texture_uv(m.sheen_color_texture, mesh, tri, w)).rgb);
        }
        if m.sheen_roughness_texture != NONE {
            sheen_roughness *= sample_texture(m.sheen_roughness_texture, texture_uv(m.sheen_roughness_texture, mesh, tri, w)).a;
        }
    }
    return pack_layers(coat, coat_roughness, coat_normal, sheen, sheen_roughness);
}

fn emits_towards_viewer(s: SurfaceInteraction) -> bool {
    return s.front || (s.flags & MATERIAL_DOUBLE_SIDED) != 0u;
}

// KHR_materials_ior, _specular and _transmission on top of the core BSDF (textures applied). Crossing a
// refracting surface from its front enters the volume behind it.
fn with_material_extensions(core: BsdfParams, m: Material, mesh: Mesh, tri: vec4<u32>, w: vec3<f32>, front: bool) -> BsdfParams {
    var transmission = m.transmission;
    let textured = (MATERIAL_LOBES & LOBES_LEVEL) >= LOBES_TEXTURED;
    if textured && m.transmission_texture != NONE && transmission > 0.0 {
        transmission *= sample_texture(m.transmission_texture, texture_uv(m.transmission_texture, mesh, tri, w)).r;
    }
    var f0 = m.specular_f0;
    if textured && m.specular_color_texture != NONE {
        f0 *= srgb_to_linear(sample_texture(m.specular_color_texture, texture_uv(m.specular_color_texture, mesh, tri, w)).rgb);
    }
    var weight = m.specular_weight;
    if textured && m.specular_texture != NONE {
        weight *= sample_texture(m.specular_texture, texture_uv(m.specular_texture, mesh, tri, w)).a;
    }
    var b = core;
    b.lobes = pack_lobes(f0, weight, transmission, m.refraction_ior, !front);
    return b;
}

// The volume a ray is in after it is transmitted through `s`, named by its material (NONE: none): the
// material's own entering through the front, none leaving through the back. Thin walls change nothing (a
// volume of IOR 1 transmits like a thin wall but still bounds its medium). Nested volumes are not tracked:
// leaving an inner one returns to none (less absorption, never more energy).
fn medium_after_transmission(s: SurfaceInteraction, medium: u32) -> u32 {
    if thin_walled(s.bsdf) && all(read_material(s.material).attenuation == vec3<f32>(0.0)) { return medium; }
    return select(NONE, s.material, s.front);
}

// Beer-Lambert transmittance over `t` inside the volume of material `medium` (NONE: none; t may be MISS: a
// ray that leaves the scene inside an absorbing volume carries nothing).
fn transmittance(medium: u32, t: f32) -> vec3<f32> {
    if medium == NONE { return vec3<f32>(1.0); }
    return exp(-read_material(medium).attenuation * t);
}
