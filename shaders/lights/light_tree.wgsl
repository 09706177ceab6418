// The spatially aware light sampler's tree (engine/src/render/gpu_scene/light_tree.rs; pbrt-v4's
// `BVHLightSampler`): from the root, a child is taken in proportion to an upper bound of the irradiance its
// lights can send to the shading point (distance, the cone of their emission directions, the cosine at the
// point), so near, facing lights are picked far more often than far or turned-away ones. The probability of a
// light is the product along the path to its leaf, which its bit trail (`Light.flags`) names.

const ONE_MINUS_EPSILON: f32 = 0.99999994;

// cos(a - b) clamped to 1 when a < b (pbrt's cosSubClamped); sin likewise clamped to 0.
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { return 1.0; }
    return cos_a * cos_b + sin_a * sin_b;
}
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { return 0.0; }
    return sin_a * cos_b - cos_a * sin_b;
}

// pbrt-v4's `LightBounds::Importance`: an upper bound of what the node's lights send to p (normal n, zero in
// free space); 0 only when no light of the node can reach p.
fn light_tree_importance(node: LightTreeNode, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let center = 0.5 * (node.lo + node.hi);
    let to_p = p - center;
    let distance2 = dot(to_p, to_p);
    let d2 = max(distance2, 0.5 * length(node.hi - node.lo));
    let wi = select(vec3<f32>(0.0, 0.0, 1.0), to_p / sqrt(distance2), distance2 > 0.0);
    var cos_w = dot(node.w, wi);
    if (node.flags & LIGHT_TREE_TWO_SIDED) != 0u { cos_w = abs(cos_w); }
    let sin_w = sqrt(max(0.0, 1.0 - cos_w * cos_w));
    // The cone of directions from p that the node's box subtends.
    let radius2 = 0.25 * dot(node.hi - node.lo, node.hi - node.lo);
    let cos_b = select(sqrt(max(0.0, 1.0 - radius2 / distance2)), -1.0, distance2 <= radius2);
    let sin_b = sqrt(max(0.0, 1.0 - cos_b * cos_b));
    let sin_o = sqrt(max(0.0, 1.0 - node.cos_theta_o * node.cos_theta_o));
    let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, node.cos_theta_o);
    let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, node.cos_theta_o);
    let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    if cos_p <= node.cos_theta_e { return 0.0; }
    var importance = node.phi * cos_p / d2;
    if any(n != vec3<f32>(0.0)) {
        let cos_i = abs(dot(wi, n));
        let sin_i = sqrt(max(0.0, 1.0 - cos_i * cos_i));
        importance *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
    }
    return max(importance, 0.0);
}

// The chance of taking node `index`'s first child from ctx (-1: neither child can light ctx).
fn light_tree_first_child_probability(index: u32, ctx: LightSampleContext) -> f32 {
    let node = read_light_tree_node(index);
    let i0 = light_tree_importance(read_light_tree_node(index + 1u), ctx.p, ctx.n);
    let i1 = light_tree_importance(read_light_tree_node(node.child_or_light), ctx.p, ctx.n);
    if i0 + i1 <= 0.0 { return -1.0; }
    return i0 / (i0 + i1);
}

// A light of the tree for ctx and its probability among the tree's lights (NONE and 0 when no light can reach
// ctx).
fn light_tree_sample(ctx: LightSampleContext, u_in: f32) -> LightChoice {
    var u = u_in;
    var index = 0u;
    var pmf = 1.0;
    loop {
        let node = read_light_tree_node(index);
        if (node.flags & LIGHT_TREE_LEAF) != 0u { return LightChoice(node.child_or_light, pmf); }
        let p0 = light_tree_first_child_probability(index, ctx);
        if p0 < 0.0 { return LightChoice(NONE, 0.0); }
        if u < p0 {
            index = index + 1u;
            pmf *= p0;
            u = min(u / p0, ONE_MINUS_EPSILON);
        } else {
            index = node.child_or_light;
            pmf *= 1.0 - p0;
            u = min((u - p0) / (1.0 - p0), ONE_MINUS_EPSILON);
        }
    }
    return LightChoice(NONE, 0.0);
}

// The probability that `light_tree_sample` from ctx picks `light` (which must be in the tree).
fn light_tree_pmf(ctx: LightSampleContext, light: u32) -> f32 {
    let trail = read_light(light).flags;
    var index = 0u;
    var pmf = 1.0;
    for (var depth = 0u; depth < 32u; depth++) {
        let node = read_light_tree_node(index);
        if (node.flags & LIGHT_TREE_LEAF) != 0u { return select(0.0, pmf, node.child_or_light == light); }
        let p0 = light_tree_first_child_probability(index, ctx);
        if p0 < 0.0 { return 0.0; }
        if ((trail >> depth) & 1u) == 0u {
            index = index + 1u;
            pmf *= p0;
        } else {
            index = node.child_or_light;
            pmf *= 1.0 - p0;
        }
    }
    return 0.0;
}
