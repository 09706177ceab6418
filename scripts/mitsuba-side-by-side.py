#!/usr/bin/env python3
"""Renders the scenes `raykin bench --export-mitsuba DIR` wrote, in Mitsuba 3, for the bench's side-by-side.

Usage:
    python3 scripts/mitsuba-side-by-side.py DIR [--variant cuda_ad_rgb|llvm_ad_rgb|scalar_rgb] [--scene NAME]...
                                            [--reference-spp N] [--max-spp N] [--repeats R]
                                            [--sampler independent|ldsampler|multijitter|orthogonal|stratified]
    (llvm_ad_rgb here: export DRJIT_LIBLLVM_PATH=libLLVM.so.19.1, see ../shared/TOOLCHAIN.md)

For each DIR/SCENE/scene.json it builds the scene from the export (world-space triangle groups, textures,
environment map, camera), with the exact glTF 2.0 BRDF of tests/reference/cornell/gltf_brdf.py (extended here by a
metallic-roughness texture), Mitsuba's `path` integrator at max_depth = raykin's depth + 1 (Mitsuba counts path
segments) with its default Russian roulette, an `independent` sampler (Mitsuba's default; `--sampler` picks another of
Mitsuba's, e.g. `ldsampler`, its low-discrepancy one, the class of raykin's) and a box pixel filter (scene and camera
centred at the origin, which only changes Mitsuba's ray offsets), and writes into
DIR/SCENE/mitsuba/:
    ref_a.exr, ref_b.exr     two independent halves of the reference (scene.json's reference_spp in all)
    spp_N.exr                one render of N spp per curve sample count, each timed on its own after a warm-up
                             render of the same count (JIT compilation is not counted), device synchronised
and DIR/SCENE/mitsuba.json (variant, device, timings), which `raykin bench --parts errors --mitsuba DIR` reads.

Mitsuba is given the same scene, not the same algorithm: its emitter sampling, BSDF sampling weights and
Russian roulette are its own. What the export could not express is listed in scene.json's `unsupported`.
"""
import argparse
import math
import json
import os
import sys
import time

import numpy as np

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
# Samples per pixel of one `mi.render` call at most: bounds the wavefront's memory on any device.
MAX_SAMPLES_PER_LAUNCH = 1 << 26


def load_arrays(scene_dir, shape):
    blob = os.path.join(scene_dir, 'geometry.bin')
    n, m = shape['vertices'], shape['triangles']

    def f32(offset, count):
        return np.fromfile(blob, dtype='<f4', count=count, offset=offset)

    positions = f32(shape['positions'], 3 * n).reshape(n, 3)
    normals = None if shape['normals'] is None else f32(shape['normals'], 3 * n).reshape(n, 3)
    uvs = None if shape['uvs'] is None else f32(shape['uvs'], 2 * n).reshape(n, 2)
    indices = np.fromfile(blob, dtype='<u4', count=3 * m, offset=shape['indices']).reshape(m, 3)
    return positions, normals, uvs, indices


def bitmap(mi, scene_dir, slot):
    """A Mitsuba bitmap texture for one exported texture slot."""
    m = np.array(slot['to_uv'], dtype=np.float64).reshape(3, 3)
    wrap = {'repeat': 'repeat', 'mirror': 'mirror', 'clamp': 'clamp'}[slot['wrap'][0]]
    return mi.load_dict({
        'type': 'bitmap',
        'filename': os.path.join(scene_dir, slot['file']),
        'raw': not slot['srgb'],
        'filter_type': 'nearest' if slot['filter'] == 'nearest' else 'bilinear',
        'wrap_mode': wrap,
        'to_uv': mi.ScalarTransform3f(m.tolist()),
    })


