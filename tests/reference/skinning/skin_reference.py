#!/usr/bin/env python3
"""Independent reference implementation of glTF 2.0 animation sampling,
morph targets and skinning (Python + numpy only).

This is test-fixture generation code for the raykin engine; it deliberately
shares no code with the engine.  Everything is computed in float64.

Semantics (see README.md in this folder):
  * time is CLAMPED per channel to [first key, last key] (no looping);
  * STEP / LINEAR / CUBICSPLINE samplers as in the glTF 2.0 spec, appendix C;
    LINEAR rotations use slerp along the shortest path (the second quaternion
    is negated when dot < 0), the result is normalised; CUBICSPLINE rotations
    are normalised after the Hermite evaluation;
  * node local matrix = node.matrix if present, else T * R * S;
  * morph weights: animated weights > node.weights > mesh.weights > zeros;
  * joint matrix j = global(joint j) * inverseBindMatrix j (identity if the skin
    has no inverseBindMatrices);
  * skinned vertex = sum_i w_i * jointMatrix[j_i] * morphedPosition over all
    JOINTS_n/WEIGHTS_n sets, weights renormalised to sum 1; the skinned mesh
    node's own transform is ignored;
  * non-skinned mesh: world = global(node) * morphedPosition.
"""

import base64
import json
import math
import os
import struct

import numpy as np

# --------------------------------------------------------------------------
# Loading
# --------------------------------------------------------------------------

GLB_MAGIC = 0x46546C67
CHUNK_JSON = 0x4E4F534A
CHUNK_BIN = 0x004E4942

COMPONENT_DTYPES = {
    5120: np.dtype('<i1'),
    5121: np.dtype('<u1'),
    5122: np.dtype('<i2'),
    5123: np.dtype('<u2'),
    5125: np.dtype('<u4'),
    5126: np.dtype('<f4'),
}

TYPE_COMPONENTS = {
    'SCALAR': 1, 'VEC2': 2, 'VEC3': 3, 'VEC4': 4,
    'MAT2': 4, 'MAT3': 9, 'MAT4': 16,
}


