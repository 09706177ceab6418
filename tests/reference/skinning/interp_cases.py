#!/usr/bin/env python3
"""Hand-written animation-sampler cases (written to interp_cases.json by
make_fixtures.py).  Expected values come from skin_reference.sample(); a subset
is also checked against values derived by hand (HAND_CHECKS)."""

import math

import numpy as np

import skin_reference as sr

S45 = math.sin(math.radians(45.0))
C45 = math.cos(math.radians(45.0))
S225 = math.sin(math.radians(22.5))
C225 = math.cos(math.radians(22.5))
S30 = math.sin(math.radians(30.0))
C30 = math.cos(math.radians(30.0))

QI = [0.0, 0.0, 0.0, 1.0]          # identity
QZ90 = [0.0, 0.0, S45, C45]        # 90 degrees about +Z
QZ90_NEG = [0.0, 0.0, -S45, -C45]  # same rotation, opposite sign (dot with QI < 0)
QX120 = [math.sin(math.radians(60.0)), 0.0, 0.0, math.cos(math.radians(60.0))]  # 120 deg about +X
QY60 = [0.0, S30, 0.0, C30]         # 60 degrees about +Y

# Each case: name, interpolation, type (scalar|vec3|quat|weights), components,
# input (key times), output (flat list, exactly the accessor contents; for
# CUBICSPLINE per key: in-tangent, value, out-tangent, each `components` wide),
# query times.
CASES = [
    dict(name='step_scalar', interpolation='STEP', type='scalar', components=1,
         input=[1.0, 2.0, 4.0], output=[10.0, 20.0, 40.0],
         queries=[0.0, 1.0, 1.5, 1.999, 2.0, 3.0, 4.0, 5.0]),
    dict(name='step_vec3', interpolation='STEP', type='vec3', components=3,
         input=[0.0, 0.5, 1.0], output=[0, 0, 0, 1, 2, 3, -1, -2, -3],
         queries=[-1.0, 0.25, 0.5, 0.75, 1.0, 2.0]),
    dict(name='linear_scalar', interpolation='LINEAR', type='scalar', components=1,
         input=[1.0, 2.0, 4.0], output=[10.0, 20.0, 40.0],
         queries=[0.0, 1.0, 1.25, 1.5, 2.0, 3.0, 3.5, 4.0, 10.0]),
    dict(name='linear_vec3', interpolation='LINEAR', type='vec3', components=3,
         input=[0.0, 2.0], output=[0, 0, 0, 2, -4, 6],
         queries=[-0.5, 0.0, 0.5, 1.0, 2.0, 3.0]),
    dict(name='linear_vec3_nonuniform', interpolation='LINEAR', type='vec3', components=3,
         input=[0.0, 0.1, 1.0], output=[0, 0, 0, 1, 1, 1, 1, 10, 1],
         queries=[0.05, 0.1, 0.55, 0.999]),
    dict(name='linear_weights_2targets', interpolation='LINEAR', type='weights', components=2,
         input=[0.0, 1.0, 2.0], output=[0, 1, 1, 0, 0.5, 0.5],
         queries=[0.0, 0.5, 1.0, 1.5, 2.5]),
    dict(name='slerp_quat_90z', interpolation='LINEAR', type='quat', components=4,
         input=[0.0, 1.0], output=QI + QZ90,
         queries=[-1.0, 0.0, 0.25, 0.5, 1.0, 2.0]),
    dict(name='slerp_quat_negative_dot_shortest_path', interpolation='LINEAR', type='quat', components=4,
         input=[0.0, 1.0], output=QI + QZ90_NEG,
         queries=[0.0, 0.5, 1.0]),
    dict(name='slerp_quat_three_keys', interpolation='LINEAR', type='quat', components=4,
         input=[0.0, 1.0, 3.0], output=QI + QX120 + QY60,
         queries=[0.5, 1.0, 1.6, 2.0, 3.0, 3.5]),
    dict(name='slerp_quat_identical_keys', interpolation='LINEAR', type='quat', components=4,
         input=[0.0, 1.0], output=QZ90 + QZ90,
         queries=[0.3]),
    dict(name='step_quat', interpolation='STEP', type='quat', components=4,
         input=[0.0, 1.0], output=QI + QZ90,
         queries=[0.5, 1.0, 2.0]),
    # Hermite reproduces cubics exactly: f(t) = t^2 with f' = 2t on
    # non-uniform keys 0, 1, 3 -> expected value t^2 inside [0, 3].
    dict(name='cubic_scalar_t_squared', interpolation='CUBICSPLINE', type='scalar', components=1,
         input=[0.0, 1.0, 3.0],
         output=[0.0, 0.0, 0.0,   2.0, 1.0, 2.0,   6.0, 9.0, 6.0],
         queries=[-1.0, 0.0, 0.5, 1.0, 2.0, 2.5, 3.0, 4.0]),
    # Values 0 -> 0 over dt = 2 with tangents 1: checks that tangents are
    # scaled by dt (p(0.5) = 2 * (2u^3 - 3u^2 + u) at u = 0.25 = 0.1875).
    dict(name='cubic_scalar_tangent_scaling', interpolation='CUBICSPLINE', type='scalar', components=1,
         input=[0.0, 2.0],
         output=[5.0, 0.0, 1.0,   1.0, 0.0, -7.0],
         queries=[0.5, 1.0, 1.5]),
    dict(name='cubic_vec3', interpolation='CUBICSPLINE', type='vec3', components=3,
         input=[0.0, 0.5, 1.5],
         output=[0, 0, 0,  0, 0, 0,  1, 0, 0,
                 1, 1, 1,  1, 2, 3,  -1, 0, 2,
                 0, 0, 0,  4, 4, 4,  9, 9, 9],
         queries=[-0.1, 0.0, 0.25, 0.5, 0.7, 1.0, 1.5, 1.6]),
    # Cubic on weights: per key [in-tangents of all targets, values, out-tangents].
    dict(name='cubic_weights_2targets', interpolation='CUBICSPLINE', type='weights', components=2,
         input=[0.0, 1.0],
         output=[0, 0,  0, 1,  1, 0,
                 0, 0,  1, 0,  0, 0],
         queries=[0.0, 0.5, 1.0]),
    # Zero tangents, identity -> 90 deg about Z: at 0.5 the Hermite blend is
    # (q0 + q1) / 2 which normalises to the 45 degree rotation.
    dict(name='cubic_quat_zero_tangents', interpolation='CUBICSPLINE', type='quat', components=4,
         input=[0.0, 1.0],
         output=[0, 0, 0, 0] + QI + [0, 0, 0, 0] +
                [0, 0, 0, 0] + QZ90 + [0, 0, 0, 0],
         queries=[-1.0, 0.0, 0.25, 0.5, 1.0, 2.0]),
    dict(name='cubic_quat_with_tangents', interpolation='CUBICSPLINE', type='quat', components=4,
         input=[0.0, 0.5, 2.0],
         output=[0, 0, 0, 0] + QI + [0.1, 0.0, 0.5, 0.0] +
                [0.0, 0.2, 0.3, -0.1] + QZ90 + [0.0, 0.0, 0.1, 0.0] +
                [0, 0, 0, 0] + QX120 + [0, 0, 0, 0],
         queries=[0.2, 0.5, 1.25, 2.0]),
    dict(name='one_key_linear_vec3', interpolation='LINEAR', type='vec3', components=3,
         input=[0.5], output=[1.0, 2.0, 3.0],
         queries=[0.0, 0.5, 7.0]),
    dict(name='one_key_step_scalar', interpolation='STEP', type='scalar', components=1,
         input=[0.5], output=[42.0],
         queries=[0.0, 0.5, 7.0]),
    dict(name='one_key_cubic_quat', interpolation='CUBICSPLINE', type='quat', components=4,
         input=[1.0], output=[1, 1, 1, 1] + QZ90 + [2, 2, 2, 2],
         queries=[0.0, 1.0, 3.0]),
]

