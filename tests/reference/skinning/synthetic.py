#!/usr/bin/env python3
"""A tiny hand-built glTF that exercises what the sample assets do not:
sparse accessors (with and without bufferView), interleaved byteStride,
normalized u8/u16 weights, JOINTS_1/WEIGHTS_1, unnormalised weights, i16
normalized rotation outputs, STEP and CUBICSPLINE channels (incl. weights
and quaternions), node.weights overriding mesh.weights, a node that has both
skin and morph targets, an ignored transform on the skinned node, a static
node.matrix parent, and a morph-only mesh rigidly attached to a joint.

build() returns the glTF JSON (single data: URI buffer) and HAND_CHECKS
(values derived by hand in the comments below)."""

import base64
import math
import struct

S45 = math.sqrt(0.5)


class Blob:
    def __init__(self):
        self.data = bytearray()
        self.views = []

    def view(self, raw, stride=None):
        while len(self.data) % 4:
            self.data.append(0)
        v = {'buffer': 0, 'byteOffset': len(self.data), 'byteLength': len(raw)}
        if stride:
            v['byteStride'] = stride
        self.data += raw
        self.views.append(v)
        return len(self.views) - 1


def pack(fmt, values):
    return b''.join(struct.pack('<' + fmt, *v) if isinstance(v, (list, tuple)) else struct.pack('<' + fmt, v)
                    for v in values)


