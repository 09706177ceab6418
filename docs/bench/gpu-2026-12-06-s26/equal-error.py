# Time at equal error of every raykin curve against Mitsuba's, from a bench results.json (or the call's curves.json), by the
# formulas of game/src/bench/mitsuba/mod.rs `at_equal_error` (relMSE less each reference's noise, log-log interpolation,
# at the lowest error both curves reach, and the least and greatest over nine levels up to the higher first point).
#   python3 equal-error.py results.json
import json, math, sys
def reach(c, e):
    if c[0][1] <= e: return c[0][0]
    for (t0,e0),(t1,e1) in zip(c,c[1:]):
        if e1 > e or e0<=0 or e1<=0 or t0<=0: continue
        f=(math.log(e)-math.log(e0))/(math.log(e1)-math.log(e0))
        return math.exp(math.log(t0)+f*(math.log(t1)-math.log(t0)))
    return None
def at_equal(a,b):
    lo=max(min(p[1] for p in a), min(p[1] for p in b)); hi=min(a[0][1], b[0][1])
    if not (lo>0 and hi>=lo): return None
    def r(e):
        x=reach(a,e); y=reach(b,e)
        return None if x is None or y is None else x/y
    ratio=r(lo)
    if ratio is None: return None
    lv=[v for v in (r(lo*(hi/lo)**(k/8)) for k in range(1,9)) if v is not None]+[ratio]
    return lo, ratio, min(lv), max(lv)
r=json.load(open(sys.argv[1]))
sbs={s['scene']:s for s in r['mitsuba_side_by_side']}
for e in r['error_vs_time']:
    s=sbs.get(e['scene'])
    if not s: continue
    noise=e['reference_noise_rel_mse']; mnoise=s['mitsuba_reference_noise']
    curves={c['name']:c['points'] for c in e['curves']}
    m=[c for n,c in curves.items() if n.startswith('Mitsuba')][0]
    mc=[(p['time_ms'], max(p['rel_mse']-mnoise,1e-12)) for p in m]
    for n,c in curves.items():
        if n.startswith('Mitsuba'): continue
        rc=[(p['time_ms'], max(p['rel_mse']-noise,1e-12)) for p in c]
        res=at_equal(rc,mc)
        print(e['scene'], n[:24], 'chosen' if n==s['raykin_curve'] else '', res and tuple(round(x,4) if i else f"{x:.1e}" for i,x in enumerate(res)))