# (case name, query time, expected value derived by hand, note)
HAND_CHECKS = [
    ('step_scalar', 1.5, [10.0], 'step holds previous key'),
    ('step_scalar', 2.0, [20.0], 'step exactly on a key takes that key'),
    ('step_scalar', 0.0, [10.0], 'clamped before first key'),
    ('step_scalar', 5.0, [40.0], 'clamped after last key'),
    ('linear_scalar', 1.5, [15.0], 'midpoint is the average'),
    ('linear_scalar', 3.5, [35.0], 'linear in a 2 s interval'),
    ('linear_scalar', 10.0, [40.0], 'clamped after last key'),
    ('linear_vec3', 1.0, [1.0, -2.0, 3.0], 'midpoint is the average'),
    ('linear_vec3_nonuniform', 0.55, [1.0, 5.5, 1.0], 'midpoint of second interval'),
    ('linear_weights_2targets', 1.5, [0.75, 0.25], 'average of keys 1 and 2'),
    ('slerp_quat_90z', 0.5, [0.0, 0.0, S225, C225], 'slerp 90 deg at 0.5 = 45 deg'),
    ('slerp_quat_90z', 0.25, [0.0, 0.0, math.sin(math.radians(11.25)), math.cos(math.radians(11.25))],
     'slerp 90 deg at 0.25 = 22.5 deg (constant angular velocity)'),
    ('slerp_quat_negative_dot_shortest_path', 0.5, [0.0, 0.0, S225, C225],
     'q1 has negative dot: flip it, result is +45 deg (not 135 deg the long way)'),
    ('slerp_quat_negative_dot_shortest_path', 1.0, [0.0, 0.0, -S45, -C45], 'exactly on last key: the stored key as-is'),
    # t = 2.0 is halfway through [1, 3]: with equal weights the slerp midpoint
    # is the normalised sum of the two keys (their dot is > 0).
    ('slerp_quat_three_keys', 2.0,
     list((np.array(QX120) + np.array(QY60)) / np.linalg.norm(np.array(QX120) + np.array(QY60))),
     'slerp midpoint = normalised sum of the two keys'),
    ('cubic_scalar_t_squared', 0.5, [0.25], 'Hermite reproduces t^2'),
    ('cubic_scalar_t_squared', 2.0, [4.0], 'Hermite reproduces t^2 on a 2 s interval (tangent scaling)'),
    ('cubic_scalar_t_squared', 2.5, [6.25], 'Hermite reproduces t^2'),
    ('cubic_scalar_t_squared', 4.0, [9.0], 'clamped after last key'),
    ('cubic_scalar_tangent_scaling', 0.5, [0.1875], 'dt * (u^3 - 2u^2 + u + u^3 - u^2) at u = 0.25, dt = 2'),
    ('cubic_scalar_tangent_scaling', 1.0, [0.0], 'symmetric tangents cancel at the midpoint'),
    # u = 0.5, dt = 1: h00 = h01 = 0.5, h10 = 0.125, h11 = -0.125.
    # target 0: 0.5*0 + 0.125*out0(=1) + 0.5*1 + (-0.125)*in1(=0) = 0.625
    # target 1: 0.5*1 + 0.125*out0(=0) + 0.5*0 + (-0.125)*in1(=0) = 0.5
    ('cubic_weights_2targets', 0.5, [0.625, 0.5],
     'Hermite basis at u = 0.5; weights laid out per key as [in*T, v*T, out*T]'),
    ('cubic_quat_zero_tangents', 0.5, [0.0, 0.0, S225, C225], 'normalised (q0 + q1) / 2 = 45 deg'),
    ('one_key_linear_vec3', 7.0, [1.0, 2.0, 3.0], 'one-key sampler is constant'),
    ('one_key_cubic_quat', 0.0, QZ90, 'one-key cubic returns the value, not a tangent'),
]