def make_bsdf_class(mi, dr, gltf_brdf):
    class TexturedGltfBRDF(gltf_brdf.GltfBRDF):
        """The glTF BRDF with metallic (blue) and roughness (green) from a texture, factors baked in."""

        def __init__(self, props):
            gltf_brdf.GltfBRDF.__init__(self, props)
            self.metallic_roughness = (props['metallic_roughness']
                                       if 'metallic_roughness' in props else None)

        def _bind(self, si, active):
            if self.metallic_roughness is not None:
                c = self.metallic_roughness.eval(si, active)
                self.roughness = mi.Float(c[1])
                self.metallic = mi.Float(c[2])

        def sample(self, ctx, si, sample1, sample2, active=True):
            self._bind(si, active)
            return gltf_brdf.GltfBRDF.sample(self, ctx, si, sample1, sample2, active)

        def eval(self, ctx, si, wo, active=True):
            self._bind(si, active)
            return gltf_brdf.GltfBRDF.eval(self, ctx, si, wo, active)

        def pdf(self, ctx, si, wo, active=True):
            self._bind(si, active)
            return gltf_brdf.GltfBRDF.pdf(self, ctx, si, wo, active)

        def eval_pdf(self, ctx, si, wo, active=True):
            self._bind(si, active)
            return gltf_brdf.GltfBRDF.eval_pdf(self, ctx, si, wo, active)

    mi.register_bsdf('gltf_textured', lambda props: TexturedGltfBRDF(props))


def back_offset(positions, normals, indices):
    """Per vertex: a small step along its normal (vertex normals, else the area-weighted face normals)."""
    if normals is None:
        p = positions.astype(np.float64)
        face = np.cross(p[indices[:, 1]] - p[indices[:, 0]], p[indices[:, 2]] - p[indices[:, 0]])
        normals = np.zeros_like(p)
        for c in range(3):
            np.add.at(normals, indices[:, c], face)
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-30)
    eps = 2e-5 * (1.0 + float(np.abs(positions).max()))
    return (eps * normals).astype(np.float32)


def material_bsdf(mi, scene_dir, mat):
    props = {'type': 'gltf_textured', 'metallic': mat['metallic'], 'roughness': mat['roughness']}
    props['base_color'] = (bitmap(mi, scene_dir, mat['base_color_texture'])
                           if mat['base_color_texture'] else mat['base_color'])
    if mat['metallic_roughness_texture']:
        props['metallic_roughness'] = bitmap(mi, scene_dir, mat['metallic_roughness_texture'])
    bsdf = mi.load_dict(props)
    if mat['normal_texture']:
        bsdf = mi.load_dict({'type': 'normalmap', 'normalmap': bitmap(mi, scene_dir, mat['normal_texture']),
                             'bsdf': bsdf})
    if mat['alpha_mode'] != 'opaque':
        opacity = (bitmap(mi, scene_dir, mat['alpha_texture']) if mat['alpha_texture']
                   else {'type': 'rgb', 'value': [mat['alpha']] * 3})
        bsdf = mi.load_dict({'type': 'mask', 'opacity': opacity, 'bsdf': bsdf})
    return bsdf


