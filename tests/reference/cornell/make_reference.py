"""Mitsuba 3 reference render of the glTF Cornell box with the exact glTF 2.0 (Appendix B) BRDF.

Usage (from anywhere):
    export DRJIT_LIBLLVM_PATH=libLLVM.so.19.1
    python3 tests/reference/cornell/make_reference.py [GLB] [--spp-total N] [--chunk C] [--variant V]
                                                      [--out DIR] [--principled-spp S]

GLB defaults to ../shared/assets/CornellBox/CornellBox.glb relative to the repository root.
Writes into --out (default: this folder):
    cornell_64_a.exr, cornell_64_b.exr   two independent renders, N/2 spp each (linear radiance, RGB float32)
    reference.json                       settings, timings, noise estimate, mean RGB
"""
import argparse
import datetime
import json
import os
import struct
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, '..', '..', '..'))
DEFAULT_GLB_REL = '../shared/assets/CornellBox/CornellBox.glb'

# ------------------------------------------------------------------ conventions shared with raykin
WIDTH = HEIGHT = 64
EYE = [-278.0, 273.0, 800.0]
TARGET = [-278.0, 273.0, 0.0]
UP = [0.0, 1.0, 0.0]
YFOV_DEG = 39.3077
RAYKIN_DEPTH = 8                      # surface bounces
MITSUBA_MAX_DEPTH = RAYKIN_DEPTH + 1  # Mitsuba counts path segments
LIGHT_BACK_OFFSET = 0.001             # +y offset of the reversed copy of each two-sided emissive primitive
# Rigid translation of the whole scene AND camera before it is handed to Mitsuba: None = put the centre of the
# emissive primitives' bounding box at the origin.  Radiance is invariant under it; it only shrinks Mitsuba's
# position-relative ray-spawn offset ((1 + max|p|) * 8.9e-5, i.e. ~0.05 units at |p| ~ 550) near the light,
# whose top sits only 0.89 units below the ceiling.  Set to [0, 0, 0] to render in glTF coordinates.
SCENE_SHIFT = None

# ------------------------------------------------------------------ glTF parsing (numpy only)
_COMP = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_NCOMP = {'SCALAR': 1, 'VEC2': 2, 'VEC3': 3, 'VEC4': 4, 'MAT4': 16}


def load_glb(path):
    data = open(path, 'rb').read()
    magic, version, length = struct.unpack_from('<III', data, 0)
    assert magic == 0x46546C67 and version == 2, 'not a glTF 2.0 binary'
    off = 12
    gltf, binchunk = None, None
    while off < length:
        clen, ctype = struct.unpack_from('<II', data, off)
        chunk = data[off + 8: off + 8 + clen]
        if ctype == 0x4E4F534A:
            gltf = json.loads(chunk.decode('utf-8'))
        elif ctype == 0x004E4942:
            binchunk = chunk
        off += 8 + clen
    return gltf, binchunk


def read_accessor(gltf, binchunk, idx):
    acc = gltf['accessors'][idx]
    bv = gltf['bufferViews'][acc['bufferView']]
    dtype = np.dtype(_COMP[acc['componentType']])
    ncomp = _NCOMP[acc['type']]
    count = acc['count']
    start = bv.get('byteOffset', 0) + acc.get('byteOffset', 0)
    stride = bv.get('byteStride', 0) or dtype.itemsize * ncomp
    raw = np.frombuffer(binchunk, dtype=np.uint8, count=stride * (count - 1) + dtype.itemsize * ncomp,
                        offset=start)
    out = np.empty((count, ncomp), dtype=dtype)
    for i in range(count):
        out[i] = np.frombuffer(raw[i * stride: i * stride + dtype.itemsize * ncomp].tobytes(), dtype=dtype)
    if acc.get('normalized', False) and dtype.kind in 'iu':
        out = out.astype(np.float64) / np.iinfo(dtype).max
        if dtype.kind == 'i':
            out = np.maximum(out, -1.0)
    return out


def quat_to_mat(q):
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def node_matrix(node):
    if 'matrix' in node:
        return np.array(node['matrix'], dtype=np.float64).reshape(4, 4).T  # column-major
    m = np.eye(4)
    t = np.array(node.get('translation', [0, 0, 0]), dtype=np.float64)
    r = quat_to_mat(node.get('rotation', [0, 0, 0, 1]))
    s = np.array(node.get('scale', [1, 1, 1]), dtype=np.float64)
    m[:3, :3] = r @ np.diag(s)
    m[:3, 3] = t
    return m


