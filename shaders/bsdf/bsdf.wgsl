// What every BSDF returns (pbrt-v4 `BxDFFlags`, `BSDFSample`): directions are in the local shading frame
// (z = shading normal), `wo` towards the viewer, `wi` towards the light.

const BSDF_REFLECTION: u32 = 1u;
const BSDF_TRANSMISSION: u32 = 2u;
const BSDF_DIFFUSE: u32 = 4u;
const BSDF_GLOSSY: u32 = 8u;
// A delta lobe: no other strategy can sample it, so it takes no MIS weight.
const BSDF_SPECULAR: u32 = 16u;

struct BsdfSample {
    wi: vec3<f32>,
    // f * |cos| / pdf; zero when the sample failed.
    weight: vec3<f32>,
    pdf: f32,
    // The sampled lobe's BSDF_* flags; 0 when the sample failed.
    flags: u32,
}