def quat_equal_up_to_sign(a, b, tol):
    a, b = np.asarray(a), np.asarray(b)
    return min(np.abs(a - b).max(), np.abs(a + b).max()) <= tol


def build():
    """Returns (json-able dict, list of check messages, all_ok)."""
    cases = []
    by_name = {}
    for c in CASES:
        n = c['components']
        vals = np.asarray(c['output'], dtype=np.float64).reshape(-1, n)
        queries = []
        for t in c['queries']:
            v = sr.sample(c['input'], vals, c['interpolation'], t, is_quat=(c['type'] == 'quat'))
            queries.append({'t': t, 'expected': [float(x) for x in v]})
        entry = {k: c[k] for k in ('name', 'interpolation', 'type', 'components', 'input', 'output')}
        entry['output'] = [float(x) for x in c['output']]
        entry['input'] = [float(x) for x in c['input']]
        entry['queries'] = queries
        cases.append(entry)
        by_name[c['name']] = entry
    msgs = []
    ok_all = True
    for name, t, exp, note in HAND_CHECKS:
        entry = by_name[name]
        got = next(q['expected'] for q in entry['queries'] if q['t'] == t)
        if entry['type'] == 'quat':
            ok = quat_equal_up_to_sign(got, exp, 1e-12) and np.abs(np.asarray(got) - exp).max() <= 1e-12
        else:
            ok = np.abs(np.asarray(got) - exp).max() <= 1e-12
        ok_all &= bool(ok)
        msgs.append('%s %s t=%g: got %s expected %s (%s)' % (
            'OK  ' if ok else 'FAIL', name, t, np.round(got, 9).tolist(), np.round(exp, 9).tolist(), note))
    doc = {
        'generator': 'tests/reference/skinning/make_fixtures.py (independent numpy reference)',
        'conventions': {
            'output': 'flat list exactly as the glTF output accessor would hold it; '
                      'CUBICSPLINE: per key [in-tangent, value, out-tangent], each `components` wide '
                      '(for weights: in-tangents of all targets, then values, then out-tangents)',
            'quaternion_order': 'x, y, z, w',
            'time': 'clamped to [input[0], input[-1]]; a 1-key sampler is constant',
            'slerp': 'shortest path (negate second key when dot < 0), result normalised; '
                     'quaternion results may legitimately differ in overall sign: compare q and -q',
            'cubic_quat': 'Hermite on raw components then normalised',
            'cubic_tangents': 'scaled by the key interval (t[k+1] - t[k])',
        },
        'cases': cases,
        'hand_checks': [{'case': n, 't': t, 'expected': [float(x) for x in e], 'note': note}
                        for n, t, e, note in HAND_CHECKS],
    }
    return doc, msgs, ok_all
