"""The glTF metallic-roughness BRDF (../cornell/gltf_brdf.py) under a KHR_materials_clearcoat layer, as a
Mitsuba 3 BSDF plugin. Importing this module (after ``mi.set_variant(...)``) registers ``gltf_clearcoat``.

Parameters: those of ``gltf_brdf`` (base_color, metallic, roughness) and
    clearcoat           : the coat's weight in [0, 1].  Default 1.
    clearcoat_roughness : perceptual roughness of the coat (alpha = roughness^2).  Default 0.

Model, from the extension's implementation section (fresnel_coat), the coat normal = the shading normal:
    F_coat = 0.04 + 0.96 (1 - |N.V|)^5                     (IOR 1.5, on the coat normal's N.V, not V.H)
    f      = (1 - clearcoat F_coat) f_base + clearcoat F_coat coat_brdf
    coat_brdf = D_coat Vis_coat, the core specification's specular_brdf with alpha = clearcoat_roughness^2
``eval`` returns f |N.L|; two-sided as gltf_brdf (both directions mirrored when wi is below).

Sampling: with probability p_c = clip(clearcoat F_coat / (clearcoat F_coat + (1 - clearcoat F_coat) a_base),
0.1, 0.9) (a_base a rough estimate of the base's albedo) the coat's GGX visible normals, else gltf_brdf's own
mixture with sample1 stretched back to [0, 1); ``pdf`` is the exact mixture
    p_c pdf_vndf_coat + (1 - p_c) pdf_base.
"""

import os
import sys

import drjit as dr
import mitsuba as mi

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'cornell'))
import gltf_brdf  # noqa: E402  (registers 'gltf_brdf')
from gltf_brdf import ALPHA_MIN, GltfBRDF, _ggx_d, _mean3, _smith_vis  # noqa: E402

P_COAT_MIN = 0.1
P_COAT_MAX = 0.9


def _vndf_sample(wi, alpha, u):
    wi_std = dr.normalize(mi.Vector3f(alpha * wi.x, alpha * wi.y, wi.z))
    phi = 2.0 * dr.pi * u.x
    z = (1.0 - u.y) * (1.0 + wi_std.z) - wi_std.z
    sin_t = dr.sqrt(dr.clip(1.0 - z * z, 0.0, 1.0))
    s, c = dr.sincos(phi)
    h_std = mi.Vector3f(sin_t * c + wi_std.x, sin_t * s + wi_std.y, z + wi_std.z)
    h = dr.normalize(mi.Vector3f(alpha * h_std.x, alpha * h_std.y, dr.maximum(h_std.z, 0.0)))
    return 2.0 * dr.dot(wi, h) * h - wi


def _vndf_pdf(wi, wo, a2):
    h = dr.normalize(wi + wo)
    d = _ggx_d(h, a2)
    pdf = d / (2.0 * (wi.z + dr.sqrt(a2 + (1.0 - a2) * wi.z * wi.z)))
    return dr.select((wi.z > 0.0) & (wo.z > 0.0), pdf, 0.0)