def build_scene(mi, dr, scene_dir, desc, spp, sampler='independent'):
    scene = {'type': 'scene'}
    bsdfs = {}
    arrays = [load_arrays(scene_dir, shape) for shape in desc['shapes']]
    # The scene and camera moved rigidly so that the geometry's bounds are centred at the origin: radiance does
    # not change, but Mitsuba offsets spawned rays in proportion to the coordinates' magnitude (about 0.05 units at
    # 550 from the origin: enough to leak light past the Cornell box's ceiling light, 0.89 units below it).
    lo = np.min([a[0].min(axis=0) for a in arrays], axis=0) if arrays else np.zeros(3)
    hi = np.max([a[0].max(axis=0) for a in arrays], axis=0) if arrays else np.zeros(3)
    shift = (-0.5 * (lo + hi)).astype(np.float32)
    for k, shape in enumerate(desc['shapes']):
        mat_index = shape['material']
        mat = desc['materials'][mat_index]
        if mat_index not in bsdfs:
            bsdfs[mat_index] = material_bsdf(mi, scene_dir, mat)
        positions, normals, uvs, indices = arrays[k]
        positions = positions + shift
        emissive = max(mat['emission']) > 0.0
        copies = [(positions, indices, '')]
        if emissive and mat['double_sided']:
            # Mitsuba's area emitter emits from the front only: a reversed copy emits from the back. It sits a
            # hair behind the surface (along -normal, well above float rounding), so that rays from the back
            # meet it first and rays from the front meet the original.
            copies.append((positions - back_offset(positions, normals, indices), indices[:, [0, 2, 1]], '_back'))
        for pos, idx, suffix in copies:
            props = mi.Properties()
            props['bsdf'] = bsdfs[mat_index]
            if emissive:
                radiance = (bitmap(mi, scene_dir, mat['emission_texture']) if mat['emission_texture']
                            else {'type': 'rgb', 'value': mat['emission']})
                props['emitter'] = mi.load_dict({'type': 'area', 'radiance': radiance})
            mesh = mi.Mesh('%s%s' % (shape['name'], suffix), vertex_count=len(pos), face_count=len(idx),
                           props=props, has_vertex_normals=normals is not None,
                           has_vertex_texcoords=uvs is not None)
            params = mi.traverse(mesh)
            params['vertex_positions'] = dr.ravel(mi.Point3f(*[pos[:, c] for c in range(3)]))
            if normals is not None:
                sign = -1.0 if suffix else 1.0
                params['vertex_normals'] = dr.ravel(mi.Normal3f(*[sign * normals[:, c] for c in range(3)]))
            if uvs is not None:
                params['vertex_texcoords'] = dr.ravel(mi.Point2f(uvs[:, 0], uvs[:, 1]))
            params['faces'] = dr.ravel(mi.Vector3u(*[idx[:, c].astype(np.uint32) for c in range(3)]))
            params.update()
            scene['shape_%05d%s' % (k, suffix)] = mesh
    env = desc['environment']
    if env is not None:
        scene['environment'] = {
            'type': 'envmap', 'filename': os.path.join(scene_dir, env['file']), 'scale': env['strength'],
            'to_world': mi.ScalarTransform4f().rotate([0, 1, 0], env['rotation_degrees']),
        }
    cam = desc['camera']
    scene['sensor'] = {
        'type': 'perspective', 'fov': cam['yfov_deg'], 'fov_axis': 'y', 'near_clip': 1e-4, 'far_clip': 1e7,
        'to_world': mi.ScalarTransform4f().look_at(origin=(np.array(cam['eye']) + shift).tolist(),
                                                   target=(np.array(cam['target']) + shift).tolist(), up=cam['up']),
        'film': {'type': 'hdrfilm', 'width': desc['width'], 'height': desc['height'], 'rfilter': {'type': 'box'},
                 'pixel_format': 'rgb', 'component_format': 'float32'},
        'sampler': {'type': sampler, 'sample_count': spp},
    }
    scene['integrator'] = {'type': 'path', 'max_depth': desc['raykin_max_depth'] + 1, 'hide_emitters': False}
    return mi.load_dict(scene)


