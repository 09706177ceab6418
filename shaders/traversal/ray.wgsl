// Rays, hits and the primitive tests every traversal shares: slab test against a child box, Moeller-Trumbore
// against a triangle (both faces), and robust ray origins off a surface.

const MISS: f32 = 3.0e38;

struct Ray { origin: vec3<f32>, dir: vec3<f32> }

struct Hit {
    t: f32,
    instance: u32,
    // Slot in `triangles` (mesh offset included).
    triangle: u32,
    bary: vec2<f32>,
}

fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let eps = 1e-20;
    let s = select(vec3<f32>(1.0), vec3<f32>(-1.0), d < vec3<f32>(0.0));
    return 1.0 / select(d, s * eps, abs(d) < vec3<f32>(eps));
}

// Entry distance of the ray into a child box, or MISS.
fn hit_child(c: BvhChild, o: vec3<f32>, inv_d: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (c.min - o) * inv_d;
    let t1 = (c.max - o) * inv_d;
    let lo = min(t0, t1);
    let hi = max(t0, t1);
    let t_enter = max(max(lo.x, lo.y), max(lo.z, 0.0));
    let t_exit = min(min(hi.x, hi.y), min(hi.z, t_max));
    return select(MISS, t_enter, t_enter <= t_exit);
}

// Moeller-Trumbore, both faces. Returns (t, u, v); t = MISS when there is no hit in (0, t_max).
fn hit_triangle(o: vec3<f32>, d: vec3<f32>, p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>, t_max: f32) -> vec3<f32> {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pv = cross(d, e2);
    let det = dot(e1, pv);
    if det == 0.0 { return vec3<f32>(MISS, 0.0, 0.0); }
    let inv = 1.0 / det;
    let tv = o - p0;
    let u = dot(tv, pv) * inv;
    let qv = cross(tv, e1);
    let v = dot(d, qv) * inv;
    let t = dot(e2, qv) * inv;
    if u < 0.0 || v < 0.0 || u + v > 1.0 || t <= 0.0 || t >= t_max { return vec3<f32>(MISS, 0.0, 0.0); }
    return vec3<f32>(t, u, v);
}

// Offsets a ray origin off a surface by a few ULPs along the geometric normal, scaled to the coordinates'
// magnitude (Waechter & Binder, Ray Tracing Gems ch. 6): no self-intersection at large coordinates or grazing
// angles, and no visible gap near the origin.
fn offset_ray_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let int_scale = 256.0;
    let float_scale = 1.0 / 65536.0;
    let origin = 1.0 / 32.0;
    let of_i = vec3<i32>(int_scale * n);
    let p_i = vec3<f32>(
        bitcast<f32>(bitcast<i32>(p.x) + select(of_i.x, -of_i.x, p.x < 0.0)),
        bitcast<f32>(bitcast<i32>(p.y) + select(of_i.y, -of_i.y, p.y < 0.0)),
        bitcast<f32>(bitcast<i32>(p.z) + select(of_i.z, -of_i.z, p.z < 0.0)));
    return vec3<f32>(
        select(p_i.x, p.x + float_scale * n.x, abs(p.x) < origin),
        select(p_i.y, p.y + float_scale * n.y, abs(p.y) < origin),
        select(p_i.z, p.z + float_scale * n.z, abs(p.z) < origin));
}

// A ray from one surface point to another and how far it may go (pbrt-v4's `SpawnRayTo`): both ends moved off
// their surfaces as `offset_ray_origin` does, `n_from` towards the far end's side and `n_to` towards the near
// end's (zero for a point in free space), and the ray stopping just short of the moved far end. Moving only the
// origin is not enough next to a light: from a ceiling 0.9 units above a lamp at y = 548 the origin moves 0.016
// towards it, so a shadow ray aimed at the unmoved lamp point crosses the lamp's plane before a t_max of
// (1 - 1e-4) x the distance and the lamp blocks its own light.
struct RaySegment {
    ray: Ray,
    t_max: f32,
}

fn spawn_ray_to(p_from: vec3<f32>, n_from: vec3<f32>, p_to: vec3<f32>, n_to: vec3<f32>) -> RaySegment {
    let origin = offset_ray_origin(p_from, n_from);
    let d = offset_ray_origin(p_to, n_to) - origin;
    let distance = length(d);
    if !(distance > 0.0) { return RaySegment(Ray(origin, vec3<f32>(0.0, 0.0, 1.0)), 0.0); }
    return RaySegment(Ray(origin, d / distance), distance * (1.0 - 1e-4));
}
