"""Mitsuba 3 reference for raykin's glass: a smooth glass sphere with an absorbing interior (glTF
KHR_materials_transmission + KHR_materials_ior + KHR_materials_volume) on a diffuse floor, beside a coloured
panel, lit by a smooth environment map.

The script writes the test scene (glass.gltf, embedded buffers) and the map (sky_128x65.exr), then renders the
same triangles and vertex normals in Mitsuba 3 (`volpath`) with the glass as the Python plugin gltf_glass.py,
the sphere's interior a `homogeneous` absorbing medium (sigma_a = -ln(attenuationColor) / attenuationDistance,
albedo 0), and the opaque surfaces with the exact glTF BRDF (../cornell/gltf_brdf.py). raykin's test
(tests/engine/glass_reference.rs) loads the .gltf and the map and compares.

Usage (from anywhere):
    export DRJIT_LIBLLVM_PATH=libLLVM.so.19.1
    python3 tests/reference/glass/make_reference.py [--spp-total N] [--chunk C] [--variant V]
"""
import argparse
import base64
import datetime
import json
import math
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
CORNELL = os.path.join(HERE, '..', 'cornell')

WIDTH = HEIGHT = 64
EYE = [0.0, 1.9, 4.2]
TARGET = [0.0, 0.6, 0.0]
UP = [0.0, 1.0, 0.0]
YFOV_DEG = 35.0
RAYKIN_DEPTH = 8                      # surface interactions after the camera ray
MITSUBA_MAX_DEPTH = RAYKIN_DEPTH + 1  # Mitsuba counts path segments
RR_DEPTH = 1000                       # no Russian roulette within max_depth

SPHERE = dict(center=[0.0, 0.8, 0.0], radius=0.8, segments=64, rings=32)
GLASS = dict(ior=1.5, transmission=1.0, thickness=1.6, attenuation_color=[0.9, 0.5, 0.3],
             attenuation_distance=1.0)
# name: (base colour, metallic, roughness) of the opaque glTF BRDF surfaces
OPAQUE = {
    'floor': ([0.8, 0.8, 0.8], 0.0, 1.0),
    'panel': ([0.2, 0.35, 0.75], 0.0, 1.0),
}
ENV = dict(file='sky_128x65.exr', width=128, height=65, rotation_degrees=0.0,
           zenith=[0.35, 0.5, 0.9], horizon=[0.9, 0.85, 0.8], ground=[0.25, 0.2, 0.15],
           patch_direction=[-0.55, 0.6, -0.58], patch_sigma_deg=10.0, patch_radiance=[12.0, 11.4, 10.2])


# ------------------------------------------------------------------ geometry (shared by glTF and Mitsuba)
def quad(corner, edge_u, edge_v):
    """Two triangles, normal = edge_u x edge_v."""
    c, u, v = (np.array(a, dtype=np.float64) for a in (corner, edge_u, edge_v))
    pos = np.array([c, c + u, c + u + v, c + v])
    n = np.cross(u, v)
    n /= np.linalg.norm(n)
    return pos, np.tile(n, (4, 1)), np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)


def uv_sphere(center, radius, segments, rings):
    """A UV sphere: one vertex at each pole, rings - 1 latitude circles of `segments` vertices; the vertex normals
    are the exact sphere normals; triangles wound counter-clockwise seen from outside."""
    dirs = [[0.0, 1.0, 0.0]]
    for k in range(1, rings):
        theta = math.pi * k / rings
        for s in range(segments):
            phi = 2.0 * math.pi * s / segments
            dirs.append([math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi)])
    dirs.append([0.0, -1.0, 0.0])
    dirs = np.array(dirs)
    south = len(dirs) - 1

    def ring(k, s):  # vertex s of latitude circle k (1-based)
        return 1 + (k - 1) * segments + s % segments

    tris = []
    for s in range(segments):
        tris.append([0, ring(1, s + 1), ring(1, s)])
        tris.append([south, ring(rings - 1, s), ring(rings - 1, s + 1)])
        for k in range(1, rings - 1):
            a, b = ring(k, s), ring(k, s + 1)
            c, d = ring(k + 1, s), ring(k + 1, s + 1)
            tris.append([a, b, d])
            tris.append([a, d, c])
    tris = np.array(tris, dtype=np.uint32)
    pos = np.array(center) + radius * dirs
    # Every triangle faces outwards.
    p = pos[tris]
    outward = np.einsum('ij,ij->i', np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p.mean(axis=1) - center)
    assert (outward > 0).all(), 'sphere winding'
    return pos, dirs, tris