def gather_primitives(gltf, binchunk):
    """World-space triangle primitives of the default scene: list of dicts."""
    prims = []
    notes = []

    def visit(ni, parent):
        node = gltf['nodes'][ni]
        world = parent @ node_matrix(node)
        if 'mesh' in node:
            mesh = gltf['meshes'][node['mesh']]
            for pi, prim in enumerate(mesh['primitives']):
                assert prim.get('mode', 4) == 4, 'only triangle lists supported'
                attrs = prim['attributes']
                pos = read_accessor(gltf, binchunk, attrs['POSITION']).astype(np.float64)
                nrm = read_accessor(gltf, binchunk, attrs['NORMAL']).astype(np.float64)
                if 'indices' in prim:
                    idx = read_accessor(gltf, binchunk, prim['indices']).reshape(-1, 3).astype(np.uint32)
                else:
                    idx = np.arange(len(pos), dtype=np.uint32).reshape(-1, 3)
                p_w = (world[:3, :3] @ pos.T).T + world[:3, 3]
                n_mat = np.linalg.inv(world[:3, :3]).T
                n_w = (n_mat @ nrm.T).T
                n_w /= np.linalg.norm(n_w, axis=1, keepdims=True)
                if np.linalg.det(world[:3, :3]) < 0:  # mirroring transform flips winding
                    idx = idx[:, [0, 2, 1]]
                color = None
                if 'COLOR_0' in attrs:
                    color = read_accessor(gltf, binchunk, attrs['COLOR_0']).astype(np.float64)[:, :3]
                    notes.append('%s/%d COLOR_0 min %s max %s' % (mesh.get('name'), pi,
                                                                   color.min(axis=0).tolist(),
                                                                   color.max(axis=0).tolist()))
                # agreement of vertex normals with the winding's face normals
                e1 = p_w[idx[:, 1]] - p_w[idx[:, 0]]
                e2 = p_w[idx[:, 2]] - p_w[idx[:, 0]]
                fn = np.cross(e1, e2)
                fn /= np.linalg.norm(fn, axis=1, keepdims=True)
                cosines = np.einsum('ij,ij->i', np.repeat(fn, 3, axis=0), n_w[idx.reshape(-1)])
                prims.append(dict(name='%s_%d' % (mesh.get('name', 'mesh%d' % node['mesh']), pi),
                                  positions=p_w, normals=n_w, indices=idx, color=color,
                                  material=prim.get('material'), min_cos_vn_fn=float(cosines.min())))
        for c in node.get('children', []):
            visit(c, world)

    scene = gltf['scenes'][gltf.get('scene', 0)]
    for ni in scene['nodes']:
        visit(ni, np.eye(4))
    return prims, notes


def material_params(gltf, mi_idx):
    if mi_idx is None:
        return dict(name='default', base_color=[1.0, 1.0, 1.0], metallic=1.0, roughness=1.0,
                    emission=[0.0, 0.0, 0.0], double_sided=False)
    m = gltf['materials'][mi_idx]
    pbr = m.get('pbrMetallicRoughness', {})
    bc = pbr.get('baseColorFactor', [1, 1, 1, 1])[:3]
    strength = m.get('extensions', {}).get('KHR_materials_emissive_strength', {}).get('emissiveStrength', 1.0)
    em = [c * strength for c in m.get('emissiveFactor', [0, 0, 0])]
    for key in ('baseColorTexture', 'metallicRoughnessTexture'):
        assert key not in pbr, 'textures are not supported by this reference script'
    return dict(name=m.get('name'), base_color=[float(c) for c in bc],
                metallic=float(pbr.get('metallicFactor', 1.0)), roughness=float(pbr.get('roughnessFactor', 1.0)),
                emission=[float(c) for c in em], double_sided=bool(m.get('doubleSided', False)))


# ------------------------------------------------------------------ Mitsuba scene
def make_mesh(mi, dr, name, positions, normals, indices, props):
    mesh = mi.Mesh(name, vertex_count=len(positions), face_count=len(indices), props=props,
                   has_vertex_normals=True, has_vertex_texcoords=False)
    params = mi.traverse(mesh)
    params['vertex_positions'] = dr.ravel(mi.Point3f(*[positions[:, k].astype(np.float32) for k in range(3)]))
    params['vertex_normals'] = dr.ravel(mi.Normal3f(*[normals[:, k].astype(np.float32) for k in range(3)]))
    params['faces'] = dr.ravel(mi.Vector3u(*[indices[:, k].astype(np.uint32) for k in range(3)]))
    params.update()
    return mesh


