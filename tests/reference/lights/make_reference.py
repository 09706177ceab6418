"""Mitsuba 3 references for raykin's lights: a point-lit and a directionally lit scene (KHR_lights_punctual), an
environment-lit scene (an HDR map with a small, very bright sun), the environment map's orientation (a map with
marked texels seen through five cameras), and a spot-lit floor for the Rust test's numerical integration.

The script writes the test scenes itself (.gltf with embedded buffers) and the maps (.exr), then renders the
same geometry in Mitsuba with the exact glTF BRDF (../cornell/gltf_brdf.py) and Mitsuba's own `point`,
`directional` and `envmap` emitters. raykin's tests (tests/lights_reference.rs) load the .gltf files and maps
and compare.

Usage (from anywhere):
    export DRJIT_LIBLLVM_PATH=libLLVM.so.19.1
    python3 tests/reference/lights/make_reference.py [--spp-total N] [--chunk C] [--variant V]
"""
import argparse
import base64
import datetime
import json
import math
import os
import struct
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
CORNELL = os.path.join(HERE, '..', 'cornell')

WIDTH = HEIGHT = 64
EYE = [0.0, 2.2, 5.0]
TARGET = [0.0, 0.6, 0.0]
UP = [0.0, 1.0, 0.0]
YFOV_DEG = 40.0
RAYKIN_DEPTH = 3                      # surface bounces
MITSUBA_MAX_DEPTH = RAYKIN_DEPTH + 1  # Mitsuba counts path segments

POINT = dict(position=[1.5, 3.0, 1.0], color=[1.0, 0.9, 0.8], intensity=30.0)
DIRECTIONAL = dict(direction=[-0.4, -1.0, -0.3], color=[1.0, 0.95, 0.9], intensity=3.0)
SPOT = dict(position=[0.3, 2.0, -0.2], color=[1.0, 1.0, 1.0], intensity=20.0,
            inner_cone_angle=math.radians(20.0), outer_cone_angle=math.radians(35.0), range=6.0)
ENV_ROTATION_DEG = 30.0
SUNNY = dict(width=64, height=33, sun_texel=(20, 9), sun_radiance=[900.0, 820.0, 700.0])
MARKED = dict(width=64, height=33, marks=[((0, 16), [1.0, 0.0, 0.0]), ((15, 16), [0.0, 1.0, 0.0]),
                                          ((31, 16), [0.0, 0.0, 1.0]), ((47, 16), [1.0, 1.0, 0.0]),
                                          ((10, 8), [1.0, 0.0, 1.0])])
MARKED_SIZE = 32
MARKED_FOV_DEG = 60.0
# (name, look direction): towards -Z, +X, +Z, -X and up to the magenta mark, each turned a few degrees off the
# mark so that no mark projects onto a pixel border (its brightest pixel is then unambiguous).
MARKED_CAMERAS = [('neg_z', [0.0, 0.0, -1.0]), ('pos_x', [1.0, 0.0, 0.0]), ('pos_z', [0.0, 0.0, 1.0]),
                  ('neg_x', [-1.0, 0.0, 0.0]), ('up', None)]
MARKED_OFFSET_DEG = (10.1, 5.4)  # azimuth, elevation: every mark 0.38 px or more from a pixel border

# name: (base colour, metallic, roughness)
MATERIALS = {
    'floor': ([0.8, 0.8, 0.8], 0.0, 0.6),
    'wall': ([0.5, 0.6, 0.7], 0.0, 0.8),
    'clay': ([0.8, 0.3, 0.2], 0.0, 0.4),
    'brass': ([0.9, 0.8, 0.5], 1.0, 0.35),
}


# ------------------------------------------------------------------ geometry (shared by glTF and Mitsuba)
def quad(corner, edge_u, edge_v):
    """Two triangles, normal = edge_u x edge_v."""
    c, u, v = (np.array(a, dtype=np.float64) for a in (corner, edge_u, edge_v))
    pos = np.array([c, c + u, c + u + v, c + v])
    n = np.cross(u, v)
    n /= np.linalg.norm(n)
    return pos, np.tile(n, (4, 1)), np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)


