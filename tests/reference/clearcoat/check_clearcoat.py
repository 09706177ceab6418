"""Checks of the gltf_clearcoat Mitsuba plugin (as ../cornell/chi2_check.py checks gltf_brdf):
1. Mitsuba's chi^2 test: sample() distribution vs pdf().
2. eval() against a numpy transcription of the coated model (the base from chi2_check.ref_eval).
3. sample(): its pdf equals pdf(wo), weight * pdf equals eval(wo).
4. E[sample weight] against a uniform-sphere Monte Carlo estimate of the albedo, within 5 standard errors.

Usage:  DRJIT_LIBLLVM_PATH=libLLVM-19.so python3 check_clearcoat.py [variant]
"""
import os
import shutil
import sys
import tempfile

import numpy as np
import mitsuba as mi

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'cornell'))
sys.path.insert(0, HERE)
import chi2_check  # noqa: E402  (sets the variant from argv[1], default llvm_ad_rgb)
import drjit as dr  # noqa: E402
import gltf_clearcoat  # noqa: E402,F401  (registers 'gltf_clearcoat')

BASE = [0.7, 0.1, 0.1]
# (metallic, roughness, clearcoat, clearcoat roughness, view angle in degrees)
CASES = [(0.0, 0.6, 1.0, 0.3, 0.0), (0.0, 0.6, 1.0, 0.3, 45.0), (0.0, 0.6, 1.0, 0.3, 80.0),
         (1.0, 0.4, 0.5, 0.3, 30.0), (0.0, 1.0, 0.8, 0.5, 60.0)]


def ref_eval(wi, wo, m, r, coat, coat_r):
    wi = wi.copy()
    wo = wo.copy()
    flip = wi[:, 2] < 0
    wi[flip, 2] *= -1
    wo[flip, 2] *= -1
    base = chi2_check.ref_eval(wi, wo, BASE, m, r)
    # The coat's lobe alone: a white metal's (F = 1) GGX lobe of its roughness, from the same transcription.
    coat_spec = chi2_check.ref_eval(wi, wo, [1.0, 1.0, 1.0], 1.0, coat_r)
    fc = (coat * (0.04 + 0.96 * (1.0 - np.clip(wi[:, 2], 0.0, 1.0)) ** 5))[:, None]
    return (1.0 - fc) * base + fc * coat_spec


def make(m, r, coat, coat_r):
    return mi.load_dict({'type': 'gltf_clearcoat', 'base_color': BASE, 'metallic': m, 'roughness': r,
                         'clearcoat': coat, 'clearcoat_roughness': coat_r})


def main():
    rng = np.random.default_rng(99)
    fails = 0
    tmp = tempfile.mkdtemp(prefix='coat_chi2_')
    cwd = os.getcwd()
    os.chdir(tmp)
    print('gltf_clearcoat checks, mitsuba %s, variant %s, base_color %s' % (mi.__version__, mi.variant(), BASE))
    for k, (m, r, coat, coat_r, theta) in enumerate(CASES):
        wi = chi2_check.wi_from_theta(theta)
        props = {'type': 'gltf_clearcoat', 'base_color': BASE, 'metallic': m, 'roughness': r,
                 'clearcoat': coat, 'clearcoat_roughness': coat_r}
        sample_func, pdf_func = mi.chi2.BSDFAdapter('gltf_clearcoat', props, wi=wi)
        chi2 = mi.chi2.ChiSquareTest(domain=mi.chi2.SphericalDomain(), sample_func=sample_func,
                                     pdf_func=pdf_func, sample_dim=3, sample_count=1000000, res=101, ires=16,
                                     seed=k + 1)
        chi_ok = bool(chi2.run(0.01, quiet=True))
        bsdf = make(m, r, coat, coat_r)
        n = 20000
        a = rng.normal(size=(n, 3))
        a /= np.linalg.norm(a, axis=1, keepdims=True)
        b = rng.normal(size=(n, 3))
        b /= np.linalg.norm(b, axis=1, keepdims=True)
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(a[:, 0], a[:, 1], a[:, 2])
        val = chi2_check.col_np(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(b[:, 0], b[:, 1], b[:, 2])))
        ref = ref_eval(a, b, m, r, coat, coat_r)
        eval_err = float((np.abs(val - ref) / np.maximum(np.abs(ref), 1e-3)).max())
        n = 400000
        si = chi2_check.make_si(wi, n)
        ctx = mi.BSDFContext()
        u = rng.random((n, 2))
        bs, w = bsdf.sample(ctx, si, mi.Float(rng.random(n)), mi.Point2f(u[:, 0], u[:, 1]))
        pdf_s = np.array(bs.pdf)
        pdf_e = np.array(bsdf.pdf(ctx, si, bs.wo))
        val = chi2_check.col_np(bsdf.eval(ctx, si, bs.wo))
        w = chi2_check.col_np(w)
        ok = pdf_s > 0
        pdf_err = float(np.max(np.abs(pdf_s[ok] - pdf_e[ok]) / pdf_e[ok]))
        wt_err = float(np.max(np.abs(w[ok] * pdf_s[ok, None] - val[ok]) / np.maximum(val[ok], 1e-6)))
        est_s, se_s = w.mean(axis=0), w.std(axis=0) / np.sqrt(n)
        d = rng.normal(size=(4 * n, 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        f = ref_eval(np.tile(np.asarray(wi), (4 * n, 1)), d, m, r, coat, coat_r) * 4 * np.pi
        est_u, se_u = f.mean(axis=0), f.std(axis=0) / np.sqrt(4 * n)
        z = float((np.abs(est_s - est_u) / np.sqrt(se_s ** 2 + se_u ** 2 + 1e-12)).max())
        good = chi_ok and eval_err < 1e-3 and pdf_err < 1e-3 and wt_err < 1e-3 and z < 5.0
        fails += not good
        print('[%s] metallic=%.1f roughness=%.1f clearcoat=%.1f coat_roughness=%.2f wi=%4.0f deg chi2=%s '
              'eval_relerr=%.1e pdf_relerr=%.1e weight_relerr=%.1e albedo sampled=%s uniform=%s (z=%.2f)'
              % ('PASS' if good else 'FAIL', m, r, coat, coat_r, theta, 'pass' if chi_ok else 'FAIL', eval_err,
                 pdf_err, wt_err, np.array2string(est_s, precision=4), np.array2string(est_u, precision=4), z))
    os.chdir(cwd)
    shutil.rmtree(tmp, ignore_errors=True)
    print('%d/%d cases passed' % (len(CASES) - fails, len(CASES)))
    return 0 if fails == 0 else 1


if __name__ == '__main__':
    sys.exit(main())