class GltfClearcoatBRDF(GltfBRDF):
    def __init__(self, props):
        GltfBRDF.__init__(self, props)
        self.clearcoat = mi.Float(float(props.get('clearcoat', 1.0)))
        self.coat_roughness = mi.Float(float(props.get('clearcoat_roughness', 0.0)))

    def _coat_a2(self):
        alpha = dr.maximum(self.coat_roughness * self.coat_roughness, ALPHA_MIN)
        return alpha, alpha * alpha

    def _coat_weight(self, wi):
        return self.clearcoat * (0.04 + 0.96 * dr.power(1.0 - dr.clip(wi.z, 0.0, 1.0), 5.0))

    def _coat_f(self, wi, wo):
        """coat_brdf |N.L|."""
        _, a2 = self._coat_a2()
        h = dr.normalize(wi + wo)
        spec = _smith_vis(wo.z, wi.z, a2) * _ggx_d(h, a2)
        return dr.select((wi.z > 0.0) & (wo.z > 0.0), spec * wo.z, 0.0)

    def _coated_f(self, wi, wo, bc):
        fc = self._coat_weight(wi)
        return (1.0 - fc) * self._f(wi, wo, bc) + fc * self._coat_f(wi, wo)

    def _p_coat(self, wi, bc):
        fc = self._coat_weight(wi)
        base = (1.0 - self.metallic) * (0.04 + 0.96 * _mean3(bc)) + self.metallic * _mean3(bc)
        total = fc + (1.0 - fc) * base
        return dr.clip(dr.select(total > 0.0, fc / total, 0.5), P_COAT_MIN, P_COAT_MAX)

    def _coated_pdf(self, wi, wo, bc):
        p_c = self._p_coat(wi, bc)
        _, a2 = self._coat_a2()
        return p_c * _vndf_pdf(wi, wo, a2) + (1.0 - p_c) * self._pdf(wi, wo, self._spec_weight(wi, bc))

    def sample(self, ctx, si, sample1, sample2, active=True):
        sign, wi = self._flip(si)
        bc = self.base_color.eval(si, active)
        p_c = self._p_coat(wi, bc)
        pick_coat = sample1 < p_c
        alpha_c, _ = self._coat_a2()
        wo_coat = _vndf_sample(wi, alpha_c, sample2)
        # The rest of sample1's range, stretched back to [0, 1), picks the base's lobe.
        u_base = dr.minimum((sample1 - p_c) / (1.0 - p_c), 0.99999994)
        pick_spec = u_base < self._spec_weight(wi, bc)
        alpha_b, _ = self._alpha2()
        wo_spec = _vndf_sample(wi, alpha_b, sample2)
        wo_diff = mi.warp.square_to_cosine_hemisphere(sample2)
        wo = dr.select(pick_coat, wo_coat, dr.select(pick_spec, wo_spec, wo_diff))
        pdf = self._coated_pdf(wi, wo, bc)
        val = self._coated_f(wi, wo, bc)
        ok = active & (pdf > 0.0) & (wi.z > 0.0) & (wo.z > 0.0)
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.Vector3f(wo.x, wo.y, wo.z * sign)
        bs.pdf = dr.select(ok, pdf, 0.0)
        bs.eta = 1.0
        bs.sampled_component = mi.UInt32(0)
        glossy = pick_coat | pick_spec
        bs.sampled_type = dr.select(glossy, mi.UInt32(int(mi.BSDFFlags.GlossyReflection)),
                                    mi.UInt32(int(mi.BSDFFlags.DiffuseReflection)))
        weight = dr.select(ok, val / dr.select(ok, pdf, 1.0), 0.0)
        return bs, mi.Color3f(weight)

    def eval(self, ctx, si, wo, active=True):
        sign, wi = self._flip(si)
        wo = mi.Vector3f(wo.x, wo.y, wo.z * sign)
        bc = self.base_color.eval(si, active)
        return dr.select(active, mi.Color3f(self._coated_f(wi, wo, bc)), 0.0)

    def pdf(self, ctx, si, wo, active=True):
        sign, wi = self._flip(si)
        wo = mi.Vector3f(wo.x, wo.y, wo.z * sign)
        bc = self.base_color.eval(si, active)
        return dr.select(active, self._coated_pdf(wi, wo, bc), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        sign, wi = self._flip(si)
        wo = mi.Vector3f(wo.x, wo.y, wo.z * sign)
        bc = self.base_color.eval(si, active)
        val = mi.Color3f(self._coated_f(wi, wo, bc))
        pdf = self._coated_pdf(wi, wo, bc)
        return dr.select(active, val, 0.0), dr.select(active, pdf, 0.0)

    def to_string(self):
        return 'GltfClearcoatBRDF[clearcoat=%s, clearcoat_roughness=%s, metallic=%s, roughness=%s]' % (
            self.clearcoat, self.coat_roughness, self.metallic, self.roughness)


mi.register_bsdf('gltf_clearcoat', lambda props: GltfClearcoatBRDF(props))
