#!/usr/bin/env python3
"""Regenerate fixtures.json and interp_cases.json from the glTF sample assets.

Run from the repository root:
    python3 tests/reference/skinning/make_fixtures.py
Prints self-checks per case; exits non-zero if any self-check fails.
"""

import json
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

sys.dont_write_bytecode = True

import interp_cases  # noqa: E402
import skin_reference as sr  # noqa: E402
import synthetic  # noqa: E402

REPO = os.path.abspath(os.path.join(HERE, '..', '..', '..'))
ASSET_ROOT = '../shared/assets'

SKINNED = {
    'RiggedSimple': ASSET_ROOT + '/RiggedSimple/glTF-Binary/RiggedSimple.glb',
    'CesiumMan': ASSET_ROOT + '/CesiumMan/glTF-Binary/CesiumMan.glb',
    'Fox': ASSET_ROOT + '/Fox/glTF-Binary/Fox.glb',
    'RobotExpressive': ASSET_ROOT + '/RobotExpressive/RobotExpressive.glb',
}
MORPH = {
    'AnimatedMorphCube': ASSET_ROOT + '/AnimatedMorphCube/glTF-Binary/AnimatedMorphCube.glb',
    'SimpleMorph': ASSET_ROOT + '/SimpleMorph/glTF/SimpleMorph.gltf',
}
# Extra, cheap: the data-URI variant of SimpleMorph must give identical results.
SIMPLE_MORPH_EMBEDDED = ASSET_ROOT + '/SimpleMorph/glTF-Embedded/SimpleMorph.gltf'

MAX_VERTICES_PER_CASE = 1800   # keeps fixtures.json well under 1.5 MB
SIG_DIGITS = 8                 # ~1e-8 relative: far below float32 engine error

FAILURES = []


def check(ok, msg):
    print('    %s %s' % ('ok  ' if ok else 'FAIL', msg))
    if not ok:
        FAILURES.append(msg)


def f32(x):
    """Round a time to the nearest float32 so engine and reference sample at
    exactly the same instant."""
    return float(np.float32(x))


def rnd(x):
    return float('%.*g' % (SIG_DIGITS, x))


def clip_keys(doc, anim):
    chans = sr.clip_channels(doc, anim)
    all_keys = np.unique(np.concatenate([c[2] for c in chans]))
    return chans[0][2], all_keys


