"""Mitsuba 3 reference for raykin's KHR_materials_clearcoat: a clear-coated red dielectric sphere on a diffuse
floor under the glass reference's sky map (../glass/sky_128x65.exr).

The script writes the test scene (clearcoat.gltf, embedded buffers), then renders the same triangles and vertex
normals in Mitsuba 3 (`path`) with the sphere as the Python plugin gltf_clearcoat.py (checked by
check_clearcoat.py) and the floor as the exact glTF BRDF (../cornell/gltf_brdf.py). The camera, the sphere, the
floor and the map are the glass reference's (its geometry helpers are reused). raykin's test
(tests/engine/clearcoat_reference.rs) loads the .gltf and the map and compares.

Usage (from anywhere):
    export DRJIT_LIBLLVM_PATH=libLLVM-19.so
    python3 tests/reference/clearcoat/make_reference.py [--spp-total N] [--chunk C] [--variant V]
"""

import argparse
import base64
import datetime
import importlib.util
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
GLASS_DIR = os.path.join(HERE, '..', 'glass')
CORNELL = os.path.join(HERE, '..', 'cornell')

_spec = importlib.util.spec_from_file_location('glass_reference', os.path.join(GLASS_DIR, 'make_reference.py'))
glass = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(glass)

WIDTH, HEIGHT = glass.WIDTH, glass.HEIGHT
RAYKIN_DEPTH = 4                      # surface interactions after the camera ray
MITSUBA_MAX_DEPTH = RAYKIN_DEPTH + 1  # Mitsuba counts path segments
RR_DEPTH = 1000                       # no Russian roulette within max_depth
COATED = dict(base_color=[0.7, 0.1, 0.1], metallic=0.0, roughness=0.6, clearcoat=1.0, clearcoat_roughness=0.3)
FLOOR = ([0.8, 0.8, 0.8], 0.0, 1.0)
ENV = dict(file='../glass/sky_128x65.exr', rotation_degrees=0.0)


def meshes():
    s = glass.SPHERE
    out = [('floor', glass.quad([-3, 0, 3], [6, 0, 0], [0, 0, -6]), 'floor'),
           ('coated sphere', glass.uv_sphere(s['center'], s['radius'], s['segments'], s['rings']), 'coated')]
    return [(n, (p.astype(np.float32), nr.astype(np.float32), i), m) for n, (p, nr, i), m in out]


def write_gltf(path, scene_meshes):
    blob = bytearray()
    views, accessors, gltf_meshes, nodes = [], [], [], []
    names = ['floor', 'coated']

    def add_view(data, target):
        while len(blob) % 4:
            blob.append(0)
        views.append(dict(buffer=0, byteOffset=len(blob), byteLength=len(data), target=target))
        blob.extend(data)
        return len(views) - 1

    for name, (pos, nrm, idx), mat in scene_meshes:
        vp = add_view(pos.tobytes(), 34962)
        accessors.append(dict(bufferView=vp, componentType=5126, count=len(pos), type='VEC3',
                              min=pos.min(axis=0).tolist(), max=pos.max(axis=0).tolist()))
        vn = add_view(nrm.tobytes(), 34962)
        accessors.append(dict(bufferView=vn, componentType=5126, count=len(nrm), type='VEC3'))
        vi = add_view(idx.astype(np.uint32).tobytes(), 34963)
        accessors.append(dict(bufferView=vi, componentType=5125, count=int(idx.size), type='SCALAR'))
        gltf_meshes.append(dict(name=name, primitives=[dict(
            attributes=dict(POSITION=len(accessors) - 3, NORMAL=len(accessors) - 2),
            indices=len(accessors) - 1, material=names.index(mat))]))
        nodes.append(dict(name=name, mesh=len(gltf_meshes) - 1))
    bc, m, r = FLOOR
    materials = [
        dict(name='floor', doubleSided=True, pbrMetallicRoughness=dict(
            baseColorFactor=bc + [1.0], metallicFactor=m, roughnessFactor=r)),
        dict(name='coated', doubleSided=True, pbrMetallicRoughness=dict(
            baseColorFactor=COATED['base_color'] + [1.0], metallicFactor=COATED['metallic'],
            roughnessFactor=COATED['roughness']),
            extensions=dict(KHR_materials_clearcoat=dict(
                clearcoatFactor=COATED['clearcoat'], clearcoatRoughnessFactor=COATED['clearcoat_roughness']))),
    ]
    doc = dict(
        asset=dict(version='2.0', generator='raykin tests/reference/clearcoat/make_reference.py'),
        extensionsUsed=['KHR_materials_clearcoat'],
        scene=0, scenes=[dict(nodes=list(range(len(nodes))))], nodes=nodes, meshes=gltf_meshes,
        materials=materials, accessors=accessors, bufferViews=views,
        buffers=[dict(byteLength=len(blob),
                      uri='data:application/octet-stream;base64,' + base64.b64encode(bytes(blob)).decode())])
    with open(path, 'w') as f:
        json.dump(doc, f, indent=1)


