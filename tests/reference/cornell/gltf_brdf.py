"""glTF 2.0 metallic-roughness BRDF (glTF 2.0 specification, Appendix B) as a Mitsuba 3 BSDF plugin.

Importing this module (after ``mi.set_variant(...)``) registers the plugin under the name ``gltf_brdf``.

Parameters (``mi.load_dict``):
    base_color : RGB triple (list/tuple/ScalarColor3f) or a Mitsuba texture dict/object.  Default 0.5.
    metallic   : float in [0, 1].  Default 0.
    roughness  : float in [0, 1] (perceptual roughness; alpha = roughness^2).  Default 0.5.

Model (all evaluated in the local shading frame, N = +z):
    alpha = roughness^2
    D     = alpha^2 chi+(N.H) / (pi ((N.H)^2 (alpha^2 - 1) + 1)^2)
    Vis   = chi+(H.L) chi+(H.V) 0.5 /
            (|N.L| sqrt((N.V)^2 (1 - alpha^2) + alpha^2) + |N.V| sqrt((N.L)^2 (1 - alpha^2) + alpha^2))
    spec  = Vis D
    diff  = baseColor / pi
    F_d   = 0.04 + 0.96 (1 - |V.H|)^5
    F_m   = baseColor + (1 - baseColor) (1 - |V.H|)^5
    f     = (1 - metallic) ((1 - F_d) diff + F_d spec) + metallic F_m spec
``eval`` returns f |N.L| (Mitsuba convention).

Two-sidedness: the BSDF is two-sided (glTF ``doubleSided``).  When the incident direction lies below the
shading frame (wi.z < 0), both directions are mirrored through the tangent plane (z -> -z) before evaluation,
exactly like Mitsuba's ``twosided`` adapter does.  The value is zero unless N.V > 0 and N.L > 0 after that.

Sampling: a one-sample mixture of
    * GGX visible-normal sampling (Heitz 2018, spherical-cap formulation of Dupuy & Benyoub 2023), and
    * cosine-weighted hemisphere sampling,
with mixture weight w_s(wi) (a Fresnel-based estimate of the specular share, clamped to [0.1, 0.9]) that
depends on wi only.  ``pdf`` returns the exact mixture density
    pdf(wo) = w_s pdf_vndf(wo) + (1 - w_s) cos(theta_o) / pi,
    pdf_vndf(wo) = D(H) / (2 (N.V + sqrt(alpha^2 + (1 - alpha^2) (N.V)^2)))      (H = normalize(V + L)),
and ``sample`` returns the weight eval / pdf.

The only deviation from the formula: alpha is clamped below at 1e-4 so that roughness = 0 does not divide by
zero (irrelevant for roughness >= 0.01).
"""

import drjit as dr
import mitsuba as mi

ALPHA_MIN = 1e-4
W_SPEC_MIN = 0.1
W_SPEC_MAX = 0.9


def _ggx_d(h, a2):
    """GGX D of the unit half-vector h (shading frame). The denominator (N.H)^2 (alpha^2 - 1) + 1 is written as
    h.x^2 + h.y^2 + alpha^2 h.z^2 (the same for unit h): at alpha = 1e-4 (roughness 0) the first form cancels to 0
    in f32 next to the peak, D became infinite and the sampled weights NaN (the bench's smooth spheres rendered
    dark, with non-finite pixels)."""
    t = h.x * h.x + h.y * h.y + a2 * h.z * h.z
    return dr.select(h.z > 0.0, a2 / (dr.pi * t * t), 0.0)


def _smith_vis(nl, nv, a2):
    """Height-correlated Smith visibility term V = G2 / (4 |N.L| |N.V|)."""
    nl = dr.abs(nl)
    nv = dr.abs(nv)
    denom = nl * dr.sqrt(nv * nv * (1.0 - a2) + a2) + nv * dr.sqrt(nl * nl * (1.0 - a2) + a2)
    return dr.select(denom > 0.0, 0.5 / denom, 0.0)


def _mean3(c):
    return (c[0] + c[1] + c[2]) * (1.0 / 3.0)