class Gltf:
    """A parsed glTF document: .json (dict), .buffers (list of bytes)."""

    def __init__(self, path):
        self.path = path
        base = os.path.dirname(os.path.abspath(path))
        with open(path, 'rb') as f:
            data = f.read()
        glb_bin = None
        if len(data) >= 12 and struct.unpack_from('<I', data, 0)[0] == GLB_MAGIC:
            version, total = struct.unpack_from('<II', data, 4)
            if version != 2:
                raise ValueError('unsupported GLB version %d' % version)
            off = 12
            js = None
            while off + 8 <= min(total, len(data)):
                clen, ctype = struct.unpack_from('<II', data, off)
                chunk = data[off + 8: off + 8 + clen]
                if ctype == CHUNK_JSON and js is None:
                    js = json.loads(chunk.decode('utf-8'))
                elif ctype == CHUNK_BIN and glb_bin is None:
                    glb_bin = chunk
                off += 8 + clen
                off = (off + 3) & ~3
            if js is None:
                raise ValueError('GLB without JSON chunk')
            self.json = js
        else:
            self.json = json.loads(data.decode('utf-8'))
        self.buffers = []
        for i, b in enumerate(self.json.get('buffers', [])):
            uri = b.get('uri')
            if uri is None:
                if glb_bin is None:
                    raise ValueError('buffer %d has no uri and there is no GLB BIN chunk' % i)
                raw = glb_bin
            elif uri.startswith('data:'):
                header, _, payload = uri.partition(',')
                if not header.endswith(';base64'):
                    raise ValueError('only base64 data URIs are supported')
                raw = base64.b64decode(payload)
            else:
                from urllib.parse import unquote
                with open(os.path.join(base, unquote(uri)), 'rb') as f:
                    raw = f.read()
            if len(raw) < b['byteLength']:
                raise ValueError('buffer %d shorter than byteLength' % i)
            self.buffers.append(raw[:b['byteLength']])
        self._acc_cache = {}

    # ---------------------------------------------------------------- accessors
    def _read_view(self, view_index, byte_offset, count, comp_dtype, ncomp, mat_cols=None):
        """Read `count` elements from a bufferView.  Returns (count, ncomp) array
        of the raw component dtype.  Handles byteStride and the column padding of
        matrices with 1- or 2-byte components."""
        view = self.json['bufferViews'][view_index]
        buf = self.buffers[view['buffer']]
        start = view.get('byteOffset', 0) + byte_offset
        csize = comp_dtype.itemsize
        if mat_cols is not None:
            rows = ncomp // mat_cols
            col_bytes = rows * csize
            col_stride = (col_bytes + 3) & ~3  # columns start on 4-byte boundaries
            elem_size = col_stride * mat_cols
        else:
            elem_size = ncomp * csize
        stride = view.get('byteStride', 0) or elem_size
        if count == 0:
            return np.zeros((0, ncomp), dtype=comp_dtype)
        end = start + (count - 1) * stride + elem_size
        if end > view.get('byteOffset', 0) + view['byteLength'] or end > len(buf):
            raise ValueError('accessor overruns bufferView %d' % view_index)
        if mat_cols is None:
            arr = np.ndarray(shape=(count, ncomp), dtype=comp_dtype, buffer=buf,
                             offset=start, strides=(stride, csize))
            return np.array(arr, copy=True)
        out = np.empty((count, ncomp), dtype=comp_dtype)
        rows = ncomp // mat_cols
        for c in range(mat_cols):
            arr = np.ndarray(shape=(count, rows), dtype=comp_dtype, buffer=buf,
                             offset=start + c * col_stride, strides=(stride, csize))
            out[:, c * rows:(c + 1) * rows] = arr
        return out

    def accessor_raw(self, index):
        """Accessor contents in the raw component type (sparse applied),
        shape (count, ncomp)."""
        acc = self.json['accessors'][index]
        dt = COMPONENT_DTYPES[acc['componentType']]
        ncomp = TYPE_COMPONENTS[acc['type']]
        count = acc['count']
        mat_cols = None
        if acc['type'].startswith('MAT') and dt.itemsize < 4:
            mat_cols = int(acc['type'][3])
        if 'bufferView' in acc:
            data = self._read_view(acc['bufferView'], acc.get('byteOffset', 0), count, dt, ncomp, mat_cols)
        else:
            data = np.zeros((count, ncomp), dtype=dt)
        sp = acc.get('sparse')
        if sp:
            n = sp['count']
            idx_info = sp['indices']
            idx_dt = COMPONENT_DTYPES[idx_info['componentType']]
            view = self.json['bufferViews'][idx_info['bufferView']]
            off = view.get('byteOffset', 0) + idx_info.get('byteOffset', 0)
            idx = np.frombuffer(self.buffers[view['buffer']], dtype=idx_dt, count=n, offset=off)
            val_info = sp['values']
            vals = self._read_view(val_info['bufferView'], val_info.get('byteOffset', 0), n, dt, ncomp, mat_cols)
            data = data.copy()
            data[idx.astype(np.int64)] = vals
        return data

    def accessor(self, index):
        """Accessor contents as float64 (normalized integers converted per the
        spec), shape (count, ncomp)."""
        if index in self._acc_cache:
            return self._acc_cache[index]
        acc = self.json['accessors'][index]
        raw = self.accessor_raw(index)
        ct = acc['componentType']
        if ct == 5126:
            out = raw.astype(np.float64)
        elif acc.get('normalized', False):
            if ct == 5121:
                out = raw.astype(np.float64) / 255.0
            elif ct == 5123:
                out = raw.astype(np.float64) / 65535.0
            elif ct == 5120:
                out = np.maximum(raw.astype(np.float64) / 127.0, -1.0)
            elif ct == 5122:
                out = np.maximum(raw.astype(np.float64) / 32767.0, -1.0)
            else:
                raise ValueError('normalized u32 is not allowed')
        else:
            out = raw.astype(np.float64)
        self._acc_cache[index] = out
        return out

    def accessor_int(self, index):
        return self.accessor_raw(index).astype(np.int64)