def meshes():
    """(name, (positions, normals, indices), material name), as float32 exactly as both renderers see them."""
    out = [
        ('floor', quad([-3, 0, 3], [6, 0, 0], [0, 0, -6]), 'floor'),
        ('panel', quad([-0.3, 0, -1.6], [3.0, 0, 0], [0, 1.8, 0]), 'panel'),
        ('glass sphere', uv_sphere(SPHERE['center'], SPHERE['radius'], SPHERE['segments'], SPHERE['rings']),
         'glass'),
    ]
    return [(n, (p.astype(np.float32), nr.astype(np.float32), i), m) for n, (p, nr, i), m in out]


# ------------------------------------------------------------------ glTF writer
def gltf_materials():
    mats = [dict(name=n, doubleSided=True, pbrMetallicRoughness=dict(
        baseColorFactor=bc + [1.0], metallicFactor=m, roughnessFactor=r)) for n, (bc, m, r) in OPAQUE.items()]
    mats.append(dict(
        name='glass', pbrMetallicRoughness=dict(baseColorFactor=[1.0, 1.0, 1.0, 1.0], metallicFactor=0.0,
                                                roughnessFactor=0.0),
        extensions=dict(
            KHR_materials_transmission=dict(transmissionFactor=GLASS['transmission']),
            KHR_materials_ior=dict(ior=GLASS['ior']),
            KHR_materials_volume=dict(thicknessFactor=GLASS['thickness'],
                                      attenuationColor=GLASS['attenuation_color'],
                                      attenuationDistance=GLASS['attenuation_distance']))))
    return mats


def write_gltf(path, scene_meshes):
    blob = bytearray()
    views, accessors, gltf_meshes, nodes = [], [], [], []
    material_names = list(OPAQUE) + ['glass']

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
            indices=len(accessors) - 1, material=material_names.index(mat))]))
        nodes.append(dict(name=name, mesh=len(gltf_meshes) - 1))
    doc = dict(
        asset=dict(version='2.0', generator='raykin tests/reference/glass/make_reference.py'),
        extensionsUsed=['KHR_materials_transmission', 'KHR_materials_ior', 'KHR_materials_volume'],
        scene=0, scenes=[dict(nodes=list(range(len(nodes))))], nodes=nodes, meshes=gltf_meshes,
        materials=gltf_materials(), accessors=accessors, bufferViews=views,
        buffers=[dict(byteLength=len(blob),
                      uri='data:application/octet-stream;base64,' + base64.b64encode(bytes(blob)).decode())])
    with open(path, 'w') as f:
        json.dump(doc, f, indent=1)


# ------------------------------------------------------------------ environment map
def map_direction(i, j, w, h):
    """Mitsuba's direction of texel (i, j): u = (i + 1/2) / w, v = j / (h - 1)."""
    u, v = (i + 0.5) / w, j / (h - 1)
    t, p = v * math.pi, u * 2 * math.pi
    return np.array([math.sin(p) * math.sin(t), math.cos(t), -math.cos(p) * math.sin(t)])


def sky_map():
    """A smooth sky: zenith-to-horizon gradient, a darker ground blended in over a few degrees below the
    horizon, and a broad bright Gaussian patch (no small sun, so caustics stay low-noise)."""
    w, h = ENV['width'], ENV['height']
    zenith, horizon, ground = (np.array(ENV[k]) for k in ('zenith', 'horizon', 'ground'))
    centre = np.array(ENV['patch_direction'], dtype=np.float64)
    centre /= np.linalg.norm(centre)
    sigma = math.radians(ENV['patch_sigma_deg'])
    img = np.zeros((h, w, 3), dtype=np.float64)
    for j in range(h):
        for i in range(w):
            d = map_direction(i, j, w, h)
            y = d[1]
            sky = horizon + (zenith - horizon) * math.sqrt(max(y, 0.0))
            g = min(max(-y / math.sin(math.radians(5.0)), 0.0), 1.0)  # 0 at the horizon, 1 from 5 degrees down
            c = sky * (1 - g) + ground * g
            angle = math.acos(min(max(float(d @ centre), -1.0), 1.0))
            c = c + np.array(ENV['patch_radiance']) * math.exp(-0.5 * (angle / sigma) ** 2)
            img[j, i] = c
    return img.astype(np.float32)