class GltfBRDF(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        bc = props.get('base_color', 0.5) if props.has_property('base_color') else 0.5
        if isinstance(bc, mi.Texture):
            self.base_color = bc
        else:
            if isinstance(bc, (int, float)):
                bc = [bc, bc, bc]
            bc = [float(bc[0]), float(bc[1]), float(bc[2])]
            self.base_color = mi.load_dict({'type': 'rgb', 'value': bc})
        self.metallic = mi.Float(float(props.get('metallic', 0.0)))
        self.roughness = mi.Float(float(props.get('roughness', 0.5)))
        flags = (mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.GlossyReflection |
                 mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide)
        self.m_components = [flags]
        self.m_flags = flags

    # ---------------------------------------------------------------- helpers
    def _alpha2(self):
        alpha = dr.maximum(self.roughness * self.roughness, ALPHA_MIN)
        return alpha, alpha * alpha

    @staticmethod
    def _flip(si):
        """Return (sign, wi_local_flipped) with wi.z >= 0."""
        sign = dr.select(si.wi.z < 0.0, -1.0, 1.0)
        wi = mi.Vector3f(si.wi.x, si.wi.y, si.wi.z * sign)
        return sign, wi

    def _spec_weight(self, wi, bc):
        m = self.metallic
        fc = dr.power(1.0 - dr.clip(wi.z, 0.0, 1.0), 5.0)
        f_d = 0.04 + 0.96 * fc
        f_m = bc + (1.0 - bc) * fc
        spec_est = (1.0 - m) * f_d + m * _mean3(f_m)
        diff_est = (1.0 - m) * (1.0 - f_d) * _mean3(bc)
        tot = spec_est + diff_est
        w = dr.select(tot > 0.0, spec_est / tot, 0.5)
        return dr.clip(w, W_SPEC_MIN, W_SPEC_MAX)

    def _f(self, wi, wo, bc):
        """BRDF value times cos(theta_o), wi.z >= 0 assumed (flipped frame)."""
        alpha, a2 = self._alpha2()
        m = self.metallic
        h = dr.normalize(wi + wo)
        vh = dr.dot(wi, h)
        lh = dr.dot(wo, h)
        d = _ggx_d(h, a2)
        vis = _smith_vis(wo.z, wi.z, a2)
        chi = (vh > 0.0) & (lh > 0.0)
        spec = dr.select(chi, vis * d, 0.0)
        fc = dr.power(1.0 - dr.abs(vh), 5.0)
        f_d = 0.04 + 0.96 * fc
        f_m = bc + (1.0 - bc) * fc
        diffuse = bc * dr.inv_pi
        dielectric = (1.0 - f_d) * diffuse + f_d * spec
        metal = f_m * spec
        f = (1.0 - m) * dielectric + m * metal
        valid = (wi.z > 0.0) & (wo.z > 0.0)
        return dr.select(valid, f * wo.z, 0.0)

    def _pdf(self, wi, wo, w_s):
        alpha, a2 = self._alpha2()
        h = dr.normalize(wi + wo)
        d = _ggx_d(h, a2)
        pdf_vndf = d / (2.0 * (wi.z + dr.sqrt(a2 + (1.0 - a2) * wi.z * wi.z)))
        pdf_cos = wo.z * dr.inv_pi
        pdf = w_s * pdf_vndf + (1.0 - w_s) * pdf_cos
        valid = (wi.z > 0.0) & (wo.z > 0.0)
        return dr.select(valid, pdf, 0.0)

    def _sample_vndf(self, wi, u):
        alpha, a2 = self._alpha2()
        wi_std = dr.normalize(mi.Vector3f(alpha * wi.x, alpha * wi.y, wi.z))
        phi = 2.0 * dr.pi * u.x
        z = (1.0 - u.y) * (1.0 + wi_std.z) - wi_std.z
        sin_t = dr.sqrt(dr.clip(1.0 - z * z, 0.0, 1.0))
        s, c = dr.sincos(phi)
        h_std = mi.Vector3f(sin_t * c + wi_std.x, sin_t * s + wi_std.y, z + wi_std.z)
        h = dr.normalize(mi.Vector3f(alpha * h_std.x, alpha * h_std.y, dr.maximum(h_std.z, 0.0)))
        return 2.0 * dr.dot(wi, h) * h - wi

    # ---------------------------------------------------------------- Mitsuba interface
    def sample(self, ctx, si, sample1, sample2, active=True):
        sign, wi = self._flip(si)
        bc = self.base_color.eval(si, active)
        w_s = self._spec_weight(wi, bc)
        pick_spec = sample1 < w_s
        wo_spec = self._sample_vndf(wi, sample2)
        wo_diff = mi.warp.square_to_cosine_hemisphere(sample2)
        wo = dr.select(pick_spec, wo_spec, wo_diff)
        pdf = self._pdf(wi, wo, w_s)
        val = self._f(wi, wo, bc)
        ok = active & (pdf > 0.0) & (wi.z > 0.0) & (wo.z > 0.0)

        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.Vector3f(wo.x, wo.y, wo.z * sign)
        bs.pdf = dr.select(ok, pdf, 0.0)
        bs.eta = 1.0
        bs.sampled_component = mi.UInt32(0)
        bs.sampled_type = dr.select(pick_spec, mi.UInt32(int(mi.BSDFFlags.GlossyReflection)),
                                    mi.UInt32(int(mi.BSDFFlags.DiffuseReflection)))
        weight = dr.select(ok, val / dr.select(ok, pdf, 1.0), 0.0)
        return bs, mi.Color3f(weight)

    def eval(self, ctx, si, wo, active=True):
        sign, wi = self._flip(si)
        wo = mi.Vector3f(wo.x, wo.y, wo.z * sign)
        bc = self.base_color.eval(si, active)
        return dr.select(active, mi.Color3f(self._f(wi, wo, bc)), 0.0)

    def pdf(self, ctx, si, wo, active=True):
        sign, wi = self._flip(si)
        wo = mi.Vector3f(wo.x, wo.y, wo.z * sign)
        bc = self.base_color.eval(si, active)
        w_s = self._spec_weight(wi, bc)
        return dr.select(active, self._pdf(wi, wo, w_s), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        sign, wi = self._flip(si)
        wo = mi.Vector3f(wo.x, wo.y, wo.z * sign)
        bc = self.base_color.eval(si, active)
        w_s = self._spec_weight(wi, bc)
        val = mi.Color3f(self._f(wi, wo, bc))
        pdf = self._pdf(wi, wo, w_s)
        return dr.select(active, val, 0.0), dr.select(active, pdf, 0.0)

    def traverse(self, callback):
        pass

    def parameters_changed(self, keys):
        pass

    def to_string(self):
        return 'GltfBRDF[metallic=%s, roughness=%s]' % (self.metallic, self.roughness)


mi.register_bsdf('gltf_brdf', lambda props: GltfBRDF(props))
