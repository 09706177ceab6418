//! Per-vertex tangents from UV derivatives, for normal-mapped meshes whose file has no TANGENT attribute.

use super::MeshData;
use glam::{Vec3, Vec4};

/// Accumulates each triangle's UV-space tangent on its vertices, then orthogonalises against the normal.
/// Returns `None` without UVs. Vertices whose tangent is undefined get a zero tangent: the shader then skips
/// normal mapping there instead of shading with garbage.
pub fn generate(mesh: &MeshData) -> Option<Vec<Vec4>> {
    let uv = mesh.uv0.as_ref()?;
    let n = mesh.positions.len();
    let mut tan = vec![Vec3::ZERO; n];
    let mut bitan = vec![Vec3::ZERO; n];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i as usize);
        let (e1, e2) = (
            mesh.positions[b] - mesh.positions[a],
            mesh.positions[c] - mesh.positions[a],
        );
        let (d1, d2) = (uv[b] - uv[a], uv[c] - uv[a]);
        let det = d1.x * d2.y - d2.x * d1.y;
        if det.abs() < 1e-12 {
            continue;
        }
        let r = 1.0 / det;
        let t_dir = (e1 * d2.y - e2 * d1.y) * r;
        let b_dir = (e2 * d1.x - e1 * d2.x) * r;
        for v in [a, b, c] {
            tan[v] += t_dir;
            bitan[v] += b_dir;
        }
    }
    Some(
        (0..n)
            .map(|v| {
                let normal = mesh.normals.as_ref().map_or(Vec3::ZERO, |ns| ns[v]);
                let t = (tan[v] - normal * normal.dot(tan[v])).normalize_or_zero();
                if t == Vec3::ZERO {
                    return Vec4::ZERO;
                }
                let w = if normal.cross(t).dot(bitan[v]) < 0.0 {
                    -1.0
                } else {
                    1.0
                };
                t.extend(w)
            })
            .collect(),
    )
}