def box(center, size, yaw_deg):
    """A cube with flat faces (24 vertices), turned about +Y."""
    r = math.radians(yaw_deg)
    rot = np.array([[math.cos(r), 0, math.sin(r)], [0, 1, 0], [-math.sin(r), 0, math.cos(r)]])
    h = size / 2.0
    faces = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = np.zeros(3)
            n[axis] = sign
            a, b = [k for k in range(3) if k != axis]
            u = np.zeros(3)
            v = np.zeros(3)
            u[a] = 2 * h
            v[b] = 2 * h
            if np.dot(np.cross(u, v), n) < 0:
                u, v = v, u
            corner = n * h - u / 2 - v / 2
            faces.append(quad(corner, u, v))
    pos = np.concatenate([f[0] for f in faces]) @ rot.T + np.array(center)
    nrm = np.concatenate([f[1] for f in faces]) @ rot.T
    idx = np.concatenate([f[2] + 4 * k for k, f in enumerate(faces)])
    return pos, nrm, idx


def test_scene_meshes(with_wall=True):
    meshes = [('floor', quad([-4, 0, 4], [8, 0, 0], [0, 0, -8]), 'floor')]
    if with_wall:
        meshes.append(('wall', quad([-4, 0, -2], [8, 0, 0], [0, 4, 0]), 'wall'))
    meshes.append(('clay box', box([-0.6, 0.5, 0.0], 1.0, 0.0), 'clay'))
    meshes.append(('brass box', box([0.9, 0.4, -0.4], 0.8, 30.0), 'brass'))
    return meshes


# ------------------------------------------------------------------ glTF writer
def quat_from_neg_z(d):
    """Unit quaternion (x, y, z, w) turning the local -Z axis onto direction d."""
    d = np.array(d, dtype=np.float64)
    d /= np.linalg.norm(d)
    f = np.array([0.0, 0.0, -1.0])
    c = float(np.dot(f, d))
    if c < -0.999999:
        return [0.0, 1.0, 0.0, 0.0]
    axis = np.cross(f, d)
    q = np.array([axis[0], axis[1], axis[2], 1.0 + c])
    q /= np.linalg.norm(q)
    return [float(x) for x in q]


def write_gltf(path, meshes, lights):
    """meshes: (name, (positions, normals, indices), material name); lights: (node dict, light dict)."""
    blob = bytearray()
    views, accessors, gltf_meshes, nodes = [], [], [], []
    material_names = list(MATERIALS)

    def add_view(data, target):
        while len(blob) % 4:
            blob.append(0)
        views.append(dict(buffer=0, byteOffset=len(blob), byteLength=len(data), target=target))
        blob.extend(data)
        return len(views) - 1

    for name, (pos, nrm, idx), mat in meshes:
        p32 = pos.astype(np.float32)
        n32 = nrm.astype(np.float32)
        vp = add_view(p32.tobytes(), 34962)
        accessors.append(dict(bufferView=vp, componentType=5126, count=len(p32), type='VEC3',
                              min=p32.min(axis=0).tolist(), max=p32.max(axis=0).tolist()))
        vn = add_view(n32.tobytes(), 34962)
        accessors.append(dict(bufferView=vn, componentType=5126, count=len(n32), type='VEC3'))
        vi = add_view(idx.astype(np.uint32).tobytes(), 34963)
        accessors.append(dict(bufferView=vi, componentType=5125, count=int(idx.size), type='SCALAR'))
        gltf_meshes.append(dict(name=name, primitives=[dict(
            attributes=dict(POSITION=len(accessors) - 3, NORMAL=len(accessors) - 2),
            indices=len(accessors) - 1, material=material_names.index(mat))]))
        nodes.append(dict(name=name, mesh=len(gltf_meshes) - 1))
    gltf_lights = []
    for node, light in lights:
        gltf_lights.append(light)
        nodes.append(dict(node, extensions=dict(KHR_lights_punctual=dict(light=len(gltf_lights) - 1))))
    doc = dict(
        asset=dict(version='2.0', generator='raykin tests/reference/lights/make_reference.py'),
        scene=0, scenes=[dict(nodes=list(range(len(nodes))))], nodes=nodes, meshes=gltf_meshes,
        materials=[dict(name=n, doubleSided=True, pbrMetallicRoughness=dict(
            baseColorFactor=MATERIALS[n][0] + [1.0], metallicFactor=MATERIALS[n][1],
            roughnessFactor=MATERIALS[n][2])) for n in material_names],
        accessors=accessors, bufferViews=views,
        buffers=[dict(byteLength=len(blob),
                      uri='data:application/octet-stream;base64,' + base64.b64encode(bytes(blob)).decode())])
    if gltf_lights:
        doc['extensionsUsed'] = ['KHR_lights_punctual']
        doc['extensions'] = dict(KHR_lights_punctual=dict(lights=gltf_lights))
    with open(path, 'w') as f:
        json.dump(doc, f, indent=1)