# ------------------------------------------------------------------ Mitsuba
def make_mesh(mi, dr, name, positions, normals, indices, props):
    mesh = mi.Mesh(name, vertex_count=len(positions), face_count=len(indices), props=props,
                   has_vertex_normals=True, has_vertex_texcoords=False)
    params = mi.traverse(mesh)
    params['vertex_positions'] = dr.ravel(mi.Point3f(*[positions[:, k] for k in range(3)]))
    params['vertex_normals'] = dr.ravel(mi.Normal3f(*[normals[:, k] for k in range(3)]))
    params['faces'] = dr.ravel(mi.Vector3u(*[indices[:, k].astype(np.uint32) for k in range(3)]))
    params.update()
    return mesh


def sigma_a():
    """Absorption coefficient per RGB channel (KHR_materials_volume): -ln(attenuationColor) / distance."""
    return (-np.log(np.array(GLASS['attenuation_color'])) / GLASS['attenuation_distance']).tolist()


def medium(mi):
    s = np.array(sigma_a())
    scale = float(s.max())
    # `homogeneous` takes sigma_t as an RGB reflectance-like value in [0, 1] times `scale`.
    return mi.load_dict({'type': 'homogeneous', 'albedo': 0.0, 'scale': scale,
                         'sigma_t': {'type': 'rgb', 'value': (s / scale).tolist()}})


def mitsuba_scene(mi, dr, env_path, spp):
    scene = {'type': 'scene'}
    for k, (name, (pos, nrm, idx), mat) in enumerate(meshes()):
        props = mi.Properties()
        if mat == 'glass':
            props['bsdf'] = mi.load_dict({'type': 'gltf_glass', 'ior': GLASS['ior'], 'base_color': [1.0, 1.0, 1.0]})
            props['interior'] = medium(mi)
        else:
            bc, metallic, roughness = OPAQUE[mat]
            props['bsdf'] = mi.load_dict({'type': 'gltf_brdf', 'base_color': bc, 'metallic': metallic,
                                          'roughness': roughness})
        scene['shape_%02d' % k] = make_mesh(mi, dr, name, pos, nrm, idx, props)
    scene['env'] = {'type': 'envmap', 'filename': env_path,
                    'to_world': mi.ScalarTransform4f().rotate([0, 1, 0], ENV['rotation_degrees'])}
    scene['sensor'] = {
        'type': 'perspective', 'fov': YFOV_DEG, 'fov_axis': 'y', 'near_clip': 0.001, 'far_clip': 1e5,
        'to_world': mi.ScalarTransform4f().look_at(origin=EYE, target=TARGET, up=UP),
        'film': {'type': 'hdrfilm', 'width': WIDTH, 'height': HEIGHT, 'rfilter': {'type': 'box'},
                 'pixel_format': 'rgb', 'component_format': 'float32'},
        'sampler': {'type': 'independent', 'sample_count': spp},
    }
    scene['integrator'] = {'type': 'volpath', 'max_depth': MITSUBA_MAX_DEPTH, 'rr_depth': RR_DEPTH,
                           'hide_emitters': False}
    return mi.load_dict(scene)


def render_accumulated(mi, scene, spp_total, chunk, seed_base):
    passes = spp_total // chunk
    acc = None
    t0 = time.time()
    for i in range(passes):
        img = np.array(mi.render(scene, spp=chunk, seed=seed_base + i), dtype=np.float64)[:, :, :3]
        acc = img if acc is None else acc + img
        print('  pass %d/%d, %.0f s' % (i + 1, passes, time.time() - t0), flush=True)
    return acc / passes, time.time() - t0


def write_exr(mi, path, img):
    mi.Bitmap(np.ascontiguousarray(img.astype(np.float32)), pixel_format=mi.Bitmap.PixelFormat.RGB).write(path)