def mitsuba_scene(mi, dr, env_path, spp):
    scene = {'type': 'scene'}
    for k, (name, (pos, nrm, idx), mat) in enumerate(meshes()):
        props = mi.Properties()
        if mat == 'coated':
            props['bsdf'] = mi.load_dict(dict(COATED, type='gltf_clearcoat'))
        else:
            bc, metallic, roughness = FLOOR
            props['bsdf'] = mi.load_dict({'type': 'gltf_brdf', 'base_color': bc, 'metallic': metallic,
                                          'roughness': roughness})
        scene['shape_%02d' % k] = glass.make_mesh(mi, dr, name, pos, nrm, idx, props)
    scene['env'] = {'type': 'envmap', 'filename': env_path,
                    'to_world': mi.ScalarTransform4f().rotate([0, 1, 0], ENV['rotation_degrees'])}
    scene['sensor'] = {
        'type': 'perspective', 'fov': glass.YFOV_DEG, 'fov_axis': 'y', 'near_clip': 0.001, 'far_clip': 1e5,
        'to_world': mi.ScalarTransform4f().look_at(origin=glass.EYE, target=glass.TARGET, up=glass.UP),
        'film': {'type': 'hdrfilm', 'width': WIDTH, 'height': HEIGHT, 'rfilter': {'type': 'box'},
                 'pixel_format': 'rgb', 'component_format': 'float32'},
        'sampler': {'type': 'independent', 'sample_count': spp},
    }
    scene['integrator'] = {'type': 'path', 'max_depth': MITSUBA_MAX_DEPTH, 'rr_depth': RR_DEPTH,
                           'hide_emitters': False}
    return mi.load_dict(scene)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--spp-total', type=int, default=65536, help='total spp over both halves')
    ap.add_argument('--chunk', type=int, default=1024)
    ap.add_argument('--variant', default='llvm_ad_rgb')
    args = ap.parse_args()

    import mitsuba as mi
    mi.set_variant(args.variant)
    import drjit as dr
    sys.path.insert(0, CORNELL)
    sys.path.insert(0, HERE)
    import gltf_brdf  # noqa: F401  registers 'gltf_brdf'
    import gltf_clearcoat  # noqa: F401  registers 'gltf_clearcoat'

    write_gltf(os.path.join(HERE, 'clearcoat.gltf'), meshes())
    env_path = os.path.normpath(os.path.join(HERE, ENV['file']))
    half = args.spp_total // 2
    chunk = min(args.chunk, half)
    scene = mitsuba_scene(mi, dr, env_path, chunk)
    print('clearcoat: 2 x %d spp' % half, flush=True)
    a, ta = glass.render_accumulated(mi, scene, half, chunk, 0)
    b, tb = glass.render_accumulated(mi, scene, half, chunk, 1000000)
    glass.write_exr(mi, os.path.join(HERE, 'clearcoat_a.exr'), a)
    glass.write_exr(mi, os.path.join(HERE, 'clearcoat_b.exr'), b)
    avg = 0.5 * (a + b)
    rel = float(np.mean((a - b) ** 2 / (avg ** 2 + 1e-2)))
    mask = glass.sphere_pixels()  # the same camera and sphere as the glass reference
    info = dict(
        description=__doc__.split('\n\n')[0],
        mitsuba_version=mi.__version__, drjit_version=dr.__version__, variant=args.variant,
        integrator=dict(type='path', max_depth=MITSUBA_MAX_DEPTH, rr_depth=RR_DEPTH, raykin_depth=RAYKIN_DEPTH),
        resolution=[WIDTH, HEIGHT],
        camera=dict(eye=glass.EYE, target=glass.TARGET, up=glass.UP, yfov_deg=glass.YFOV_DEG, pixel_filter='box'),
        sphere=glass.SPHERE, coated=COATED, floor=dict(base_color=FLOOR[0], metallic=FLOOR[1], roughness=FLOOR[2]),
        envmap=ENV, files=['clearcoat_a.exr', 'clearcoat_b.exr'], spp_per_half=half, chunk=chunk,
        seeds=dict(a=[0, half // chunk - 1], b=[1000000, 1000000 + half // chunk - 1]),
        render_time_s=round(ta + tb, 1),
        relMSE_definition='mean over pixels and channels of (a-b)^2 / (((a+b)/2)^2 + 1e-2)',
        relMSE_between_halves=rel,
        mean_rgb=[float(x) for x in avg.reshape(-1, 3).mean(axis=0)],
        sphere_pixels=dict(definition='all four pixel corners see the exact sphere', count=int(mask.sum()),
                           mean_rgb=[float(x) for x in avg[mask].mean(axis=0)]),
        host=dict(cpus=os.cpu_count(), date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec='seconds')))
    with open(os.path.join(HERE, 'reference.json'), 'w') as f:
        json.dump(info, f, indent=1)
    print(json.dumps({k: info[k] for k in ('render_time_s', 'relMSE_between_halves', 'mean_rgb', 'sphere_pixels')}),
          flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