# ------------------------------------------------------------------ maps
def sunny_map():
    w, h = SUNNY['width'], SUNNY['height']
    img = np.zeros((h, w, 3), dtype=np.float32)
    for j in range(h):
        theta = math.pi * j / (h - 1)
        up = max(math.cos(theta), 0.0)
        img[j, :] = np.array([0.25, 0.35, 0.55]) * (0.3 + up) + np.array([0.05, 0.04, 0.03]) * (theta > math.pi / 2)
    i, j = SUNNY['sun_texel']
    img[j, i] = SUNNY['sun_radiance']
    return img


def marked_map():
    img = np.zeros((MARKED['height'], MARKED['width'], 3), dtype=np.float32)
    for (i, j), c in MARKED['marks']:
        img[j, i] = c
    return img


def map_direction(i, j, w, h):
    """Mitsuba's direction of texel (i, j): u = (i + 1/2) / w, v = j / (h - 1)."""
    u, v = (i + 0.5) / w, j / (h - 1)
    t, p = v * math.pi, u * 2 * math.pi
    return [math.sin(p) * math.sin(t), math.cos(t), -math.cos(p) * math.sin(t)]


def turned(d, azimuth_deg, elevation_deg):
    """d turned about +Y by azimuth, then raised by elevation."""
    x, y, z = d
    a = math.radians(azimuth_deg)
    x, z = math.cos(a) * x + math.sin(a) * z, -math.sin(a) * x + math.cos(a) * z
    horizontal = math.hypot(x, z)
    elevation = math.atan2(y, horizontal) + math.radians(elevation_deg)
    return [x / horizontal * math.cos(elevation), math.sin(elevation), z / horizontal * math.cos(elevation)]


def marked_cameras():
    out = []
    for name, d in MARKED_CAMERAS:
        if d is None:
            (i, j), _ = MARKED['marks'][4]
            d = map_direction(i, j, MARKED['width'], MARKED['height'])
        out.append((name, [float(x) for x in turned(d, *MARKED_OFFSET_DEG)]))
    return out


def project(look, d, size, fov_deg):
    """Image position (x right, y down, pixels) of direction d seen by a camera at the origin looking along
    `look` with +Y up; None behind the camera or outside the image."""
    f = np.array(look) / np.linalg.norm(look)
    right = np.cross(f, UP)
    right /= np.linalg.norm(right)
    up = np.cross(right, f)
    d = np.array(d)
    depth = float(d @ f)
    if depth <= 0:
        return None
    t = math.tan(math.radians(fov_deg) / 2)
    x = (float(d @ right) / depth / t + 1) * 0.5 * size
    y = (1 - float(d @ up) / depth / t) * 0.5 * size
    return (x, y) if 0 <= x < size and 0 <= y < size else None


# ------------------------------------------------------------------ Mitsuba
def make_mesh(mi, dr, name, positions, normals, indices, props):
    mesh = mi.Mesh(name, vertex_count=len(positions), face_count=len(indices), props=props,
                   has_vertex_normals=True, has_vertex_texcoords=False)
    params = mi.traverse(mesh)
    params['vertex_positions'] = dr.ravel(mi.Point3f(*[positions[:, k].astype(np.float32) for k in range(3)]))
    params['vertex_normals'] = dr.ravel(mi.Normal3f(*[normals[:, k].astype(np.float32) for k in range(3)]))
    params['faces'] = dr.ravel(mi.Vector3u(*[indices[:, k].astype(np.uint32) for k in range(3)]))
    params.update()
    return mesh


def sensor(mi, eye, target, fov, size, spp):
    return {
        'type': 'perspective', 'fov': fov, 'fov_axis': 'y', 'near_clip': 0.001, 'far_clip': 1e5,
        'to_world': mi.ScalarTransform4f().look_at(origin=eye, target=target, up=UP),
        'film': {'type': 'hdrfilm', 'width': size, 'height': size, 'rfilter': {'type': 'box'},
                 'pixel_format': 'rgb', 'component_format': 'float32'},
        'sampler': {'type': 'independent', 'sample_count': spp},
    }