def sphere_pixels():
    """Pixels whose four corners' camera rays all hit the (exact) sphere: the glass's own pixels."""
    f = np.array(TARGET) - np.array(EYE)
    f /= np.linalg.norm(f)
    right = np.cross(f, UP)
    right /= np.linalg.norm(right)
    up = np.cross(right, f)
    t = math.tan(math.radians(YFOV_DEG) / 2)
    c = np.array(SPHERE['center'])
    r = SPHERE['radius']

    def hits(x, y):
        d = f + right * (2 * x / WIDTH - 1) * t + up * (1 - 2 * y / HEIGHT) * t
        d /= np.linalg.norm(d)
        oc = np.array(EYE) - c
        b = float(oc @ d)
        return b * b - (float(oc @ oc) - r * r) > 0

    mask = np.zeros((HEIGHT, WIDTH), dtype=bool)
    for y in range(HEIGHT):
        for x in range(WIDTH):
            mask[y, x] = all(hits(x + dx, y + dy) for dx in (0, 1) for dy in (0, 1))
    return mask


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--spp-total', type=int, default=16384, help='total spp over both halves')
    ap.add_argument('--chunk', type=int, default=512)
    ap.add_argument('--variant', default='llvm_ad_rgb')
    ap.add_argument('--scene-only', action='store_true', help='write the .gltf and the map, render nothing')
    args = ap.parse_args()

    import mitsuba as mi
    mi.set_variant(args.variant)
    import drjit as dr
    sys.path.insert(0, CORNELL)
    sys.path.insert(0, HERE)
    import gltf_brdf  # noqa: F401  registers 'gltf_brdf'
    import gltf_glass  # noqa: F401  registers 'gltf_glass'

    write_gltf(os.path.join(HERE, 'glass.gltf'), meshes())
    env_path = os.path.join(HERE, ENV['file'])
    write_exr(mi, env_path, sky_map())
    if args.scene_only:
        return 0

    half = args.spp_total // 2
    chunk = min(args.chunk, half)
    scene = mitsuba_scene(mi, dr, env_path, chunk)
    print('glass: 2 x %d spp' % half, flush=True)
    a, ta = render_accumulated(mi, scene, half, chunk, 0)
    b, tb = render_accumulated(mi, scene, half, chunk, 1000000)
    write_exr(mi, os.path.join(HERE, 'glass_a.exr'), a)
    write_exr(mi, os.path.join(HERE, 'glass_b.exr'), b)
    avg = 0.5 * (a + b)
    rel = float(np.mean((a - b) ** 2 / (avg ** 2 + 1e-2)))
    mask = sphere_pixels()
    info = dict(
        description=__doc__.split('\n\n')[0],
        mitsuba_version=mi.__version__, drjit_version=dr.__version__, variant=args.variant,
        integrator=dict(type='volpath', max_depth=MITSUBA_MAX_DEPTH, rr_depth=RR_DEPTH, raykin_depth=RAYKIN_DEPTH),
        resolution=[WIDTH, HEIGHT], camera=dict(eye=EYE, target=TARGET, up=UP, yfov_deg=YFOV_DEG,
                                                pixel_filter='box'),
        sphere=SPHERE, glass=dict(GLASS, sigma_a=sigma_a()), opaque_materials=OPAQUE, envmap=ENV,
        files=['glass_a.exr', 'glass_b.exr'], spp_per_half=half, chunk=chunk,
        seeds=dict(a=[0, half // chunk - 1], b=[1000000, 1000000 + half // chunk - 1]),
        render_time_s=round(ta + tb, 1),
        relMSE_definition='mean over pixels and channels of (a-b)^2 / (((a+b)/2)^2 + 1e-2)',
        relMSE_between_halves=rel,
        mean_rgb=[float(x) for x in avg.reshape(-1, 3).mean(axis=0)],
        sphere_pixels=dict(definition='all four pixel corners see the exact sphere', count=int(mask.sum()),
                           mean_rgb=[float(x) for x in avg[mask].mean(axis=0)],
                           mean_rgb_a=[float(x) for x in a[mask].mean(axis=0)],
                           mean_rgb_b=[float(x) for x in b[mask].mean(axis=0)]),
        host=dict(cpus=os.cpu_count(), date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec='seconds')))
    with open(os.path.join(HERE, 'reference.json'), 'w') as f:
        json.dump(info, f, indent=1)
    print(json.dumps({k: info[k] for k in ('render_time_s', 'relMSE_between_halves', 'mean_rgb', 'sphere_pixels')}),
          flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
