// The traversal work of one invocation, counted only in pipelines that set TRAVERSAL_STATS (the ray-casting
// benchmark's counting run, engine/src/render/passes/raycast): everywhere else the override folds it away.

override TRAVERSAL_STATS: bool = false;

// Per invocation: x top-level BVH2 nodes fetched, y deformable meshes' BVH2 nodes, z wide (CWBVH) nodes,
// w triangles tested.
var<private> traversal_work: vec4<u32>;

const WORK_TLAS_NODE = vec4<u32>(1u, 0u, 0u, 0u);
const WORK_BVH2_NODE = vec4<u32>(0u, 1u, 0u, 0u);
const WORK_WIDE_NODE = vec4<u32>(0u, 0u, 1u, 0u);
const WORK_TRIANGLE = vec4<u32>(0u, 0u, 0u, 1u);

fn count_work(work: vec4<u32>) {
    if TRAVERSAL_STATS {
        traversal_work += work;
    }
}