def build_scene(mi, dr, glb_path, spp_per_pass, bsdf_mode='gltf'):
    """bsdf_mode: 'gltf' (exact glTF BRDF plugin) or 'principled' (Mitsuba's built-in, for comparison)."""
    gltf, binchunk = load_glb(glb_path)
    prims, notes = gather_primitives(gltf, binchunk)
    if SCENE_SHIFT is None:
        em = [p['positions'] for p in prims
              if any(c > 0 for c in material_params(gltf, p['material'])['emission'])]
        em = np.concatenate(em) if em else np.zeros((1, 3))
        shift = -0.5 * (em.min(axis=0) + em.max(axis=0))
    else:
        shift = np.asarray(SCENE_SHIFT, dtype=np.float64)
    for p in prims:
        p['positions'] = p['positions'] + shift
    scene = {'type': 'scene'}
    info = dict(primitives=[], notes=list(notes), mitsuba_scene_shift=[float(c) for c in shift])
    for k, p in enumerate(prims):
        mat = material_params(gltf, p['material'])
        if p['color'] is not None and not np.allclose(p['color'], 1.0):
            raise SystemExit('COLOR_0 of %s is not white: per-vertex base colour not implemented' % p['name'])
        if bsdf_mode == 'gltf':
            bsdf = {'type': 'gltf_brdf', 'base_color': mat['base_color'], 'metallic': mat['metallic'],
                    'roughness': mat['roughness']}
            # gltf_brdf is two-sided by itself (mirrors wi/wo to the side of wi, like 'twosided').
            if not mat['double_sided']:
                raise SystemExit('single-sided materials are not handled by this script')
        else:
            bsdf = {'type': 'twosided', 'nested': {
                'type': 'principled', 'base_color': {'type': 'rgb', 'value': mat['base_color']},
                'metallic': mat['metallic'], 'roughness': mat['roughness']}}
        bsdf_obj = mi.load_dict(bsdf)
        emissive = any(c > 0 for c in mat['emission'])
        copies = [(p['positions'], p['normals'], p['indices'], '')]
        if emissive and mat['double_sided']:
            # Mitsuba's area emitter is one-sided: add a reversed copy (winding and normals flipped),
            # offset by LIGHT_BACK_OFFSET along +y, so that the surface emits from both sides.
            copies.append((p['positions'] + np.array([0.0, LIGHT_BACK_OFFSET, 0.0]), -p['normals'],
                           p['indices'][:, [0, 2, 1]], '_back'))
        for (pos, nrm, idx, suffix) in copies:
            props = mi.Properties()
            props['bsdf'] = bsdf_obj
            if emissive:
                props['emitter'] = mi.load_dict({'type': 'area',
                                                 'radiance': {'type': 'rgb', 'value': mat['emission']}})
            mesh = make_mesh(mi, dr, p['name'] + suffix, pos, nrm, idx, props)
            scene['shape_%02d%s' % (k, suffix)] = mesh
        info['primitives'].append(dict(name=p['name'], material=mat['name'], triangles=int(len(p['indices'])),
                                       base_color=mat['base_color'], metallic=mat['metallic'],
                                       roughness=mat['roughness'], emission=mat['emission'],
                                       two_sided_emitter_copy=bool(emissive and mat['double_sided']),
                                       min_cos_vertex_normal_vs_face_normal=p['min_cos_vn_fn']))
    scene['sensor'] = {
        'type': 'perspective', 'fov': YFOV_DEG, 'fov_axis': 'y',
        'near_clip': 0.01, 'far_clip': 1e5,
        'to_world': mi.ScalarTransform4f().look_at(origin=(np.array(EYE) + shift).tolist(),
                                                   target=(np.array(TARGET) + shift).tolist(), up=UP),
        'film': {'type': 'hdrfilm', 'width': WIDTH, 'height': HEIGHT, 'rfilter': {'type': 'box'},
                 'pixel_format': 'rgb', 'component_format': 'float32'},
        'sampler': {'type': 'independent', 'sample_count': spp_per_pass},
    }
    scene['integrator'] = {'type': 'path', 'max_depth': MITSUBA_MAX_DEPTH, 'hide_emitters': False}
    return mi.load_dict(scene), info