# --------------------------------------------------------------------------
# Math helpers (column vectors, glTF quaternion order x, y, z, w)
# --------------------------------------------------------------------------

def quat_normalize(q):
    q = np.asarray(q, dtype=np.float64)
    n = np.linalg.norm(q)
    if n == 0.0:
        return np.array([0.0, 0.0, 0.0, 1.0])
    return q / n


def quat_to_mat3(q):
    x, y, z, w = quat_normalize(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def trs_matrix(t, r, s):
    m = np.eye(4)
    m[:3, :3] = quat_to_mat3(r) * np.asarray(s, dtype=np.float64)[None, :]
    m[:3, 3] = t
    return m


def slerp(a, b, u):
    """Shortest-path spherical linear interpolation, normalised result."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    d = float(np.dot(a, b))
    if d < 0.0:
        b = -b
        d = -d
    if d > 1.0 - 1e-12:
        # (nearly) identical: linear interpolation is exact to rounding.
        r = (1.0 - u) * a + u * b
    else:
        d = min(d, 1.0)
        theta = math.acos(d)
        st = math.sin(theta)
        r = (math.sin((1.0 - u) * theta) / st) * a + (math.sin(u * theta) / st) * b
    return quat_normalize(r)


# --------------------------------------------------------------------------
# Animation sampling
# --------------------------------------------------------------------------

def sample(times, values, interpolation, t, is_quat=False):
    """Sample an animation sampler.

    times:  (n,) key times (strictly increasing)
    values: (n, c) for STEP/LINEAR, (3n, c) for CUBICSPLINE laid out per key as
            [in-tangent, value, out-tangent] (c components per element).
    Returns a (c,) float64 array.  t is clamped to [times[0], times[-1]].
    """
    times = np.asarray(times, dtype=np.float64).reshape(-1)
    values = np.asarray(values, dtype=np.float64)
    n = len(times)
    cubic = interpolation == 'CUBICSPLINE'
    if cubic:
        assert values.shape[0] == 3 * n, (values.shape, n)

        def val(k):
            return values[3 * k + 1]
    else:
        assert values.shape[0] == n, (values.shape, n)

        def val(k):
            return values[k]

    def finish(v):
        v = np.array(v, dtype=np.float64)
        return quat_normalize(v) if is_quat else v

    if n == 1 or t <= times[0]:
        return finish(val(0))
    if t >= times[-1]:
        return finish(val(n - 1))
    # k such that times[k] <= t < times[k+1]
    k = int(np.searchsorted(times, t, side='right')) - 1
    k = max(0, min(k, n - 2))
    t0, t1 = times[k], times[k + 1]
    dt = t1 - t0
    u = (t - t0) / dt
    if interpolation == 'STEP':
        return finish(val(k))
    if interpolation == 'LINEAR':
        if is_quat:
            return slerp(val(k), val(k + 1), u)
        return finish((1.0 - u) * val(k) + u * val(k + 1))
    if cubic:
        p0 = values[3 * k + 1]
        m0 = dt * values[3 * k + 2]        # out-tangent of key k
        p1 = values[3 * (k + 1) + 1]
        m1 = dt * values[3 * (k + 1)]      # in-tangent of key k+1
        u2, u3 = u * u, u * u * u
        h00 = 2 * u3 - 3 * u2 + 1
        h10 = u3 - 2 * u2 + u
        h01 = -2 * u3 + 3 * u2
        h11 = u3 - u2
        return finish(h00 * p0 + h10 * m0 + h01 * p1 + h11 * m1)
    raise ValueError('unknown interpolation %r' % interpolation)


def morph_target_count(doc, mesh_index):
    mesh = doc.json['meshes'][mesh_index]
    return max((len(p.get('targets', [])) for p in mesh['primitives']), default=0)


def clip_channels(doc, anim_index):
    """List of (node, path, times, values, interpolation, components)."""
    anim = doc.json['animations'][anim_index]
    out = []
    for ch in anim['channels']:
        tgt = ch['target']
        if 'node' not in tgt:
            continue
        smp = anim['samplers'][ch['sampler']]
        interp = smp.get('interpolation', 'LINEAR')
        times = doc.accessor(smp['input'])[:, 0]
        vals = doc.accessor(smp['output'])
        path = tgt['path']
        if path == 'weights':
            node = doc.json['nodes'][tgt['node']]
            ntg = morph_target_count(doc, node['mesh'])
            vals = vals.reshape(-1, ntg)
        out.append((tgt['node'], path, times, vals, interp))
    return out


def clip_duration(doc, anim_index):
    return max(float(times[-1]) for (_, _, times, _, _) in clip_channels(doc, anim_index))


def sample_clip(doc, anim_index, t):
    """Returns {node: {'translation'|'rotation'|'scale'|'weights': value}}."""
    pose = {}
    for node, path, times, vals, interp in clip_channels(doc, anim_index):
        v = sample(times, vals, interp, t, is_quat=(path == 'rotation'))
        pose.setdefault(node, {})[path] = v
    return pose


# --------------------------------------------------------------------------
# Scene graph
# --------------------------------------------------------------------------

def local_matrix(node, anim=None):
    anim = anim or {}
    if 'matrix' in node and not anim:
        return np.array(node['matrix'], dtype=np.float64).reshape(4, 4).T  # column-major
    if 'matrix' in node:
        # Animated node with a matrix is invalid glTF; decompose is not needed
        # for the assets in use.  Refuse loudly rather than guess.
        raise ValueError('animated node has a matrix')
    t = anim.get('translation', node.get('translation', [0.0, 0.0, 0.0]))
    r = anim.get('rotation', node.get('rotation', [0.0, 0.0, 0.0, 1.0]))
    s = anim.get('scale', node.get('scale', [1.0, 1.0, 1.0]))
    return trs_matrix(t, r, s)


def global_matrices(doc, pose=None):
    """Global matrix for every node (parent chains follow `children`)."""
    pose = pose or {}
    nodes = doc.json.get('nodes', [])
    parent = [None] * len(nodes)
    for i, n in enumerate(nodes):
        for c in n.get('children', []):
            if parent[c] is not None:
                raise ValueError('node %d has two parents' % c)
            parent[c] = i
    local = [local_matrix(n, pose.get(i)) for i, n in enumerate(nodes)]
    glob = [None] * len(nodes)

    def g(i):
        if glob[i] is None:
            glob[i] = local[i] if parent[i] is None else g(parent[i]) @ local[i]
        return glob[i]

    for i in range(len(nodes)):
        g(i)
    return glob


def scene_nodes(doc, scene=None):
    """All nodes reachable from the scene (pre-order, roots in order)."""
    if scene is None:
        scene = doc.json.get('scene', 0)
    roots = doc.json['scenes'][scene].get('nodes', [])
    out = []
    stack = list(reversed(roots))
    while stack:
        i = stack.pop()
        out.append(i)
        stack.extend(reversed(doc.json['nodes'][i].get('children', [])))
    return out


# --------------------------------------------------------------------------
# Morphing and skinning
# --------------------------------------------------------------------------

def node_morph_weights(doc, node_index, pose=None):
    node = doc.json['nodes'][node_index]
    mesh = doc.json['meshes'][node['mesh']]
    ntg = morph_target_count(doc, node['mesh'])
    anim = (pose or {}).get(node_index, {})
    if 'weights' in anim:
        w = anim['weights']
    elif 'weights' in node:
        w = node['weights']
    elif 'weights' in mesh:
        w = mesh['weights']
    else:
        w = [0.0] * ntg
    return np.asarray(w, dtype=np.float64).reshape(-1)


def morphed_attribute(doc, prim, name, weights):
    base = doc.accessor(prim['attributes'][name]).copy()
    for ti, tgt in enumerate(prim.get('targets', [])):
        if name in tgt and ti < len(weights) and weights[ti] != 0.0:
            base = base + weights[ti] * doc.accessor(tgt[name])
    return base


def joint_matrices(doc, skin_index, glob):
    skin = doc.json['skins'][skin_index]
    joints = skin['joints']
    if 'inverseBindMatrices' in skin:
        ibm = doc.accessor(skin['inverseBindMatrices']).reshape(-1, 4, 4).transpose(0, 2, 1)
    else:
        ibm = np.broadcast_to(np.eye(4), (len(joints), 4, 4))
    return np.stack([glob[j] @ ibm[k] for k, j in enumerate(joints)])


def skin_sets(doc, prim):
    """(joints (n, 4k) int, weights (n, 4k) float) over all JOINTS_n/WEIGHTS_n."""
    attrs = prim['attributes']
    js, ws = [], []
    s = 0
    while 'JOINTS_%d' % s in attrs and 'WEIGHTS_%d' % s in attrs:
        js.append(doc.accessor_int(attrs['JOINTS_%d' % s]))
        ws.append(doc.accessor(attrs['WEIGHTS_%d' % s]))
        s += 1
    if not js:
        return None, None
    return np.concatenate(js, axis=1), np.concatenate(ws, axis=1)


def skin_positions(positions, joints, weights, jmats):
    """Linear blend skinning; weights renormalised to sum 1 (rows summing to 0
    are left as-is, which yields the origin; none of the assets have any)."""
    w = weights.copy()
    sums = w.sum(axis=1, keepdims=True)
    ok = sums[:, 0] > 0
    w[ok] /= sums[ok]
    # blended matrix per vertex
    m = np.einsum('vi,vijk->vjk', w, jmats[joints])
    p = np.concatenate([positions, np.ones((len(positions), 1))], axis=1)
    out = np.einsum('vjk,vk->vj', m, p)
    return out[:, :3]


def transform_points(mat, pts):
    return pts @ mat[:3, :3].T + mat[:3, 3]


def evaluate(doc, anim_index=None, t=0.0, scene=None):
    """World-space positions of every mesh node of the scene.

    Returns list of dicts: {node, mesh, skinned, primitives: [{primitive,
    positions (n,3)}]}.  anim_index None = static (rest) pose."""
    pose = sample_clip(doc, anim_index, t) if anim_index is not None else {}
    glob = global_matrices(doc, pose)
    result = []
    for ni in scene_nodes(doc, scene):
        node = doc.json['nodes'][ni]
        if 'mesh' not in node:
            continue
        mesh = doc.json['meshes'][node['mesh']]
        weights = node_morph_weights(doc, ni, pose)
        skinned = 'skin' in node
        jm = joint_matrices(doc, node['skin'], glob) if skinned else None
        prims = []
        for pi, prim in enumerate(mesh['primitives']):
            pos = morphed_attribute(doc, prim, 'POSITION', weights)
            if skinned:
                joints, w = skin_sets(doc, prim)
                if joints is None:
                    raise ValueError('skinned node %d primitive %d lacks JOINTS_0/WEIGHTS_0' % (ni, pi))
                world = skin_positions(pos, joints, w, jm)
            else:
                world = transform_points(glob[ni], pos)
            prims.append({'primitive': pi, 'positions': world})
        result.append({'node': ni, 'mesh': node['mesh'], 'skinned': skinned, 'primitives': prims})
    return result