def build():
    b = Blob()
    acc = []

    def accessor(**kw):
        acc.append(kw)
        return len(acc) - 1

    # ---- mesh 0: 4 vertices, POSITION (f32 x3) interleaved with JOINTS_0 (u8 x4), stride 16
    pos = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)]
    j0 = [(0, 1, 0, 0), (0, 1, 0, 0), (0, 1, 0, 0), (0, 1, 0, 0)]
    inter = b''.join(struct.pack('<3f', *p) + struct.pack('<4B', *j) for p, j in zip(pos, j0))
    v_inter = b.view(inter, stride=16)
    a_pos = accessor(bufferView=v_inter, byteOffset=0, componentType=5126, type='VEC3', count=4,
                     min=[0, 0, 0], max=[1, 1, 0])
    a_j0 = accessor(bufferView=v_inter, byteOffset=12, componentType=5121, type='VEC4', count=4)
    # WEIGHTS_0: u8 normalized.  v0: 1 on joint 0; v1: 128/255 j0 + 127/255 j1;
    # v2: 1 on joint 1... (see JOINTS_0 above: slot0 -> joint 0, slot1 -> joint 1)
    w0 = [(255, 0, 0, 0), (128, 127, 0, 0), (0, 255, 0, 0), (100, 0, 0, 0)]
    a_w0 = accessor(bufferView=b.view(pack('4B', w0)), componentType=5121, normalized=True,
                    type='VEC4', count=4)
    # JOINTS_1 (u16) / WEIGHTS_1 (u16 normalized): only v3 uses the second set:
    # 32768/65535 on joint 1.  v3 total = 100/255 + 32768/65535 ~ 0.892 -> renormalised.
    a_j1 = accessor(bufferView=b.view(pack('4H', [(0, 0, 0, 0)] * 3 + [(1, 0, 0, 0)])),
                    componentType=5123, type='VEC4', count=4)
    a_w1 = accessor(bufferView=b.view(pack('4H', [(0, 0, 0, 0)] * 3 + [(32768, 0, 0, 0)])),
                    componentType=5123, normalized=True, type='VEC4', count=4)
    # target 0: sparse accessor WITHOUT bufferView (zeros) + index 3 -> (0, 0, 1); u8 indices
    t0_idx = b.view(pack('B', [3]))
    t0_val = b.view(pack('3f', [(0, 0, 1)]))
    a_t0 = accessor(componentType=5126, type='VEC3', count=4, min=[0, 0, 0], max=[0, 0, 1],
                    sparse={'count': 1, 'indices': {'bufferView': t0_idx, 'componentType': 5121},
                            'values': {'bufferView': t0_val}})
    # target 1: dense (0, 0, 0.5) for all, sparse override index 0 -> (0, 0, -1); u16 indices
    t1_base = b.view(pack('3f', [(0, 0, 0.5)] * 4))
    t1_idx = b.view(pack('H', [0]))
    t1_val = b.view(pack('3f', [(0, 0, -1)]))
    a_t1 = accessor(bufferView=t1_base, componentType=5126, type='VEC3', count=4,
                    min=[0, 0, -1], max=[0, 0, 0.5],
                    sparse={'count': 1, 'indices': {'bufferView': t1_idx, 'componentType': 5123},
                            'values': {'bufferView': t1_val}})
    a_idx0 = accessor(bufferView=b.view(pack('H', [0, 1, 2, 2, 1, 3])), componentType=5123,
                      type='SCALAR', count=6)

    # ---- mesh 1: rigid, morph-only triangle; target sparse with u32 indices
    a_pos1 = accessor(bufferView=b.view(pack('3f', [(0, 0, 0), (1, 0, 0), (0, 0, 1)])),
                      componentType=5126, type='VEC3', count=3, min=[0, 0, 0], max=[1, 0, 1])
    m1_idx = b.view(pack('I', [1, 2]))
    m1_val = b.view(pack('3f', [(0, 2, 0), (0, 0, 4)]))
    a_t10 = accessor(componentType=5126, type='VEC3', count=3, min=[0, 0, 0], max=[0, 2, 4],
                     sparse={'count': 2, 'indices': {'bufferView': m1_idx, 'componentType': 5125},
                             'values': {'bufferView': m1_val}})

    # ---- skin: joints [J0 (node 1), J1 (node 2)]; bind globals T(10,0,0) and T(10,1,0)
    ibm = [
        (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -10, 0, 0, 1),
        (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -10, -1, 0, 1),
    ]
    a_ibm = accessor(bufferView=b.view(pack('16f', ibm)), componentType=5126, type='MAT4', count=2)

    # ---- animation 0 (TRS)
    a_t_0_2 = accessor(bufferView=b.view(pack('f', [0.0, 2.0])), componentType=5126, type='SCALAR',
                       count=2, min=[0.0], max=[2.0])
    a_t_0_1_2 = accessor(bufferView=b.view(pack('f', [0.0, 1.0, 2.0])), componentType=5126,
                         type='SCALAR', count=3, min=[0.0], max=[2.0])
    a_t_step = accessor(bufferView=b.view(pack('f', [0.0, 0.5, 1.5])), componentType=5126,
                        type='SCALAR', count=3, min=[0.0], max=[1.5])
    # J0 rotation CUBICSPLINE: identity -> 90 deg about +X, zero tangents.
    j0_rot = [(0, 0, 0, 0), (0, 0, 0, 1), (0, 0, 0, 0),
              (0, 0, 0, 0), (S45, 0, 0, S45), (0, 0, 0, 0)]
    a_j0_rot = accessor(bufferView=b.view(pack('4f', j0_rot)), componentType=5126, type='VEC4', count=6)
    # J1 translation CUBICSPLINE (in, value, out per key)
    j1_tr = [(0, 0, 0), (0, 1, 0), (1, 0, 0),
             (0, 1, 0), (1, 1, 0), (0, 1, 0),
             (-1, 0, 0), (0, 2, 0), (0, 0, 0)]
    a_j1_tr = accessor(bufferView=b.view(pack('3f', j1_tr)), componentType=5126, type='VEC3', count=9)
    # J1 rotation LINEAR, i16 normalized: identity -> -(90 deg about Z) (negative dot)
    q90 = int(round(S45 * 32767))
    a_j1_rot = accessor(bufferView=b.view(pack('4h', [(0, 0, 0, 32767), (0, 0, -q90, -q90)])),
                        componentType=5122, normalized=True, type='VEC4', count=2)
    # J1 scale STEP
    a_j1_sc = accessor(bufferView=b.view(pack('3f', [(1, 1, 1), (2, 2, 2), (1, 1, 3)])),
                       componentType=5126, type='VEC3', count=3)

    # ---- animation 1 (weights)
    a_t_0_1 = accessor(bufferView=b.view(pack('f', [0.0, 1.0])), componentType=5126, type='SCALAR',
                       count=2, min=[0.0], max=[1.0])
    # node 3 (2 targets) CUBICSPLINE: per key [in0 in1, v0 v1, out0 out1]
    w_cub = [0, 0, 0, 0, 1, 0,
             0, 0, 1, 1, 0, 0]
    a_w_cub = accessor(bufferView=b.view(pack('f', w_cub)), componentType=5126, type='SCALAR', count=12)
    # node 4 (1 target) STEP, u8 normalized output
    a_w_step = accessor(bufferView=b.view(pack('B', [0, 255])), componentType=5121, normalized=True,
                        type='SCALAR', count=2)

    root_matrix = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 10, 0, 0, 1]
    gltf = {
        'asset': {'version': '2.0', 'generator': 'raykin tests/reference/skinning/synthetic.py'},
        'scene': 0,
        'scenes': [{'nodes': [0, 3]}],
        'nodes': [
            {'name': 'Root', 'matrix': root_matrix, 'children': [1]},
            {'name': 'J0', 'children': [2]},
            {'name': 'J1', 'translation': [0, 1, 0], 'children': [4]},
            {'name': 'SkinnedMorphed', 'mesh': 0, 'skin': 0, 'weights': [1.0, 0.25],
             'translation': [100, 100, 100], 'scale': [3, 3, 3]},
            {'name': 'RigidOnJ1', 'mesh': 1, 'translation': [0, 0, 1]},
        ],
        'meshes': [
            {'name': 'skinned', 'weights': [0.0, 0.5], 'primitives': [{
                'attributes': {'POSITION': a_pos, 'JOINTS_0': a_j0, 'WEIGHTS_0': a_w0,
                               'JOINTS_1': a_j1, 'WEIGHTS_1': a_w1},
                'indices': a_idx0, 'targets': [{'POSITION': a_t0}, {'POSITION': a_t1}]}]},
            {'name': 'rigid', 'weights': [0.5], 'primitives': [{
                'attributes': {'POSITION': a_pos1}, 'targets': [{'POSITION': a_t10}]}]},
        ],
        'skins': [{'joints': [1, 2], 'inverseBindMatrices': a_ibm, 'skeleton': 1}],
        'animations': [
            {'name': 'trs', 'samplers': [
                {'input': a_t_0_2, 'output': a_j0_rot, 'interpolation': 'CUBICSPLINE'},
                {'input': a_t_0_1_2, 'output': a_j1_tr, 'interpolation': 'CUBICSPLINE'},
                {'input': a_t_0_2, 'output': a_j1_rot, 'interpolation': 'LINEAR'},
                {'input': a_t_step, 'output': a_j1_sc, 'interpolation': 'STEP'},
            ], 'channels': [
                {'sampler': 0, 'target': {'node': 1, 'path': 'rotation'}},
                {'sampler': 1, 'target': {'node': 2, 'path': 'translation'}},
                {'sampler': 2, 'target': {'node': 2, 'path': 'rotation'}},
                {'sampler': 3, 'target': {'node': 2, 'path': 'scale'}},
            ]},
            {'name': 'weights', 'samplers': [
                {'input': a_t_0_1, 'output': a_w_cub, 'interpolation': 'CUBICSPLINE'},
                {'input': a_t_0_1, 'output': a_w_step, 'interpolation': 'STEP'},
            ], 'channels': [
                {'sampler': 0, 'target': {'node': 3, 'path': 'weights'}},
                {'sampler': 1, 'target': {'node': 4, 'path': 'weights'}},
            ]},
        ],
        'accessors': acc,
        'bufferViews': b.views,
    }
    while len(b.data) % 4:
        b.data.append(0)
    gltf['buffers'] = [{'byteLength': len(b.data),
                        'uri': 'data:application/octet-stream;base64,' + base64.b64encode(bytes(b.data)).decode()}]
    return gltf


