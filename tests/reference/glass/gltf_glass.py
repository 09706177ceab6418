"""Smooth glTF glass (KHR_materials_transmission + KHR_materials_ior, roughness 0, metallic 0) as a Mitsuba 3
BSDF plugin, written to the model raykin implements.

Importing this module (after ``mi.set_variant(...)``) registers the plugin under the name ``gltf_glass``.

Parameters (``mi.load_dict``):
    ior        : float > 1, the index inside (KHR_materials_ior).  Default 1.5.
    base_color : RGB triple, tints the transmitted light (glTF baseColorFactor).  Default white.

Model (local shading frame, normal = +z; ``wi`` points towards the previous path vertex):
    cos_i = wi.z.  Entering (cos_i > 0): eta = ior (eta_t / eta_i).  Leaving (cos_i < 0): eta = 1 / ior.
    cos_t = sqrt(1 - (1 - cos_i^2) / eta^2)   (radicand < 0: total internal reflection)
    f0    = ((ior - 1) / (ior + 1))^2
    F     = f0 + (1 - f0) (1 - c)^5 with c the cosine on the air side: c = |cos_i| entering, c = cos_t leaving;
            F = 1 under total internal reflection.
    With probability F: mirror reflection, weight 1.  Otherwise: Snell refraction,
    wo = (-wi.x / eta, -wi.y / eta, -sign(cos_i) cos_t), weight base_color / eta^2 (radiance transport; 1 for
    importance transport).  Both lobes are Dirac deltas: ``eval`` and ``pdf`` are 0.  The returned pdf is the
    lobe's selection probability (F or 1 - F), as Mitsuba's own ``dielectric`` does, and ``bs.eta`` is eta for
    refraction, 1 for reflection.

When the context enables only one of the two lobes, that lobe is taken with probability 1 and its weight carries
F (reflection) or 1 - F (refraction) instead.
"""

import drjit as dr
import mitsuba as mi


class GltfGlass(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.ior = float(props.get('ior', 1.5))
        if not self.ior > 1.0:
            raise ValueError('gltf_glass: ior must be > 1 (got %s)' % self.ior)
        bc = props.get('base_color', [1.0, 1.0, 1.0]) if props.has_property('base_color') else [1.0, 1.0, 1.0]
        if isinstance(bc, (int, float)):
            bc = [bc, bc, bc]
        self.base_color = mi.Color3f(float(bc[0]), float(bc[1]), float(bc[2]))
        self.f0 = ((self.ior - 1.0) / (self.ior + 1.0)) ** 2
        sides = mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
        reflection = mi.BSDFFlags.DeltaReflection | sides
        transmission = mi.BSDFFlags.DeltaTransmission | mi.BSDFFlags.NonSymmetric | sides
        self.m_components = [reflection, transmission]
        self.m_flags = reflection | transmission

    def fresnel(self, cos_i):
        """(F, cos_t, eta) for incident cosine cos_i (signed, local frame); cos_t >= 0."""
        entering = cos_i > 0.0
        eta = dr.select(entering, self.ior, 1.0 / self.ior)
        abs_cos_i = dr.abs(cos_i)
        radicand = 1.0 - (1.0 - cos_i * cos_i) / (eta * eta)
        tir = radicand < 0.0
        cos_t = dr.sqrt(dr.maximum(radicand, 0.0))
        c = dr.select(entering, abs_cos_i, cos_t)
        f = self.f0 + (1.0 - self.f0) * dr.power(1.0 - c, 5.0)
        return dr.select(tir, 1.0, f), cos_t, eta

    def sample(self, ctx, si, sample1, sample2, active=True):
        wi = si.wi
        cos_i = wi.z
        f, cos_t, eta = self.fresnel(cos_i)
        has_r = ctx.is_enabled(mi.BSDFFlags.DeltaReflection, 0)
        has_t = ctx.is_enabled(mi.BSDFFlags.DeltaTransmission, 1)
        both = has_r and has_t
        if both:
            pick_r = sample1 <= f
        else:
            pick_r = mi.Bool(has_r)

        wo_r = mi.Vector3f(-wi.x, -wi.y, wi.z)
        sign = dr.select(cos_i > 0.0, 1.0, -1.0)
        wo_t = mi.Vector3f(-wi.x / eta, -wi.y / eta, -sign * cos_t)

        scale = 1.0 / (eta * eta) if ctx.mode == mi.TransportMode.Radiance else mi.Float(1.0)
        w_t = self.base_color * scale
        if both:
            pdf = dr.select(pick_r, f, 1.0 - f)
            weight = dr.select(pick_r, mi.Color3f(1.0), w_t)
        else:
            pdf = mi.Float(1.0)
            weight = dr.select(pick_r, mi.Color3f(f), w_t * (1.0 - f))

        ok = active & (has_r or has_t) & (cos_i != 0.0) & (pdf > 0.0)
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = dr.select(pick_r, wo_r, wo_t)
        bs.pdf = dr.select(ok, pdf, 0.0)
        bs.eta = dr.select(pick_r, 1.0, eta)
        bs.sampled_component = dr.select(pick_r, mi.UInt32(0), mi.UInt32(1))
        bs.sampled_type = dr.select(pick_r, mi.UInt32(int(mi.BSDFFlags.DeltaReflection)),
                                    mi.UInt32(int(mi.BSDFFlags.DeltaTransmission)))
        return bs, dr.select(ok, weight, 0.0)

    def eval(self, ctx, si, wo, active=True):
        return mi.Color3f(0.0)

    def pdf(self, ctx, si, wo, active=True):
        return mi.Float(0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return mi.Color3f(0.0), mi.Float(0.0)

    def traverse(self, callback):
        pass

    def parameters_changed(self, keys):
        pass

    def to_string(self):
        return 'GltfGlass[ior=%s, base_color=%s]' % (self.ior, self.base_color)


mi.register_bsdf('gltf_glass', lambda props: GltfGlass(props))