def render(mi, dr, scene, spp, seed, pixels, square=False):
    """One image of `spp` samples per pixel, in launches of at most MAX_SAMPLES_PER_LAUNCH samples, synchronised.
    `square`: every launch's count a power of 4 (the samplers that round other counts up)."""
    per_launch = max(1, min(spp, MAX_SAMPLES_PER_LAUNCH // max(pixels, 1)))
    if square:
        per_launch = 4 ** int(math.log(per_launch, 4) + 1e-9)
    launches = (spp + per_launch - 1) // per_launch
    acc = None
    done = 0
    for i in range(launches):
        n = min(per_launch, spp - done)
        img = mi.render(scene, spp=n, seed=(seed * 1009 + i) & 0xFFFFFFFF)
        dr.eval(img)
        img = img * n
        acc = img if acc is None else acc + img
        done += n
    acc = acc / spp
    dr.eval(acc)
    dr.sync_thread()
    return acc


def write_exr(mi, path, img):
    mi.Bitmap(img, pixel_format=mi.Bitmap.PixelFormat.RGB).write(path)


def device_name(variant):
    if variant.startswith('cuda'):
        try:
            import subprocess
            out = subprocess.run(['nvidia-smi', '--query-gpu=name', '--format=csv,noheader'],
                                 capture_output=True, text=True, timeout=20)
            return out.stdout.strip().splitlines()[0] + ' (CUDA, OptiX)'
        except Exception:  # noqa: BLE001 - the name is informative only
            return 'CUDA device'
    return '%d CPU threads (%s)' % (os.cpu_count(), variant)


def run_scene(mi, dr, scene_dir, args):
    desc = json.load(open(os.path.join(scene_dir, 'scene.json')))
    for item in desc['unsupported']:
        print('%s: not given to Mitsuba: %s' % (desc['scene'], item), file=sys.stderr)
    out_dir = os.path.join(scene_dir, 'mitsuba')
    os.makedirs(out_dir, exist_ok=True)
    # Mitsuba's ldsampler and stratified take square powers of two from 4 only (they round 1 and the others up,
    # which would mislabel a point): launches and curve points in powers of 4.
    square = args.sampler in ('ldsampler', 'stratified')
    t0 = time.perf_counter()
    scene = build_scene(mi, dr, scene_dir, desc, 4 if square else 1, args.sampler)
    load_s = time.perf_counter() - t0
    pixels = desc['width'] * desc['height']
    reference_spp = args.reference_spp or desc['reference_spp']
    half = max(1, reference_spp // 2)
    reference_files = []
    t0 = time.perf_counter()
    for k, name in enumerate(('ref_a.exr', 'ref_b.exr')):
        img = render(mi, dr, scene, half, 7_000_000 + k, pixels, square)
        write_exr(mi, os.path.join(out_dir, name), img)
        reference_files.append('mitsuba/' + name)
    reference_s = time.perf_counter() - t0
    checkpoints = [c for c in desc['checkpoints'] if c <= (args.max_spp or c)]
    if square:
        checkpoints = [c for c in checkpoints if c >= 4 and 4 ** int(math.log(c, 4) + 1e-9) == c]
    points = []
    for spp in checkpoints:
        render(mi, dr, scene, spp, 1, pixels, square)  # warm-up: compiles this launch size's kernels
        times = []
        for r in range(args.repeats):
            t0 = time.perf_counter()
            img = render(mi, dr, scene, spp, 1000 + 17 * r + spp, pixels, square)
            times.append(time.perf_counter() - t0)
        write_exr(mi, os.path.join(out_dir, 'spp_%d.exr' % spp), img)
        seconds = float(np.median(times))
        points.append({'spp': spp, 'seconds': seconds, 'file': 'mitsuba/spp_%d.exr' % spp})
        print('%s: %d spp in %.4f s (%.1f M samples/s)' % (desc['scene'], spp, seconds,
                                                          pixels * spp / seconds / 1e6), file=sys.stderr)
    result = {
        'variant': args.variant, 'mitsuba_version': mi.__version__, 'drjit_version': dr.__version__,
        'device': device_name(args.variant), 'scene_load_s': load_s,
        'reference': {'spp': 2 * half, 'files': reference_files, 'seconds': reference_s},
        'points': points, 'integrator': 'path, max_depth = raykin depth + 1, default rr_depth 5',
        'sampler': args.sampler,
        'unsupported': desc['unsupported'],
    }
    with open(os.path.join(scene_dir, 'mitsuba.json'), 'w') as f:
        json.dump(result, f, indent=2)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('dir')
    ap.add_argument('--variant', default='cuda_ad_rgb')
    ap.add_argument('--scene', action='append', default=[])
    ap.add_argument('--reference-spp', type=int, default=0, help='default: scene.json\'s (the bench suite\'s)')
    ap.add_argument('--max-spp', type=int, default=0, help='largest curve sample count (default: scene.json\'s)')
    ap.add_argument('--repeats', type=int, default=3, help='timed renders per sample count (median)')
    ap.add_argument('--sampler', default='independent', help='Mitsuba sampler plugin (default: its default)')
    args = ap.parse_args()

    import mitsuba as mi
    mi.set_variant(args.variant)
    import drjit as dr
    sys.path.insert(0, os.path.join(REPO, 'tests', 'reference', 'cornell'))
    import gltf_brdf
    make_bsdf_class(mi, dr, gltf_brdf)

    scenes = args.scene or sorted(d for d in os.listdir(args.dir)
                                  if os.path.exists(os.path.join(args.dir, d, 'scene.json')))
    if not scenes:
        sys.exit('%s: no exported scenes (run raykin bench --export-mitsuba %s first)' % (args.dir, args.dir))
    failed = []
    for name in scenes:
        print('mitsuba-side-by-side: %s (%s)' % (name, args.variant), file=sys.stderr)
        try:
            run_scene(mi, dr, os.path.join(args.dir, name), args)
        except Exception as e:  # noqa: BLE001 - one scene's failure must not lose the others
            print('mitsuba-side-by-side: %s failed: %r' % (name, e), file=sys.stderr)
            failed.append(name)
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