def pick_times(doc, anim, which):
    """which: subset of ('zero', 'key', 'between', 'past_end')."""
    keys, all_keys = clip_keys(doc, anim)
    n = len(keys)
    dur = sr.clip_duration(doc, anim)
    out = []
    for w in which:
        if w == 'zero':
            out.append((0.0, 'zero' + (' (before first key %.6g: clamps)' % keys[0] if keys[0] > 0 else '')))
        elif w == 'key':
            k = max(1, n // 3)
            out.append((float(keys[k]), 'exactly on key %d' % k))
        elif w == 'between':
            k = min(n - 2, max(0, (2 * n) // 3))
            t = f32(keys[k] + 0.3 * (keys[k + 1] - keys[k]))
            assert not np.any(all_keys == t)
            out.append((t, 'between keys %d and %d (30%%)' % (k, k + 1)))
        elif w == 'past_end':
            out.append((f32(dur + 0.75), 'past the end (%.6g): clamps to last key' % dur))
    return out


def stride_for(doc, nodes_result):
    total = sum(len(p['positions']) for n in nodes_result for p in n['primitives'])
    return max(1, int(math.ceil(total / MAX_VERTICES_PER_CASE)))


def case_checks(doc, t, res):
    """Per-case self checks: weights, NaN, bounding box."""
    for n in res:
        node = doc.json['nodes'][n['node']]
        mesh = doc.json['meshes'][n['mesh']]
        for p in n['primitives']:
            P = p['positions']
            prim = mesh['primitives'][p['primitive']]
            check(np.all(np.isfinite(P)), 'node %d prim %d: %d vertices finite' % (n['node'], p['primitive'], len(P)))
            lo, hi = P.min(0), P.max(0)
            print('         bbox min %s max %s' % (np.round(lo, 4).tolist(), np.round(hi, 4).tolist()))
            if n['skinned']:
                _, w = sr.skin_sets(doc, prim)
                s = w.sum(1)
                print('         raw weight sums: min %.7f max %.7f (%d vertices off by >1e-3, renormalised)'
                      % (s.min(), s.max(), int(np.sum(np.abs(s - 1) > 1e-3))))
                check(s.min() > 0, 'no vertex has all-zero weights')


def bind_pose_check(doc, name, pose, label):
    """Where all joint matrices of a skin coincide (M), skinning must equal
    M * (raw POSITION).  Returns True if such a pose was checked."""
    glob = sr.global_matrices(doc, pose)
    checked = False
    for ni in sr.scene_nodes(doc):
        node = doc.json['nodes'][ni]
        if 'skin' not in node:
            continue
        jm = sr.joint_matrices(doc, node['skin'], glob)
        M = jm[0]
        spread = np.abs(jm - M).max() / max(1.0, np.abs(M).max())
        if spread > 1e-5:
            print('    %s %s node %d: joint matrices not uniform (rel spread %.3g), no bind-pose identity'
                  % (name, label, ni, spread))
            continue
        checked = True
        mesh = doc.json['meshes'][node['mesh']]
        w = sr.node_morph_weights(doc, ni, pose)
        for pi, prim in enumerate(mesh['primitives']):
            raw = sr.morphed_attribute(doc, prim, 'POSITION', w)
            joints, weights = sr.skin_sets(doc, prim)
            sk = sr.skin_positions(raw, joints, weights, jm)
            expect = sr.transform_points(M, raw)
            err = np.abs(sk - expect).max()
            extent = np.abs(expect).max()
            what = ('identity' if np.abs(M - np.eye(4)).max() < 1e-4 else
                    'global(mesh node)' if np.abs(M - glob[ni]).max() < 1e-4 * max(1, np.abs(M).max())
                    else 'a common matrix')
            check(err <= 1e-4 * max(1.0, extent),
                  '%s %s node %d prim %d: all joint matrices = %s; skinned == M*POSITION (max err %.3g, extent %.3g)'
                  % (name, label, ni, pi, what, err, extent))
    return checked


def independent_checks(doc, name, anim, t):
    """Cross-check vectorised maths against slower, differently-derived code."""
    pose = sr.sample_clip(doc, anim, t)
    # (a) quaternion -> matrix vs rotating basis vectors with q v q*.
    def qmul(a, b):
        ax, ay, az, aw = a
        bx, by, bz, bw = b
        return np.array([aw * bx + ax * bw + ay * bz - az * by,
                         aw * by - ax * bz + ay * bw + az * bx,
                         aw * bz + ax * by - ay * bx + az * bw,
                         aw * bw - ax * bx - ay * by - az * bz])
    worst = 0.0
    for ch in pose.values():
        if 'rotation' in ch:
            q = ch['rotation']
            check_norm = abs(np.linalg.norm(q) - 1.0)
            worst = max(worst, check_norm)
            qc = np.array([-q[0], -q[1], -q[2], q[3]])
            R = sr.quat_to_mat3(q)
            for axis in range(3):
                v = np.zeros(4)
                v[axis] = 1.0
                rv = qmul(qmul(q, v), qc)[:3]
                worst = max(worst, np.abs(rv - R[:, axis]).max())
    check(worst < 1e-12, '%s anim %d t=%g: sampled rotations unit length and quat->matrix == q v q* (%.2g)'
          % (name, anim, t, worst))
    # (b) slow per-vertex skinning loop on a few vertices.
    glob = sr.global_matrices(doc, pose)
    for ni in sr.scene_nodes(doc):
        node = doc.json['nodes'][ni]
        if 'skin' not in node:
            continue
        skin = doc.json['skins'][node['skin']]
        ibm = doc.accessor(skin['inverseBindMatrices']) if 'inverseBindMatrices' in skin else None
        prim = doc.json['meshes'][node['mesh']]['primitives'][0]
        pos = doc.accessor(prim['attributes']['POSITION'])
        joints, weights = sr.skin_sets(doc, prim)
        fast = sr.skin_positions(pos, joints, weights, sr.joint_matrices(doc, node['skin'], glob))
        worst = 0.0
        for v in range(0, len(pos), max(1, len(pos) // 25)):
            acc = np.zeros(3)
            total = sum(weights[v])
            for j, w in zip(joints[v], weights[v]):
                if w == 0:
                    continue
                node_j = skin['joints'][j]
                inv = np.eye(4) if ibm is None else np.array(ibm[j]).reshape(4, 4, order='F')
                m = glob[node_j].dot(inv)
                acc += (w / total) * (m.dot(np.append(pos[v], 1.0))[:3])
            worst = max(worst, np.abs(acc - fast[v]).max() / max(1.0, np.abs(acc).max()))
        check(worst < 1e-12, '%s node %d: slow per-vertex skinning loop agrees (%.2g)' % (name, ni, worst))


def robot_attachment_check(res):
    """RobotExpressive: the skinned hands must sit at the end of the rigid
    (bone-parented) arm meshes Arm.L (node 18) / Arm.R (node 38)."""
    by_node = {n['node']: np.concatenate([p['positions'] for p in n['primitives']]) for n in res}
    height = max(P[:, 1].max() for P in by_node.values()) - min(P[:, 1].min() for P in by_node.values())
    for hand, arm in ((72, 38), (73, 18)):
        H, A = by_node[hand], by_node[arm]
        d = np.sqrt(((H[:, None, :] - A[None, :, :]) ** 2).sum(-1)).min()
        check(d < 0.05 * height, 'hand node %d to arm node %d min distance %.4f (robot height %.3f)'
              % (hand, arm, d, height))


def make_case(rel_path, doc, anim, t, note):
    res = sr.evaluate(doc, anim, t)
    k = stride_for(doc, res)
    nodes_out = []
    for n in res:
        prims = []
        for p in n['primitives']:
            idx = list(range(0, len(p['positions']), k))
            prims.append({'primitive': p['primitive'],
                          'vertex_count': len(p['positions']),
                          'vertex_indices': idx,
                          'positions': [[rnd(c) for c in p['positions'][i]] for i in idx]})
        nodes_out.append({'node': n['node'], 'mesh': n['mesh'], 'skinned': n['skinned'], 'primitives': prims})
    case = {'asset': rel_path, 'animation': anim, 'time': t, 'note': note,
            'vertex_stride': k, 'nodes': nodes_out}
    return case, res


def main():
    os.chdir(REPO)
    cases = []
    plan = [
        ('RiggedSimple', [(0, ('zero', 'key', 'between', 'past_end'))]),
        ('CesiumMan', [(0, ('zero', 'key', 'between', 'past_end'))]),
        ('Fox', [(0, ('zero', 'key', 'between', 'past_end')), (1, ('between',)), (2, ('key',))]),
        ('RobotExpressive', [(0, ('zero', 'key', 'between', 'past_end')), (12, ('key', 'between'))]),
        ('AnimatedMorphCube', [(0, ('zero', 'between', 'past_end'))]),
        ('SimpleMorph', [(0, ('key', 'between', 'past_end'))]),
    ]
    assets = dict(SKINNED, **MORPH)
    for name, clips in plan:
        rel = assets[name]
        doc = sr.Gltf(rel)
        print('=== %s (%s)' % (name, rel))
        if name in SKINNED:
            if not bind_pose_check(doc, name, {}, 'rest pose (no animation)'):
                print('    %s: rest pose is not the bind pose' % name)
        for anim, which in clips:
            aname = doc.json['animations'][anim].get('name', '')
            for t, note in pick_times(doc, anim, which):
                print('  case: anim %d %r t=%r  [%s]' % (anim, aname, t, note))
                case, res = make_case(rel, doc, anim, t, note)
                cases.append(case)
                case_checks(doc, t, res)
                if name in SKINNED:
                    independent_checks(doc, name, anim, t)
                    bind_pose_check(doc, name, sr.sample_clip(doc, anim, t), 'anim %d t=%g' % (anim, t))
                if name == 'RobotExpressive':
                    robot_attachment_check(res)
                if name == 'SimpleMorph':
                    simple_morph_hand_check(doc, t, res)
                if name == 'AnimatedMorphCube':
                    morph_cube_check(doc, anim, t, res)

    print('=== SimpleMorph embedded (data: URI buffers) vs external .bin')
    a, b = sr.Gltf(MORPH['SimpleMorph']), sr.Gltf(SIMPLE_MORPH_EMBEDDED)
    for t in (0.0, 1.5, 3.25):
        pa = sr.evaluate(a, 0, t)[0]['primitives'][0]['positions']
        pb = sr.evaluate(b, 0, t)[0]['primitives'][0]['positions']
        check(np.array_equal(pa, pb), 'embedded == external at t=%g' % t)

    doc = {
        'generator': 'tests/reference/skinning/make_fixtures.py (independent numpy float64 reference; '
                     'see README.md for semantics)',
        'positions': 'world space, per vertex of the primitive POSITION accessor; only vertex_indices '
                     '(every vertex_stride-th vertex) are stored; values rounded to %d significant digits'
                     % SIG_DIGITS,
        'cases': cases,
    }
    out = os.path.join(HERE, 'fixtures.json')
    with open(out, 'w') as f:
        json.dump(doc, f, separators=(',', ':'))
        f.write('\n')
    print('wrote %s: %d cases, %d bytes' % (os.path.relpath(out), len(cases), os.path.getsize(out)))

    make_synthetic()

    print('=== interp_cases.json hand checks')
    idoc, msgs, ok = interp_cases.build()
    for m in msgs:
        print('    ' + m)
        if m.startswith('FAIL'):
            FAILURES.append(m)
    out = os.path.join(HERE, 'interp_cases.json')
    with open(out, 'w') as f:
        json.dump(idoc, f, indent=1)
        f.write('\n')
    print('wrote %s: %d sampler cases, %d queries, %d bytes' % (
        os.path.relpath(out), len(idoc['cases']), sum(len(c['queries']) for c in idoc['cases']),
        os.path.getsize(out)))

    if FAILURES:
        print('%d SELF-CHECK FAILURES' % len(FAILURES))
        for f in FAILURES:
            print('  ' + f)
        return 1
    print('all self-checks passed')
    return 0


SYNTHETIC_REL = 'tests/reference/skinning/synthetic_skin_morph.gltf'


def make_synthetic():
    """Write the hand-built glTF and its fixtures (same case format)."""
    print('=== synthetic (%s)' % SYNTHETIC_REL)
    gltf = synthetic.build()
    path = os.path.join(REPO, SYNTHETIC_REL)
    with open(path, 'w') as f:
        json.dump(gltf, f, indent=1)
        f.write('\n')
    doc = sr.Gltf(SYNTHETIC_REL)
    for anim, t, node, v, exp in synthetic.HAND_CHECKS:
        res = {n['node']: n for n in sr.evaluate(doc, anim, t)}
        got = res[node]['primitives'][0]['positions'][v]
        check(np.abs(got - np.array(exp)).max() < 1e-9,
              'hand check anim %s t=%g node %d vertex %d: got %s expected %s'
              % (anim, t, node, v, np.round(got, 9).tolist(), list(exp)))
    cases = []
    for anim, t, note in [(0, 0.0, 'first key: rest pose'), (0, 0.5, 'exactly on STEP key 1'),
                          (0, 1.25, 'between keys'), (0, 2.0, 'last key'), (0, 3.0, 'past the end: clamps'),
                          (1, 0.5, 'between weight keys'), (1, 1.0, 'last weight key'),
                          (1, 1.5, 'past the end: clamps')]:
        case, res = make_case(SYNTHETIC_REL, doc, anim, t, note)
        cases.append(case)
        ok = all(np.all(np.isfinite(p['positions'])) for n in res for p in n['primitives'])
        check(ok, 'synthetic anim %d t=%g finite' % (anim, t))
    out = os.path.join(HERE, 'synthetic_fixtures.json')
    with open(out, 'w') as f:
        json.dump({'generator': 'tests/reference/skinning/make_fixtures.py (synthetic.py asset)',
                   'features': 'sparse accessors (no bufferView / with bufferView; u8, u16, u32 indices), '
                               'interleaved byteStride, u8/u16 normalized weights, JOINTS_1/WEIGHTS_1, '
                               'unnormalised weight sum (vertex 3), i16 normalized rotation output, '
                               'STEP and CUBICSPLINE (vec3, quat, weights), node.weights overriding '
                               'mesh.weights, skin + morph on one node, skinned node TRS ignored, '
                               'static node.matrix parent, morph-only mesh parented to a joint',
                   'hand_checks': [{'animation': a, 'time': t, 'node': n, 'vertex': v, 'expected': list(e)}
                                   for a, t, n, v, e in synthetic.HAND_CHECKS if a is not None],
                   'cases': cases}, f, separators=(',', ':'))
        f.write('\n')
    print('wrote %s: %d cases, %d bytes' % (os.path.relpath(out), len(cases), os.path.getsize(out)))


def simple_morph_hand_check(doc, t, res):
    """SimpleMorph weights keys: t=0 (0,0), 1 (0,1), 2 (1,1), 3 (1,0), 4 (0,0),
    LINEAR.  Recompute the weights by hand and the morphed triangle."""
    keys = {0: (0, 0), 1: (0, 1), 2: (1, 1), 3: (1, 0), 4: (0, 0)}
    tc = min(max(t, 0.0), 4.0)
    k = min(int(math.floor(tc)), 3)
    u = tc - k
    w = (1 - u) * np.array(keys[k], float) + u * np.array(keys[k + 1], float)
    prim = doc.json['meshes'][0]['primitives'][0]
    base = doc.accessor(prim['attributes']['POSITION'])
    t0 = doc.accessor(prim['targets'][0]['POSITION'])
    t1 = doc.accessor(prim['targets'][1]['POSITION'])
    expect = base + w[0] * t0 + w[1] * t1  # node has no transform
    got = res[0]['primitives'][0]['positions']
    check(np.abs(got - expect).max() < 1e-12, 'SimpleMorph t=%g: hand weights %s -> positions %s'
          % (t, np.round(w, 6).tolist(), np.round(got, 6).tolist()))


def morph_cube_check(doc, anim, t, res):
    """AnimatedMorphCube: sampled weights must lie in [0, 1] (up to 1e-6: the
    last key of target 1 is stored as -1.5e-7); positions equal
    base + sum w_i * delta_i (recomputed directly from the accessors)."""
    pose = sr.sample_clip(doc, anim, t)
    w = pose[0]['weights']
    prim = doc.json['meshes'][0]['primitives'][0]
    expect = doc.accessor(prim['attributes']['POSITION']).copy()
    for i, tg in enumerate(prim['targets']):
        expect += w[i] * doc.accessor(tg['POSITION'])
    node = doc.json['nodes'][0]
    M = sr.local_matrix(node)
    expect = expect @ M[:3, :3].T + M[:3, 3]
    got = res[0]['primitives'][0]['positions']
    check(np.all((w >= -1e-6) & (w <= 1 + 1e-6)) and np.abs(got - expect).max() < 1e-12,
          'AnimatedMorphCube t=%g: weights %s, morphed positions consistent' % (t, np.round(w, 6).tolist()))


if __name__ == '__main__':
    sys.exit(main())