def render_accumulated(mi, dr, scene, spp_total, chunk, seed_base, log):
    """Average of spp_total/chunk independent passes (each `chunk` spp) with distinct seeds."""
    assert spp_total % chunk == 0
    passes = spp_total // chunk
    acc = np.zeros((HEIGHT, WIDTH, 3), dtype=np.float64)
    t0 = time.time()
    for i in range(passes):
        img = mi.render(scene, spp=chunk, seed=seed_base + i)
        acc += np.array(img, dtype=np.float64)[:, :, :3]
        if log and (i == 0 or (i + 1) % max(1, passes // 8) == 0):
            el = time.time() - t0
            print('  pass %d/%d  %.1fs elapsed, eta %.0fs' % (i + 1, passes, el, el / (i + 1) * (passes - i - 1)),
                  flush=True)
    return acc / passes, time.time() - t0


def principled_comparison(mi, dr, glb, spp, chunk, ref):
    """Render with Mitsuba's built-in principled BSDF (twosided) and compare brightness with `ref`."""
    chunk = min(chunk, spp)
    pscene, _ = build_scene(mi, dr, glb, chunk, bsdf_mode='principled')
    img_p, t_p = render_accumulated(mi, dr, pscene, spp, chunk, 7, False)
    lum = np.array([0.2126, 0.7152, 0.0722])
    emitter_px = ref.max(axis=2) > 5.0  # pixels that see the light directly (radiance 100)
    res = dict(spp=spp, render_time_s=round(t_p, 1),
               note='Mitsuba built-in principled (wrapped in twosided; specular=0.5 i.e. F0=0.04, other lobes off) '
                    'vs the glTF BRDF, same scene and settings; ratios are principled / glTF; not written as EXR')
    for key, mask in (('all_pixels', np.ones_like(emitter_px)), ('excluding_emitter_pixels', ~emitter_px)):
        mp = img_p[mask].mean(axis=0)
        mr = ref[mask].mean(axis=0)
        res[key] = dict(pixels=int(mask.sum()), mean_rgb_principled=[float(c) for c in mp],
                        mean_rgb_gltf=[float(c) for c in mr], ratio_mean_rgb=[float(c) for c in mp / mr],
                        ratio_mean_luminance=float(mp @ lum / (mr @ lum)))
    return res


def write_exr(mi, path, img):
    bmp = mi.Bitmap(np.ascontiguousarray(img.astype(np.float32)), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.write(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('glb', nargs='?', default=os.path.join(REPO, DEFAULT_GLB_REL))
    ap.add_argument('--spp-total', type=int, default=65536, help='total spp N over both halves')
    ap.add_argument('--chunk', type=int, default=1024, help='spp per render pass')
    ap.add_argument('--variant', default='llvm_ad_rgb')
    ap.add_argument('--out', default=HERE)
    ap.add_argument('--principled-spp', type=int, default=0,
                    help='if > 0, also render with Mitsuba\'s built-in principled BSDF at this spp and record '
                         'the brightness ratio (not written as EXR)')
    ap.add_argument('--principled-only', action='store_true',
                    help='only run the principled comparison against the existing EXRs in --out and add it to '
                         'reference.json')
    ap.add_argument('--seed', type=int, default=0, help='base seed (half a: seed, half b: seed + 1e6)')
    args = ap.parse_args()

    import mitsuba as mi
    mi.set_variant(args.variant)
    import drjit as dr
    sys.path.insert(0, HERE)
    import gltf_brdf  # noqa: F401  registers 'gltf_brdf'

    if args.principled_only:
        # compare against the EXRs already in --out and update reference.json in place
        img_a = np.array(mi.Bitmap(os.path.join(args.out, 'cornell_64_a.exr')), dtype=np.float64)
        img_b = np.array(mi.Bitmap(os.path.join(args.out, 'cornell_64_b.exr')), dtype=np.float64)
        path = os.path.join(args.out, 'reference.json')
        out = json.load(open(path))
        out['principled_comparison'] = principled_comparison(
            mi, dr, args.glb, args.principled_spp or 8192, args.chunk, 0.5 * (img_a + img_b))
        with open(path, 'w') as f:
            json.dump(out, f, indent=2)
        print(json.dumps(out['principled_comparison'], indent=1))
        return 0

    half = args.spp_total // 2
    chunk = min(args.chunk, half)
    assert half % chunk == 0, 'spp per half must be a multiple of --chunk'
    scene, info = build_scene(mi, dr, args.glb, chunk)
    for n in info['notes']:
        print('note:', n)

    print('half a: %d spp' % half, flush=True)
    img_a, t_a = render_accumulated(mi, dr, scene, half, chunk, args.seed, True)
    print('half b: %d spp' % half, flush=True)
    img_b, t_b = render_accumulated(mi, dr, scene, half, chunk, args.seed + 1000000, True)

    os.makedirs(args.out, exist_ok=True)
    write_exr(mi, os.path.join(args.out, 'cornell_64_a.exr'), img_a)
    write_exr(mi, os.path.join(args.out, 'cornell_64_b.exr'), img_b)

    avg = 0.5 * (img_a + img_b)
    rel_between = float(np.mean((img_a - img_b) ** 2 / (avg ** 2 + 1e-2)))
    # orientation check: mean redness of the left vs right image columns
    left, right = avg[:, :WIDTH // 4], avg[:, -(WIDTH // 4):]
    red_left = float(left[..., 0].mean() - left[..., 1].mean())
    red_right = float(right[..., 0].mean() - right[..., 1].mean())

    out = dict(
        description='Mitsuba 3 reference of the glTF Cornell box with the exact glTF 2.0 Appendix B BRDF '
                    '(tests/reference/cornell/gltf_brdf.py). Two independent halves; reference = (a+b)/2.',
        glb=os.path.relpath(os.path.abspath(args.glb), REPO),
        files=dict(a='cornell_64_a.exr', b='cornell_64_b.exr'),
        resolution=[WIDTH, HEIGHT],
        spp_per_half=half, spp_total=2 * half, spp_per_pass=chunk,
        seeds=dict(a='%d..%d' % (args.seed, args.seed + half // chunk - 1),
                   b='%d..%d' % (args.seed + 1000000, args.seed + 1000000 + half // chunk - 1)),
        max_depth=dict(mitsuba_max_depth=MITSUBA_MAX_DEPTH, raykin_depth=RAYKIN_DEPTH,
                       note='Mitsuba max_depth counts path segments; raykin depth counts surface bounces'),
        russian_roulette='Mitsuba default (rr_depth=5), unbiased',
        camera=dict(eye=EYE, target=TARGET, up=UP, yfov_deg=YFOV_DEG, pixel_filter='box',
                    mitsuba='perspective, fov_axis=y, look_at(eye, target, up)'),
        light=dict(radiance=[100.0, 100.0, 100.0], two_sided=True,
                   back_copy_offset_y=LIGHT_BACK_OFFSET,
                   note='Mitsuba area emitters are one-sided: the doubleSided emissive quad gets a second copy with '
                        'reversed winding and normals, offset +y by back_copy_offset_y (see README)'),
        coordinates='camera and geometry are given in glTF world coordinates; both are translated rigidly by '
                    'scene.mitsuba_scene_shift before rendering (radiance is translation invariant)',
        environment='black',
        mitsuba_version=mi.__version__, drjit_version=dr.__version__, variant=args.variant,
        render_time_s=dict(a=round(t_a, 1), b=round(t_b, 1), total=round(t_a + t_b, 1)),
        relMSE_between_halves=rel_between,
        relMSE_reference_estimate=rel_between / 4.0,
        relMSE_definition='mean over pixels and channels of (a-b)^2 / (((a+b)/2)^2 + 1e-2); '
                          'the average (a+b)/2 has relMSE vs truth ~ relMSE_between_halves / 4',
        mean_rgb=[float(c) for c in avg.reshape(-1, 3).mean(axis=0)],
        mean_rgb_a=[float(c) for c in img_a.reshape(-1, 3).mean(axis=0)],
        mean_rgb_b=[float(c) for c in img_b.reshape(-1, 3).mean(axis=0)],
        orientation_check=dict(red_minus_green_left_quarter=red_left, red_minus_green_right_quarter=red_right,
                               red_wall_on_left=bool(red_left > 0 > red_right)),
        scene=info,
        host=dict(cpus=os.cpu_count(), date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec='seconds')),
    )

    if args.principled_spp > 0:
        out['principled_comparison'] = principled_comparison(mi, dr, args.glb, args.principled_spp, chunk, avg)

    with open(os.path.join(args.out, 'reference.json'), 'w') as f:
        json.dump(out, f, indent=2)
    print(json.dumps({k: out[k] for k in ('spp_per_half', 'render_time_s', 'relMSE_between_halves',
                                          'relMSE_reference_estimate', 'mean_rgb', 'orientation_check')
                      if k in out}, indent=1))
    if 'principled_comparison' in out:
        print('principled:', out['principled_comparison'])
    return 0


if __name__ == '__main__':
    sys.exit(main())
