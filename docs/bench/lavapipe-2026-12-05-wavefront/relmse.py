import mitsuba as mi, numpy as np, sys
mi.set_variant('scalar_rgb')
def load(p): return np.array(mi.Bitmap(p), dtype=np.float64)[..., :3]
ref = load('ref.exr')
for spp in (16, 64):
    for kind in ('old', 'new'):
        v = [np.mean((load(f'{kind}-{spp}-{s}.exr') - ref)**2 / (ref**2 + 1e-2)) for s in range(1, 7)]
        print(spp, kind, ' '.join(f'{x:.5f}' for x in v), 'mean', f'{np.mean(v):.5f}')