# Hand derivations.  Morphed positions of mesh 0 with node.weights (1, 0.25):
#   t0 = (0,0,0),(0,0,0),(0,0,0),(0,0,1)   t1 = (0,0,-1),(0,0,.5),(0,0,.5),(0,0,.5)
#   v0 (0,0,-0.25)  v1 (1,0,0.125)  v2 (0,1,0.125)  v3 (1,1,1.125)
# Rest pose / anim 0 at t=0: every joint matrix is identity (globals equal the
# bind globals), so skinned == morphed; the node's own TRS (100s, scale 3) is ignored.
# Rigid mesh (node 4, child of J1, local T(0,0,1)): global = T(10,1,1);
#   mesh.weights 0.5, target (0,0,0),(0,2,0),(0,0,4):
#   (10,1,1), (11,2,1), (10,1,4)
# Anim 0 at t=2 (J0 = 90 deg about X, J1 T(0,2,0) R(-90 deg about Z), S(1,1,3)):
#   v0 has weight 1 on J0: T(10) Rx90 T(-10) (0,0,-0.25) = (0, 0.25, 0)
#   (Rx90 maps (x,y,z) -> (x,-z,y)).
# Anim 1 at t=0.5 (CUBICSPLINE weights, dt=1, u=.5: h00=h01=.5, h10=.125, h11=-.125):
#   w0 = .5*0 + .125*out0(=1) + .5*1 + (-.125)*in1(=0) = 0.625
#   w1 = .5*0 + .125*0 + .5*1 + (-.125)*0 = 0.5
#   -> v0 = (0,0,-0.5) (still rest skeleton: skinned == morphed)
#   node 4 STEP weight at 0.5 = 0 -> rigid mesh unmorphed: (10,1,1),(11,1,1),(10,1,2)
#   at t=1.0 the STEP weight is 255/255 = 1 -> v2 = (0,0,1)+(0,0,4) -> (10,1,6)
HAND_CHECKS = [
    # (animation or None, time, node, vertex, expected world position)
    (None, 0.0, 3, 0, (0.0, 0.0, -0.25)),
    (None, 0.0, 3, 1, (1.0, 0.0, 0.125)),
    (None, 0.0, 3, 3, (1.0, 1.0, 1.125)),
    (0, 0.0, 3, 2, (0.0, 1.0, 0.125)),
    (None, 0.0, 4, 1, (11.0, 2.0, 1.0)),
    (None, 0.0, 4, 2, (10.0, 1.0, 4.0)),
    (0, 2.0, 3, 0, (0.0, 0.25, 0.0)),
    (0, 5.0, 3, 0, (0.0, 0.25, 0.0)),
    (1, 0.5, 3, 0, (0.0, 0.0, -0.5)),
    (1, 0.5, 3, 3, (1.0, 1.0, 0.625 + 0.25)),
    (1, 0.5, 4, 1, (11.0, 1.0, 1.0)),
    (1, 1.0, 4, 2, (10.0, 1.0, 6.0)),
]