def mitsuba_scene(mi, dr, meshes, emitters, spp):
    scene = {'type': 'scene'}
    for k, (name, (pos, nrm, idx), mat) in enumerate(meshes):
        props = mi.Properties()
        bc, metallic, roughness = MATERIALS[mat]
        props['bsdf'] = mi.load_dict({'type': 'gltf_brdf', 'base_color': bc, 'metallic': metallic,
                                      'roughness': roughness})
        scene['shape_%02d' % k] = make_mesh(mi, dr, name, pos, nrm, idx, props)
    scene.update(emitters)
    scene['sensor'] = sensor(mi, EYE, TARGET, YFOV_DEG, WIDTH, spp)
    scene['integrator'] = {'type': 'path', 'max_depth': MITSUBA_MAX_DEPTH, 'hide_emitters': False}
    return mi.load_dict(scene)


def render_accumulated(mi, scene, spp_total, chunk, seed_base):
    passes = spp_total // chunk
    acc = None
    t0 = time.time()
    for i in range(passes):
        img = np.array(mi.render(scene, spp=chunk, seed=seed_base + i), dtype=np.float64)[:, :, :3]
        acc = img if acc is None else acc + img
    return acc / passes, time.time() - t0


def write_exr(mi, path, img):
    mi.Bitmap(np.ascontiguousarray(img.astype(np.float32)), pixel_format=mi.Bitmap.PixelFormat.RGB).write(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--spp-total', type=int, default=16384, help='total spp over both halves, per scene')
    ap.add_argument('--chunk', type=int, default=512)
    ap.add_argument('--marked-spp', type=int, default=1024)
    ap.add_argument('--variant', default='llvm_ad_rgb')
    ap.add_argument('--only', nargs='*', help='render only these scenes (point, directional, envmap, marked)')
    args = ap.parse_args()

    import mitsuba as mi
    mi.set_variant(args.variant)
    import drjit as dr
    sys.path.insert(0, CORNELL)
    import gltf_brdf  # noqa: F401  registers 'gltf_brdf'

    c = np.array(POINT['color']) * POINT['intensity']
    e = np.array(DIRECTIONAL['color']) * DIRECTIONAL['intensity']
    write_gltf(os.path.join(HERE, 'point.gltf'), test_scene_meshes(), [
        (dict(name='point light', translation=POINT['position']),
         dict(name='bulb', type='point', color=POINT['color'], intensity=POINT['intensity']))])
    write_gltf(os.path.join(HERE, 'directional.gltf'), test_scene_meshes(), [
        (dict(name='sun', rotation=quat_from_neg_z(DIRECTIONAL['direction'])),
         dict(name='sun', type='directional', color=DIRECTIONAL['color'], intensity=DIRECTIONAL['intensity']))])
    write_gltf(os.path.join(HERE, 'envmap.gltf'), test_scene_meshes(), [])
    write_gltf(os.path.join(HERE, 'spot.gltf'), test_scene_meshes(with_wall=False)[:1], [
        (dict(name='spot', translation=SPOT['position'], rotation=quat_from_neg_z([0.0, -1.0, 0.0])),
         dict(name='spot', type='spot', color=SPOT['color'], intensity=SPOT['intensity'], range=SPOT['range'],
              spot=dict(innerConeAngle=SPOT['inner_cone_angle'], outerConeAngle=SPOT['outer_cone_angle'])))])
    sunny_path = os.path.join(HERE, 'sunny_64x33.exr')
    marked_path = os.path.join(HERE, 'marked_64x33.exr')
    write_exr(mi, sunny_path, sunny_map())
    write_exr(mi, marked_path, marked_map())

    scenes = {
        'point': (test_scene_meshes(), {'light': {'type': 'point', 'position': POINT['position'],
                                                  'intensity': {'type': 'rgb', 'value': c.tolist()}}}),
        'directional': (test_scene_meshes(), {'light': {
            'type': 'directional', 'direction': DIRECTIONAL['direction'],
            'irradiance': {'type': 'rgb', 'value': e.tolist()}}}),
        'envmap': (test_scene_meshes(), {'light': {
            'type': 'envmap', 'filename': sunny_path,
            'to_world': mi.ScalarTransform4f().rotate([0, 1, 0], ENV_ROTATION_DEG)}}),
    }
    info = dict(
        description=__doc__.split('\n\n')[0],
        mitsuba_version=mi.__version__, drjit_version=dr.__version__, variant=args.variant,
        resolution=[WIDTH, HEIGHT], camera=dict(eye=EYE, target=TARGET, up=UP, yfov_deg=YFOV_DEG,
                                                pixel_filter='box'),
        max_depth=dict(mitsuba_max_depth=MITSUBA_MAX_DEPTH, raykin_depth=RAYKIN_DEPTH),
        materials=MATERIALS, point=POINT, directional=DIRECTIONAL, spot=SPOT,
        envmap=dict(file=os.path.basename(sunny_path), rotation_degrees=ENV_ROTATION_DEG, **SUNNY),
        relMSE_definition='mean over pixels and channels of (a-b)^2 / (((a+b)/2)^2 + 1e-2)',
        scenes={}, host=dict(cpus=os.cpu_count(),
                             date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec='seconds')))
    old = os.path.join(HERE, 'reference.json')
    if os.path.exists(old):
        info['scenes'] = json.load(open(old)).get('scenes', {})
    half = args.spp_total // 2
    chunk = min(args.chunk, half)
    for name, (meshes, emitters) in scenes.items():
        if args.only and name not in args.only:
            continue
        scene = mitsuba_scene(mi, dr, meshes, emitters, chunk)
        print('%s: 2 x %d spp' % (name, half), flush=True)
        a, ta = render_accumulated(mi, scene, half, chunk, 0)
        b, tb = render_accumulated(mi, scene, half, chunk, 1000000)
        write_exr(mi, os.path.join(HERE, '%s_a.exr' % name), a)
        write_exr(mi, os.path.join(HERE, '%s_b.exr' % name), b)
        avg = 0.5 * (a + b)
        rel = float(np.mean((a - b) ** 2 / (avg ** 2 + 1e-2)))
        info['scenes'][name] = dict(files=['%s_a.exr' % name, '%s_b.exr' % name], spp_per_half=half,
                                    render_time_s=round(ta + tb, 1), relMSE_between_halves=rel,
                                    mean_rgb=[float(x) for x in avg.reshape(-1, 3).mean(axis=0)])
        print(json.dumps(info['scenes'][name]), flush=True)
    if not args.only or 'marked' in args.only:
        cams = []
        for name, d in marked_cameras():
            scene = mi.load_dict({
                'type': 'scene',
                'light': {'type': 'envmap', 'filename': marked_path},
                'sensor': sensor(mi, [0.0, 0.0, 0.0], d, MARKED_FOV_DEG, MARKED_SIZE, args.marked_spp),
                'integrator': {'type': 'path', 'max_depth': 1, 'hide_emitters': False}})
            img = np.array(mi.render(scene, spp=args.marked_spp, seed=3), dtype=np.float64)[:, :, :3]
            write_exr(mi, os.path.join(HERE, 'marked_%s.exr' % name), img)
            visible = []
            for (i, j), color in MARKED['marks']:
                at = project(d, map_direction(i, j, MARKED['width'], MARKED['height']), MARKED_SIZE,
                             MARKED_FOV_DEG)
                if at is None:
                    continue
                # The pixel whose score (channels the mark has minus those it lacks) is highest in Mitsuba's image.
                score = (img * np.where(np.array(color) > 0, 1.0, -1.0)).sum(axis=2)
                y, x = np.unravel_index(np.argmax(score), score.shape)
                visible.append(dict(texel=[i, j], projected=[at[0], at[1]], mitsuba_brightest=[int(x), int(y)]))
            cams.append(dict(name=name, look=d, file='marked_%s.exr' % name, visible_marks=visible))
        info['marked'] = dict(map=os.path.basename(marked_path), size=MARKED_SIZE, yfov_deg=MARKED_FOV_DEG,
                              eye=[0.0, 0.0, 0.0], spp=args.marked_spp, cameras=cams,
                              marks=[dict(texel=list(t), color=col) for t, col in MARKED['marks']])
    with open(old, 'w') as f:
        json.dump(info, f, indent=1)
    return 0


if __name__ == '__main__':
    sys.exit(main())
